#version 430
// defines: LOCAL_SIZE
// The capture's draw lists (rtta.passes.draw_lists): per object, from R (records.glsl) and
// B_world (the bounds buffer, moved by the explode offsets), its kind:
//   0 culled back faces, not clipped   1 double-sided, not clipped
//   2 culled back faces, clipped       3 double-sided, clipped
// or none (not packed, cut away whole, no triangles). Clipped: the region meets the
// viewport's edge (Records.meets_edge), or every object (u_clip_all: the geometry-shader
// path). Culled: closed and wholly beyond the near plane (rtta.scene.closure.beyond_near, in
// doubles). One workgroup per LOCAL_SIZE consecutive objects: an object starts a run where
// the one before it differs in kind (or is not adjacent in the index buffer) or the block
// begins, and its thread walks the run to its end, writing one DrawElementsIndirect command
// (count, 1, first index, 0, 0) into its kind's list at a slot from the kind's counter. The
// commands of a list come in any order: each object has its own atlas region, and a run keeps
// its objects' triangles in order.
#include "records.glsl"

layout(local_size_x = LOCAL_SIZE) in;

layout(std430, binding = BINDING_BOUNDS) readonly buffer BoundsBuffer { vec4 bounds[]; };  // min, max
// per object: bit 0 closed (Scene.closed), bit 1 cut away whole (Placement.removed)
layout(std430, binding = BINDING_DRAW_FLAGS) readonly buffer FlagBuffer { uint flags[]; };
layout(std430, binding = BINDING_DRAW_RANGES) readonly buffer RangeBuffer { uvec2 ranges[]; };  // first, count
layout(std430, binding = BINDING_DRAW_COMMANDS) writeonly buffer CommandBuffer { uint commands[]; };
layout(std430, binding = BINDING_DRAW_COUNTS) buffer CountBuffer { uint counts[4]; };

uniform uint u_count;       // objects
uniform uint u_capacity;    // commands per kind's list
uniform vec2 u_viewport;    // (W, H) in pixels
uniform dvec4 u_view_z;     // the view matrix's third row
uniform double u_near;      // the near plane's distance before the eye
uniform bool u_cull_closed;  // GpuScene.cull_closed
uniform bool u_clip_all;

shared int s_kind[LOCAL_SIZE];
shared uvec2 s_range[LOCAL_SIZE];

bool beyond_near(uint i) {
    dvec3 lo = dvec3(bounds[2u * i].xyz), hi = dvec3(bounds[2u * i + 1u].xyz);
    dvec3 center = (hi + lo) / 2.0LF, half_size = (hi - lo) / 2.0LF;
    double nearest = dot(center, u_view_z.xyz) + u_view_z.w + dot(half_size, abs(u_view_z.xyz));
    return nearest < -u_near;
}

int kind_of(uint i) {
    if (i >= u_count) return -1;
    Record r = records[i];
    uint f = flags[i];
    if (r.info.y == 0 || (f & 2u) != 0u || ranges[i].y == 0u) return -1;
    vec4 v = r.viewport;
    bool edge = v.x <= 0.0 || v.y <= 0.0 || v.z >= u_viewport.x || v.w >= u_viewport.y;
    bool cull = u_cull_closed && (f & 1u) != 0u && beyond_near(i);
    return ((u_clip_all || edge) ? 2 : 0) + (cull ? 0 : 1);
}

bool continues(uint k) {  // object k of the block continues the run of object k - 1
    return s_kind[k] == s_kind[k - 1u] && s_range[k].x == s_range[k - 1u].x + s_range[k - 1u].y;
}

void main() {
    uint block = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;  // 2-D past 65,535 blocks
    uint k = gl_LocalInvocationID.x, i = block * uint(LOCAL_SIZE) + k;
    int kind = kind_of(i);
    s_kind[k] = kind;
    s_range[k] = i < u_count ? ranges[i] : uvec2(0u);
    barrier();
    if (kind < 0 || (k > 0u && continues(k))) return;
    uint end = k + 1u;
    while (end < uint(LOCAL_SIZE) && continues(end)) ++end;
    uint first = s_range[k].x, last = s_range[end - 1u].x + s_range[end - 1u].y;
    uint slot = atomicAdd(counts[kind], 1u);
    uint at = 5u * (uint(kind) * u_capacity + slot);
    commands[at] = last - first;
    commands[at + 1u] = 1u;
    commands[at + 2u] = first;
    commands[at + 3u] = 0u;
    commands[at + 4u] = 0u;
}
