#version 430
// defines: ARRAY
// Shows a texture (a composite, or one layer of the atlas with ARRAY) in the GL viewport,
// over u_background where its alpha is below 1 (STD background) or, for the depth-keyed
// atlas, where its depth is 1 (empty texels, whose colour is stale: targets.py).
#ifdef ARRAY
layout(binding = BINDING_VIEW_TEXTURE) uniform sampler2DArray u_texture;
layout(binding = BINDING_ATLAS_DEPTH) uniform sampler2DArray u_depth;
uniform int u_layer;
#else
layout(binding = BINDING_VIEW_TEXTURE) uniform sampler2D u_texture;
#endif
uniform vec2 u_extent;       // fraction of the texture shown (the used part of the atlas)
uniform vec3 u_background;

in vec2 v_uv;
out vec4 out_color;

void main() {
#ifdef ARRAY
    vec3 uvl = vec3(v_uv * u_extent, float(u_layer));
    vec4 c = texture(u_texture, uvl);
    if (texture(u_depth, uvl).r >= 1.0) c.a = 0.0;
#else
    vec4 c = texture(u_texture, v_uv * u_extent);
#endif
    out_color = vec4(mix(u_background, c.rgb, c.a), 1.0);
}
