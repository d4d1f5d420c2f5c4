#version 430
// defines: MODE_SPRITE MODE_BLEND MODE_OUTLINE WITH_AO PROJECTOR LENS
// Per-object compositing from the atlas:
//   MODE_SPRITE  depth sprite: atlas colour, gl_FragDepth = atlas depth (focus objects, `sprites`)
//   MODE_BLEND   premultiplied blend with the object's opacity (`transparent`, ghosted context)
//   MODE_OUTLINE the object's silhouette from its own unoccluded coverage (ghosted focus)
//   WITH_AO      shade with the atlas post-process (ambient occlusion, edges) of `ghosted-ao`
//   PROJECTOR    paint with the projector at the world position reconstructed from the atlas depth
//   LENS         cut away (discard) texels whose world position is inside the lens (parity test)
#include "composite.glsl"
#include "projector.glsl"
#include "ldi.glsl"

layout(binding = 0) uniform sampler2DArray u_color;
layout(binding = 1) uniform sampler2DArray u_depth;
layout(binding = 3) uniform sampler2DArray u_post;   // (ao, edge) per atlas texel, WITH_AO only
layout(binding = 4) uniform sampler2DArray u_normal;  // view-space normal * 0.5 + 0.5 per atlas texel, PROJECTOR only
uniform mat4 u_inv_view_proj;   // (P V)^-1: viewport NDC + depth -> world relative to the origin
uniform mat4 u_lens_to_crop;        // world relative to the origin -> the lens LDI's crop space
uniform ivec2 u_lens_crop_size;     // (its layers are image unit 0: ldi.glsl)
uniform int u_lens_depth;
uniform int u_lens_per_row;     // crop texels per row of its layers image (ldi.glsl)
uniform int u_lens_object;      // a scene object used as the lens is not cut (-1: none)

uniform float u_desaturate;     // context desaturation in [0, 1] (MODE_BLEND)
uniform vec4 u_edge_color;
uniform int u_outline_width;    // pixels (MODE_OUTLINE)

flat in int g_object;
flat in vec4 g_map;
flat in float g_scale;
flat in int g_layer;
flat in ivec4 g_rect;
flat in float g_opacity;
layout(location = 0) out vec4 out_color;

vec3 shade(vec3 rgb, ivec3 t) {
#ifdef WITH_AO
    vec2 post = texelFetch(u_post, t, 0).rg;
    rgb *= post.r;
    rgb = mix(rgb, u_edge_color.rgb, post.g * u_edge_color.a);
#endif
    return rgb;
}

bool outside(ivec2 s) { return any(lessThan(s, g_rect.xy)) || any(greaterThan(s, g_rect.zw)); }

// Whether atlas texel `s` holds this object: inside its B_atlas and written by the capture.
// The atlas is depth-keyed (targets.py): empty texels have depth 1 and stale colour.
bool covered(ivec3 s) { return !outside(s.xy) && texelFetch(u_depth, s, 0).r < 1.0; }

void main() {
    ivec3 t = atlas_texel(g_map, g_scale, g_layer, gl_FragCoord.xy);
#ifdef MODE_OUTLINE
    // a silhouette texel: the object's own, with a neighbour within the width that is not
    if (!covered(t)) discard;
    bool near_other = false;
    for (int dy = -u_outline_width; dy <= u_outline_width && !near_other; ++dy)
        for (int dx = -u_outline_width; dx <= u_outline_width; ++dx)
            if (!covered(t + ivec3(dx, dy, 0))) { near_other = true; break; }
    if (!near_other) discard;
    out_color = vec4(u_edge_color.rgb, 1.0);
#else
    if (outside(t.xy)) discard;
    float depth = texelFetch(u_depth, t, 0).r;
    if (depth >= 1.0) discard;
    vec3 rgb = texelFetch(u_color, t, 0).rgb;
#if defined(PROJECTOR) || defined(LENS)
    vec4 ndc = vec4(gl_FragCoord.xy / u_viewport * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    vec4 world = u_inv_view_proj * ndc;
    world.xyz /= world.w;
#endif
#ifdef LENS
    if (g_object != u_lens_object
            && ldi_inside(u_lens_depth, u_lens_per_row, (u_lens_to_crop * vec4(world.xyz, 1.0)).xyz, u_lens_crop_size))
        discard;
#endif
#ifdef PROJECTOR
    rgb = painted(rgb, surface_light(normalize(texelFetch(u_normal, t, 0).xyz * 2.0 - 1.0)), world.xyz);
#endif
    rgb = shade(rgb, t);
#ifdef MODE_SPRITE
    gl_FragDepth = depth;
    out_color = vec4(rgb, 1.0);
#else
    float a = g_opacity;
    float grey = dot(rgb, vec3(0.299, 0.587, 0.114));
    rgb = mix(rgb, vec3(grey), u_desaturate);
    gl_FragDepth = depth;
    out_color = vec4(rgb * a, a);
#endif
#endif
}
