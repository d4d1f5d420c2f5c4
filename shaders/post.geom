#version 430
// defines:
// A quad over the object's atlas rectangle (border included) on its layer; culled objects
// emit nothing. Texels outside every rectangle are never shaded: nothing reads them. What a
// fragment needs of the record goes as flat values, so no fragment reads the record buffer.
#include "records.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 4) out;

flat in int v_object[];
flat out ivec4 g_rect;     // the rectangle's first and last texel (x0, y0, x1, y1)
flat out vec4 g_map;       // (origin, step): atlas texel -> viewport NDC, ndc = origin + (t + 0.5) * step
flat out float g_scale;    // atlas texels per viewport pixel

uniform vec2 u_viewport;   // viewport pixels
uniform vec2 u_target;     // target size in pixels (the used atlas)

void main() {
    Record r = records[v_object[0]];
    if (r.info.y == 0) return;
    float scale = intBitsToFloat(r.info.w);
    ivec4 rect = ivec4(r.atlas.xy, r.atlas.xy + r.atlas.zw - 1.0);
    vec2 step = 2.0 / (scale * u_viewport);
    vec2 origin = (r.viewport.xy - (r.atlas.xy + float(r.info.z)) / scale) / u_viewport * 2.0 - 1.0;
    vec4 px = vec4(rect.xy, rect.zw + 1);
    vec4 ndc = px / u_target.xyxy * 2.0 - 1.0;
    vec2 corners[4] = vec2[](ndc.xy, ndc.zy, ndc.xw, ndc.zw);
    for (int i = 0; i < 4; ++i) {
        g_rect = rect;
        g_map = vec4(origin, step);
        g_scale = scale;
        gl_Layer = r.info.x;
        gl_Position = vec4(corners[i], 1.0, 1.0);   // depth 1: tested against the atlas's
        EmitVertex();
    }
    EndPrimitive();
}
