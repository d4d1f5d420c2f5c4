#version 430
// defines: COMPRESSED LOCAL_SIZE LDI_DEPTH
// Volumetric parity test of many points: one invocation per point (points in an RGB32F
// texture, row-major), 1 = inside, written to an R8UI image of the same shape. A compute
// shader skips rasterization: on llvmpipe ~20% faster than one fragment per point.
// COMPRESSED: test against the packed depth ranges. LDI_DEPTH: the LDI's layer count, a
// constant so that the layer loop unrolls (the test ran ~30% faster for 2 layers).
#include "ldi.glsl"

layout(local_size_x = LOCAL_SIZE) in;     // given by ldi_gpu.py, which dispatches by it
layout(binding = BINDING_LDI_POINTS) uniform samplerBuffer u_points;   // RGB32F, row-major over the dispatch
layout(binding = BINDING_LDI_RANGES) uniform usampler2D u_packed;
layout(binding = BINDING_LDI_INSIDE, r8ui) writeonly uniform uimage2D u_inside;
uniform mat4 u_to_crop;       // points -> the LDI's crop space
uniform ivec2 u_crop_size;
uniform int u_per_row;     // crop texels per row of the layers image (ldi.glsl)

void main() {
    ivec2 at = ivec2(gl_GlobalInvocationID.xy);
    vec3 p = texelFetch(u_points, at.y * int(gl_NumWorkGroups.x * gl_WorkGroupSize.x) + at.x).xyz;
    vec3 q = (u_to_crop * vec4(p, 1.0)).xyz;
#ifdef COMPRESSED
    bool inside = ldi_inside_compressed(u_packed, q, u_crop_size);
#else
    bool inside = ldi_inside(LDI_DEPTH, u_per_row, q, u_crop_size);
#endif
    imageStore(u_inside, at, uvec4(inside ? 1u : 0u));
}
