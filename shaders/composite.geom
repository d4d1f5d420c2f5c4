#version 430
// defines:
// Point-sprite expansion: a screen-aligned quad over the object's B_viewport (its atlas
// bounds mapped back through T^-1).
#include "composite.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 4) out;

flat in int v_object[];
flat out int g_object;

void main() {
    Record r = records[v_object[0]];
    if (r.info.y == 0) return;
    vec4 ndc = r.viewport / u_viewport.xyxy * 2.0 - 1.0;
    vec2 corners[4] = vec2[](ndc.xy, ndc.zy, ndc.xw, ndc.zw);
    for (int i = 0; i < 4; ++i) {
        g_object = v_object[0];
        gl_Position = vec4(corners[i], 0.0, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}
