// The material atlas (rtta/material_atlas.py): per object, where its base-colour texture
// lies in the atlas array, or info.w == 0 for an object without a texture.
struct Material {
    vec4 rect;     // texture origin (x, y) and size (w, h) in atlas texels, border excluded
    ivec4 info;    // (layer, 0, 0, has texture)
};
layout(std430, binding = BINDING_MATERIALS) readonly buffer MaterialBuffer { Material materials[]; };
layout(binding = BINDING_MATERIAL_ATLAS) uniform sampler2DArray u_material_atlas;

// What a fragment needs of the object's material: (rect, layer), layer -1 without a texture.
// The vertex stage reads it and passes it flat, so no fragment reads the buffer.
struct MaterialSlot { vec4 rect; int layer; };

MaterialSlot material_slot(int object) {
    Material m = materials[object];
    return MaterialSlot(m.rect, m.info.w == 0 ? -1 : m.info.x);
}

// REPEAT emulated inside the texture's rectangle: fract() wraps the coordinate, and the
// gradients of the unwrapped coordinate pick the mip level, so wrap lines show no seam.
// `duv_dx`, `duv_dy` must be taken in uniform control flow (before any branch on the object).
vec3 material_texel(vec4 rect, int layer, vec2 uv, vec2 duv_dx, vec2 duv_dy) {
    if (layer < 0) return vec3(1.0);
    vec2 size = vec2(textureSize(u_material_atlas, 0).xy);
    vec2 texel = rect.xy + fract(uv) * rect.zw;
    vec2 scale = rect.zw / size;
    return textureGrad(u_material_atlas, vec3(texel / size, float(layer)),
                       duv_dx * scale, duv_dy * scale).rgb;
}
