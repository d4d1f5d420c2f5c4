#version 430
// defines: MODE_COLLECT MODE_HALO
// Point-sprite expansion: a screen-aligned quad over the object's B_viewport (its atlas
// bounds mapped back through T^-1). What the fragments need of the record and the style
// goes as flat values: no fragment reads the buffers (per-fragment loads cost on llvmpipe).
#include "composite.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 4) out;

flat in int v_object[];
flat out int g_object;
flat out vec4 g_map;       // (B_atlas origin + border, B_viewport origin): see atlas_texel
flat out float g_scale;    // atlas texels per viewport pixel
flat out int g_layer;
flat out ivec4 g_rect;     // B_atlas's first and last texel (x0, y0, x1, y1), border included
flat out float g_opacity;  // the style's opacity
flat out vec2 g_shade;     // the style's (uses AO, uses edges)
#ifdef MODE_COLLECT
layout(std430, binding = 7) readonly buffer NodeBase { uint node_base[]; };
flat out uint g_node_base; // the object's first node: one per pixel of its B_viewport (oit.glsl)
flat out int g_vp_width;   // B_viewport's width in pixels
#endif

#ifdef MODE_HALO
uniform int u_halo_width;  // the quad reaches this far beyond B_viewport (pixels)
#endif

void main() {
    Record r = records[v_object[0]];
    if (r.info.y == 0) return;
#ifdef MODE_HALO
    vec4 ndc = (r.viewport + vec4(-u_halo_width, -u_halo_width, u_halo_width, u_halo_width)) / u_viewport.xyxy * 2.0 - 1.0;
#else
    vec4 ndc = r.viewport / u_viewport.xyxy * 2.0 - 1.0;
#endif
    vec2 corners[4] = vec2[](ndc.xy, ndc.zy, ndc.xw, ndc.zw);
    for (int i = 0; i < 4; ++i) {
        g_object = v_object[0];
        g_map = vec4(r.atlas.xy + float(r.info.z), r.viewport.xy);
        g_scale = intBitsToFloat(r.info.w);
        g_layer = r.info.x;
        g_rect = ivec4(r.atlas.xy, r.atlas.xy + r.atlas.zw - 1.0);
        g_opacity = styles[v_object[0]].params.x;
        g_shade = styles[v_object[0]].params.zw;
#ifdef MODE_COLLECT
        g_node_base = node_base[v_object[0]];
        g_vp_width = int(r.viewport.z - r.viewport.x);
#endif
        gl_Position = vec4(corners[i], 0.0, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}
