#version 430
// defines: PROJECTOR TEXTURED SEPARATE
// Multiple render targets: shaded colour, view-space normal, object id (depth is the depth attachment).
#include "records.glsl"
#include "projector.glsl"
#ifdef TEXTURED
layout(location = 5) in vec2 f_uv;
#ifdef SEPARATE
// the unbatched reference: each object drawn alone with its own texture, REPEAT sampling
uniform sampler2D u_texture;
uniform bool u_textured;
#else
#include "material.glsl"
#endif
#endif

in VertexData {
    vec3 normal;
    flat int object;
#ifdef PROJECTOR
    vec3 world;
#endif
} fs_in;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out int out_id;

void main() {
    float len_n = length(fs_in.normal);
    vec3 n = len_n > 1e-20 ? fs_in.normal / len_n : vec3(0.0, 0.0, 1.0);
    if (!gl_FrontFacing) n = -n;
    // headlight: light from the camera, two-sided
    float light = surface_light(n);
    vec3 base = object_colors[fs_in.object].rgb;
#ifdef TEXTURED
#ifdef SEPARATE
    if (u_textured) base *= texture(u_texture, f_uv).rgb;   // the sampler's REPEAT and mip selection
#else
    base *= material_texel(fs_in.object, f_uv, dFdx(f_uv), dFdy(f_uv));
#endif
#endif
    vec3 rgb = base * light;
#ifdef PROJECTOR
    rgb = painted(rgb, light, fs_in.world);
#endif
    out_color = vec4(rgb, 1.0);
    out_normal = vec4(n, 1.0);
    out_id = fs_in.object;
}
