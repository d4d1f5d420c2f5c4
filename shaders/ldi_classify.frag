#version 430
// defines: COMPRESSED
// Volumetric parity test of many points: one fragment per point (points in an RGB32F
// texture, row-major), 1 = inside. COMPRESSED: test against the packed depth ranges.
#include "ldi.glsl"

layout(binding = 0) uniform sampler2D u_points;
layout(binding = 1) uniform sampler2DArray u_layers;
layout(binding = 2) uniform usampler2D u_packed;
uniform mat4 u_to_texture;
uniform ivec2 u_size;
uniform ivec4 u_crop;
uniform int u_depth;
layout(location = 0) out uint out_inside;

void main() {
    vec3 p = texelFetch(u_points, ivec2(gl_FragCoord.xy), 0).xyz;
    vec3 T = (u_to_texture * vec4(p, 1.0)).xyz;
#ifdef COMPRESSED
    out_inside = ldi_inside_compressed(u_packed, T, u_size, u_crop) ? 1u : 0u;
#else
    out_inside = ldi_inside(u_layers, u_depth, T, u_size, u_crop) ? 1u : 0u;
#endif
}
