#version 430
// defines: COMPRESSED
// Volumetric parity test of many points: one fragment per point (points in an RGB32F
// texture, row-major), 1 = inside. COMPRESSED: test against the packed depth ranges.
#include "ldi.glsl"

layout(binding = 0) uniform sampler2D u_points;
layout(binding = 2) uniform usampler2D u_packed;
uniform mat4 u_to_crop;       // points -> the LDI's crop space
uniform ivec2 u_crop_size;
uniform int u_depth;
layout(location = 0) out uint out_inside;

void main() {
    vec3 p = texelFetch(u_points, ivec2(gl_FragCoord.xy), 0).xyz;
    vec3 q = (u_to_crop * vec4(p, 1.0)).xyz;
#ifdef COMPRESSED
    out_inside = ldi_inside_compressed(u_packed, q, u_crop_size) ? 1u : 0u;
#else
    out_inside = ldi_inside(u_depth, q, u_crop_size) ? 1u : 0u;
#endif
}
