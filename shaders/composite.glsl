// Shared by the compositing stages: per-object style, draw order, atlas lookup.
#include "records.glsl"

struct Style {
    vec4 params;   // (opacity, focus, unused, unused)
};
layout(std430, binding = 2) readonly buffer StyleBuffer { Style styles[]; };
layout(std430, binding = 3) readonly buffer OrderBuffer { int order[]; };

uniform vec2 u_viewport;   // composite target size in pixels

// Atlas texel (x, y, layer) of the viewport pixel centre `px`: B_viewport -> B_atlas through T.
ivec3 atlas_texel(Record r, vec2 px) {
    float scale = intBitsToFloat(r.info.w);
    vec2 t = r.atlas.xy + float(r.info.z) + scale * (px - r.viewport.xy);
    return ivec3(floor(t), r.info.x);
}
