// Shared by the compositing stages: per-object style, draw order, atlas lookup.
#include "records.glsl"

struct Style {
    vec4 params;   // (opacity, focus, uses AO, uses edges)
};
layout(std430, binding = BINDING_STYLES) readonly buffer StyleBuffer { Style styles[]; };
layout(std430, binding = BINDING_DRAW_LIST) readonly buffer OrderBuffer { int order[]; };

uniform vec2 u_viewport;   // composite target size in pixels

// Atlas texel (x, y, layer) of the viewport pixel centre `px`: B_viewport -> B_atlas through T,
// from the flat values of composite.geom (`map` = (B_atlas origin + border, B_viewport origin)).
ivec3 atlas_texel(vec4 map, float scale, int layer, vec2 px) {
    return ivec3(floor(map.xy + scale * (px - map.zw)), layer);
}
