#version 430
// defines: CAPTURE_VS CAPTURE_GS PROJECTOR TEXTURED REGION_CLIP REGION_GUARD PLACED SECTIONS
// PLACED, SECTIONS: exploded and cut (section.glsl)
// One vertex shader for STD/RTT (no define), the RTTA vertex-shader path (CAPTURE_VS,
// needs GL_ARB_shader_viewport_layer_array) and the RTTA geometry-shader path (CAPTURE_GS).
// REGION_CLIP (with CAPTURE_VS): clip every vertex to its object's B_viewport. Only objects
// whose region meets the viewport's edge need it (CapturePass draws them apart): llvmpipe
// spends about a sixth of a capture's vertex stage on clip distances even when none is negative.
#ifdef CAPTURE_VS
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "records.glsl"
#include "section.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in uint in_object;
#ifdef TEXTURED
layout(location = 3) in vec2 in_uv;
layout(location = 5) out vec2 v_uv;    // by location, so depth-only shaders need not declare it
layout(location = 6) flat out vec4 v_material_rect;   // the object's material slot (material.glsl)
layout(location = 7) flat out int v_material_layer;
#include "material.glsl"
#endif

uniform mat4 u_view;
uniform mat4 u_proj;

out VertexData {
    vec3 normal;
    flat int object;
    flat vec3 color;  // the object's colour, read here per vertex, not per fragment
#if defined(PROJECTOR) || defined(SECTIONS)
    vec3 world;       // relative to the scene origin: projective texturing (STD only), sections
#endif
} vs_out;

#if defined(CAPTURE_VS) && defined(REGION_CLIP)
out float gl_ClipDistance[4];
#endif

void main() {
#ifdef PLACED
    vec3 position = in_position + placement[in_object].xyz;
#else
    vec3 position = in_position;
#endif
    vec4 clip_pos = u_proj * (u_view * vec4(position, 1.0));
    vs_out.normal = mat3(u_view) * in_normal;
    vs_out.object = int(in_object);
    vs_out.color = object_colors[in_object].rgb;
#ifdef TEXTURED
    v_uv = in_uv;
    MaterialSlot m = material_slot(int(in_object));
    v_material_rect = m.rect;
    v_material_layer = m.layer;
#endif
#if defined(PROJECTOR) || defined(SECTIONS)
    vs_out.world = position;
#endif
#ifdef CAPTURE_VS
    Record r = records[in_object];
#ifdef REGION_CLIP
    float d[4];
    region_clip_distances(clip_pos, r.clip, d);
    for (int i = 0; i < 4; ++i) gl_ClipDistance[i] = r.info.y != 0 ? d[i] : -1.0;
#endif
    gl_Layer = r.info.x;
    gl_Position = displace(clip_pos, r.transform);
#else
    gl_Position = clip_pos;
#endif
}
