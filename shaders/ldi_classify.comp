#version 430
// defines: COMPRESSED LOCAL_SIZE
// Volumetric parity test of many points: one invocation per point (points in an RGB32F
// texture, row-major), 1 = inside, written to an R8UI image of the same shape. A compute
// shader skips rasterization: on llvmpipe ~20% faster than one fragment per point.
// COMPRESSED: test against the packed depth ranges.
#include "ldi.glsl"

layout(local_size_x = LOCAL_SIZE) in;     // given by ldi_gpu.py, which dispatches by it
layout(binding = 0) uniform sampler2D u_points;
layout(binding = 2) uniform usampler2D u_packed;
layout(binding = 1, r8ui) writeonly uniform uimage2D u_inside;
uniform mat4 u_to_crop;       // points -> the LDI's crop space
uniform ivec2 u_crop_size;
uniform int u_depth;

void main() {
    ivec2 at = ivec2(gl_GlobalInvocationID.xy);
    vec3 p = texelFetch(u_points, at, 0).xyz;
    vec3 q = (u_to_crop * vec4(p, 1.0)).xyz;
#ifdef COMPRESSED
    bool inside = ldi_inside_compressed(u_packed, q, u_crop_size);
#else
    bool inside = ldi_inside(u_depth, q, u_crop_size);
#endif
    imageStore(u_inside, at, uvec4(inside ? 1u : 0u));
}
