#version 430
// defines: TEXTURED SECTIONS REGION_GUARD
// The paper's path (Figure 4): displace each triangle into its atlas region and route it to its layer.
// REGION_GUARD (an extreme zoom, rtta.passes.guard): each triangle is first cut to its region's
// guard planes here, so the rasterizer never clips the huge ones; scene.frag keeps the region.
#include "records.glsl"

layout(triangles) in;
#ifdef REGION_GUARD
layout(triangle_strip, max_vertices = 7) out;
#else
layout(triangle_strip, max_vertices = 3) out;
#endif

#ifdef SECTIONS
in VertexData { vec3 normal; flat int object; flat vec3 color; vec3 world; } gs_in[];
out VertexData { vec3 normal; flat int object; flat vec3 color; vec3 world; } gs_out;
#else
in VertexData { vec3 normal; flat int object; flat vec3 color; } gs_in[];
out VertexData { vec3 normal; flat int object; flat vec3 color; } gs_out;
#endif
out float gl_ClipDistance[4];
#ifdef TEXTURED
layout(location = 5) in vec2 v_uv[];
layout(location = 5) out vec2 g_uv;
layout(location = 6) flat in vec4 v_material_rect[];
layout(location = 6) flat out vec4 g_material_rect;
layout(location = 7) flat in int v_material_layer[];
layout(location = 7) flat out int g_material_layer;
#endif

#ifdef REGION_GUARD
#include "guard_clip.glsl"
#endif

void main() {
    Record r = records[gs_in[0].object];
    if (r.info.y == 0) return;  // culled: not packed, emits nothing
#ifdef REGION_GUARD
    if (guard_cut(r)) return;  // cut and emitted, or wholly outside
#endif
    for (int i = 0; i < 3; ++i) {
        vec4 clip_pos = gl_in[i].gl_Position;
        float d[4];
        region_clip_distances(clip_pos, r.clip, d);
        for (int k = 0; k < 4; ++k) gl_ClipDistance[k] = d[k];
        gl_Layer = r.info.x;
        gl_Position = displace(clip_pos, r.transform);
        gs_out.normal = gs_in[i].normal;
        gs_out.object = gs_in[i].object;
        gs_out.color = gs_in[i].color;
#ifdef SECTIONS
        gs_out.world = gs_in[i].world;
#endif
#ifdef TEXTURED
        g_uv = v_uv[i];
        g_material_rect = v_material_rect[i];
        g_material_layer = v_material_layer[i];
#endif
        EmitVertex();
    }
    EndPrimitive();
}
