#version 430
// defines: ARRAY
// Shows a texture (a composite, or one layer of the atlas with ARRAY) in the GL viewport,
// over u_background where its alpha is below 1 (empty atlas texels, STD background).
#ifdef ARRAY
uniform sampler2DArray u_texture;
uniform int u_layer;
#else
uniform sampler2D u_texture;
#endif
uniform vec2 u_extent;       // fraction of the texture shown (the used part of the atlas)
uniform vec3 u_background;

in vec2 v_uv;
out vec4 out_color;

void main() {
#ifdef ARRAY
    vec4 c = texture(u_texture, vec3(v_uv * u_extent, float(u_layer)));
#else
    vec4 c = texture(u_texture, v_uv * u_extent);
#endif
    out_color = vec4(mix(u_background, c.rgb, c.a), 1.0);
}
