// The material atlas (rtta/material_atlas.py): per object, where its base-colour texture
// lies in the atlas array, or info.w == 0 for an object without a texture.
struct Material {
    vec4 rect;     // texture origin (x, y) and size (w, h) in atlas texels, border excluded
    ivec4 info;    // (layer, 0, 0, has texture)
};
layout(std430, binding = 2) readonly buffer MaterialBuffer { Material materials[]; };
uniform sampler2DArray u_material_atlas;

// REPEAT emulated inside the texture's rectangle: fract() wraps the coordinate, and the
// gradients of the unwrapped coordinate pick the mip level, so wrap lines show no seam.
// `duv_dx`, `duv_dy` must be taken in uniform control flow (before any branch on the object).
vec3 material_texel(int object, vec2 uv, vec2 duv_dx, vec2 duv_dy) {
    Material m = materials[object];
    if (m.info.w == 0) return vec3(1.0);
    vec2 size = vec2(textureSize(u_material_atlas, 0).xy);
    vec2 texel = m.rect.xy + fract(uv) * m.rect.zw;
    vec2 scale = m.rect.zw / size;
    return textureGrad(u_material_atlas, vec3(texel / size, float(m.info.x)),
                       duv_dx * scale, duv_dy * scale).rgb;
}
