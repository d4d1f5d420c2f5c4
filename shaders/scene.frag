#version 430
// defines: PROJECTOR TEXTURED SEPARATE NO_NORMAL SECTIONS CAP_COUNT CAP_DRAW REGION_GUARD
// REGION_GUARD: the capture at an extreme zoom keeps its region's texels alone (records.glsl)
// SECTIONS, CAP_COUNT, CAP_DRAW: cut, capped (section.glsl)
// Multiple render targets: shaded colour, view-space normal (RGBA8: n * 0.5 + 0.5; the view
// distance post-processing needs comes from the depth), object id (depth is the depth
// attachment). NO_NORMAL: colour and id only (STD, RTT: nothing reads their normals).
#include "records.glsl"
#include "projector.glsl"
#define SECTION_FRAGMENT
#include "section.glsl"
#ifdef TEXTURED
layout(location = 5) in vec2 f_uv;
#ifdef SEPARATE
// the unbatched reference: each object drawn alone with its own texture, REPEAT sampling
layout(binding = BINDING_SCENE_TEXTURE) uniform sampler2D u_texture;
uniform bool u_textured;
#else
#include "material.glsl"
layout(location = 6) flat in vec4 f_material_rect;
layout(location = 7) flat in int f_material_layer;
#endif
#endif

in VertexData {
    vec3 normal;
    flat int object;
    flat vec3 color;
#if defined(PROJECTOR) || defined(SECTIONS)
    vec3 world;
#endif
} fs_in;

layout(location = 0) out vec4 out_color;
#ifdef NO_NORMAL
layout(location = 1) out int out_id;
#else
layout(location = 1) out vec4 out_normal;
layout(location = 2) out int out_id;
#endif


void main() {
#ifdef REGION_GUARD
    if (!region_holds(gl_FragCoord.xy, records[fs_in.object])) discard;
#endif
    float len_n = length(fs_in.normal);
    vec3 n = len_n > 1e-20 ? fs_in.normal / len_n : vec3(0.0, 0.0, 1.0);
    if (!gl_FrontFacing) n = -n;
#if defined(CAP_COUNT) || defined(CAP_DRAW)
    if (!section_beyond(fs_in.world)) discard;   // every surface beyond the entry counts, removed ones too
#ifdef CAP_COUNT
    return;   // the stencil is all it writes (colour masked)
#endif
#ifdef CAP_DRAW
    vec3 hit;
    int plane;
    float enter;
    section_entry(fs_in.world, hit, plane, enter);
    gl_FragDepth = section_depth(hit);
    n = normalize(mat3(u_view) * u_sections[plane].xyz);   // faces the eye: it came from that side
#endif
#elif defined(SECTIONS)
    if (int(placement[fs_in.object].w) % 2 == 1 && section_removed(fs_in.world)) discard;
#endif
    // headlight: light from the camera, two-sided
    float light = surface_light(n);
    vec3 base = fs_in.color;
#ifdef TEXTURED
#ifdef SEPARATE
    if (u_textured) base *= texture(u_texture, f_uv).rgb;   // the sampler's REPEAT and mip selection
#else
    base *= material_texel(f_material_rect, f_material_layer, f_uv, dFdx(f_uv), dFdy(f_uv));
#endif
#endif
#ifdef CAP_DRAW
    base = cap_color(fs_in.color, hit, u_sections[plane].xyz);
#endif
    vec3 rgb = base * light;
#if defined(PROJECTOR) && defined(CAP_DRAW)
    rgb = painted(rgb, light, hit);   // the cap's point on the plane, not the back face's
#elif defined(PROJECTOR)
    rgb = painted(rgb, light, fs_in.world);
#endif
    out_color = vec4(rgb, 1.0);
    // 1 / gl_FragCoord.w is the clip w, the view distance (the RTTA displacement keeps w);
    // over `far` it lies in [near/far, 1], well inside half-float range for any scene scale
#ifndef NO_NORMAL
    out_normal = vec4(n * 0.5 + 0.5, 1.0);
#endif
    out_id = fs_in.object;
}
