#version 450
// defines: MODE_SPRITE MODE_BLEND MODE_OUTLINE MODE_COLLECT FIRST_FETCHED MODE_HALO FOCUS_CLIP WITH_AO PROJECTOR LENS UPSAMPLE
// defines: SPRITE_OUTLINE OUTLINE_QUAD UPSAMPLE_DYNAMIC
// Per-object compositing from the atlas:
//   MODE_SPRITE  depth sprite: atlas colour, gl_FragDepth = atlas depth (focus objects, `sprites`)
//   MODE_BLEND   premultiplied blend with the object's opacity (`transparent`, ghosted context)
//   MODE_OUTLINE the object's silhouette from its own unoccluded coverage (ghosted focus)
//   SPRITE_OUTLINE  with MODE_SPRITE: the outline drawn in the same pass, at depth 0 (the
//                ghosted focus, whose outlines would otherwise take a pass of their own)
//   OUTLINE_QUAD outlines of width 1, with a border of at least 1, at one texel per pixel: one
//                depth gather per fragment and quad derivatives (quad_silhouette) instead of
//                nine fetches
//   MODE_HALO    around a focus object, where context lies behind it: a halo that fades over
//                u_halo_width pixels from its silhouette (depth from its own atlas image)
//   MODE_COLLECT as MODE_BLEND, but appended to the pixel's list (oit.glsl) for a per-pixel
//                sorted blend (`--order pixel`); writes no colour, unless with MODE_BLEND:
//                blended too, every fragment listed (oit.OrderMarks)
//   FIRST_FETCHED with MODE_COLLECT: a pixel's first three surfaces kept in two colour
//                attachments and its surface count in the stencil, read and written in draw
//                order through framebuffer fetch; only later ones become nodes, linked with no
//                atomics (oit.py); with MODE_BLEND the pixels that object order gets wrong
//                are flagged in the stencil too
//   FOCUS_CLIP   with MODE_COLLECT: surfaces behind the nearest focus surface are left out (ghosted)
//   WITH_AO      shade with the atlas post-process (ambient occlusion, edges) of `ghosted-ao`
//   PROJECTOR    paint with the projector at the world position reconstructed from the atlas depth
//   LENS         cut away (discard) texels whose world position is inside the lens (parity test)
//   UPSAMPLE     the objects' regions hold less than one texel per pixel: depth-aware upsampling
//                (a variant, not a branch: on llvmpipe both sides of a branch cost)
//   UPSAMPLE_DYNAMIC  each sprite upsampled where its own scale is below u_upsample_below (a
//                branch: draws from a GPU list, whose objects' scales the CPU does not know)
#ifdef FIRST_FETCHED
#extension GL_EXT_shader_framebuffer_fetch : require
#extension GL_ARM_shader_framebuffer_fetch_depth_stencil : require
#extension GL_ARB_shader_stencil_export : require
#endif
#include "composite.glsl"
#include "projector.glsl"
#include "ldi.glsl"
#ifdef MODE_COLLECT
#include "oit.glsl"
flat in uint g_node_base;   // the object's first node
flat in int g_vp_width;     // its B_viewport's width
#ifdef FIRST_FETCHED
// a surface here is (~depth bits: larger is nearer, never 0; colour), an empty one 0; not
// cleared: they hold this frame's values where the stencil's count is above 0
layout(location = 1) inout uvec4 fetched_first;   // surfaces 0 and 1
layout(location = 2) inout uvec4 fetched_more;    // surface 2, the list of the later ones (node + 1), their nearest
#endif
#endif

layout(binding = BINDING_ATLAS_NORMAL) uniform sampler2DArray u_normal;  // view-space normal * 0.5 + 0.5 per atlas texel, PROJECTOR only
uniform mat4 u_inv_view_proj;   // (P V)^-1: viewport NDC + depth -> world relative to the origin
uniform mat4 u_lens_to_crop;        // world relative to the origin -> the lens LDI's crop space
uniform ivec2 u_lens_crop_size;     // (its layers are image unit 0: ldi.glsl)
uniform int u_lens_depth;
uniform int u_lens_per_row;     // crop texels per row of its layers image (ldi.glsl)
uniform int u_lens_object;      // a scene object used as the lens is not cut (-1: none)

uniform float u_desaturate;     // context desaturation in [0, 1] (MODE_BLEND)
uniform vec4 u_edge_color;
uniform vec4 u_outline_color;  // MODE_OUTLINE, SPRITE_OUTLINE
uniform int u_outline_width;    // pixels (MODE_OUTLINE)
uniform int u_halo_width;       // pixels (MODE_HALO)
uniform vec4 u_halo_color;      // (rgb, strength)
layout(binding = BINDING_CONTEXT_DEPTH) uniform sampler2D u_context_depth;   // farthest context depth per pixel, 0: none (MODE_HALO)
#ifdef FOCUS_CLIP
layout(binding = BINDING_FOCUS_DEPTH) uniform sampler2D u_focus_depth;     // nearest focus depth per pixel, 1: none (MODE_COLLECT)
#endif

flat in int g_object;
flat in vec4 g_map;
flat in float g_scale;
flat in int g_layer;
flat in ivec4 g_rect;
flat in float g_opacity;
flat in vec2 g_shade;      // (uses AO, uses edges): the object's role (WITH_AO)
#include "sprite_sample.glsl"
layout(location = 0) out vec4 out_color;


// Whether atlas texel `s` holds this object: inside its B_atlas and written by the capture.
// The atlas is depth-keyed (targets.py): empty texels have depth 1 and stale colour.
bool covered(ivec3 s) { return !outside(s.xy) && texelFetch(u_depth, s, 0).r < 1.0; }

// Whether atlas texel `s` lies beyond the viewport: in the border past an edge where the view
// cuts the object. What lies there is unknown, and the cut is no silhouette.
bool beyond(ivec3 s) {
    vec2 px = g_map.zw + (vec2(s.xy) + 0.5 - g_map.xy) / g_scale;
    return any(lessThan(px, vec2(0.0))) || any(greaterThan(px, u_viewport));
}

// Whether atlas texel `t` is on the object's silhouette: its own (inside B_atlas and
// covered) with a texel within u_outline_width (square window) that is not, and is in view.
bool silhouette(ivec3 t) {
    if (!covered(t)) return false;
    for (int dy = -u_outline_width; dy <= u_outline_width; ++dy)
        for (int dx = -u_outline_width; dx <= u_outline_width; ++dx)
            if (!covered(t + ivec3(dx, dy, 0)) && !beyond(t + ivec3(dx, dy, 0))) return true;
    return false;
}

#ifdef OUTLINE_QUAD
// silhouette() for width 1, a border of at least 1 and one texel per pixel, from ONE depth
// gather per fragment. The border ring of B_atlas is never written (the capture clips to
// B_atlas less its border), so a covered texel's 3x3 window lies inside B_atlas and holds
// an empty texel (depth 1) exactly where it is a silhouette texel. Each fragment of a 2x2
// quad gathers the 2x2 texels on its side away from the quad's other fragments (its own,
// ax and ay beside it, axy across); the four gathers tile the 4x4 texels around the quad,
// and the fine derivatives of their emptiness (0 or 1: exact in a difference) hand each
// fragment the 5 texels of its window that its partners gathered. Helpers too must run
// this: it is called before any discard, in uniform control flow.
bool quad_silhouette(ivec3 t) {
    ivec2 odd = ivec2(gl_FragCoord.xy) & 1, away = 2 * odd - 1;   // the partners lie at -away
    ivec2 lo = min(t.xy, t.xy + away);
    // components: x (lo.x, lo.y+1), y (lo.x+1, lo.y+1), z (lo.x+1, lo.y), w (lo.x, lo.y)
    vec4 g = textureGather(u_depth, vec3((vec2(lo) + 1.0) / vec2(textureSize(u_depth, 0).xy), float(t.z)), 0);
    vec2 own_row = odd.y == 1 ? g.wz : g.xy, away_row = odd.y == 1 ? g.xy : g.wz;
    vec4 c = odd.x == 1 ? vec4(own_row.x, own_row.y, away_row.x, away_row.y)
                        : vec4(own_row.y, own_row.x, away_row.y, away_row.x);     // (own, ax, ay, axy)
    vec4 e = vec4(greaterThanEqual(c, vec4(1.0)));      // empty (and in view: beyond() is none)
    e *= vec4(bvec4(!beyond(t), !beyond(t + ivec3(away.x, 0, 0)), !beyond(t + ivec3(0, away.y, 0)),
                    !beyond(t + ivec3(away, 0))));
    vec2 s = vec2(1 - 2 * odd);
    vec4 px = e + s.x * dFdxFine(e);                     // the partner across x: (own, ., ay, .)
    vec4 py = e + s.y * dFdyFine(e);                     // across y: (own, ax, ., .)
    float pxy = py.x + s.x * dFdxFine(py.x);             // the diagonal partner's own
    float empty_near = max(max(max(e.y, e.z), max(e.w, pxy)), max(max(px.x, px.z), max(py.x, py.y)));
    return !outside(t.xy) && e.x < 0.5 && empty_near > 0.5;
}
#endif

// Whether this fragment draws the outline (MODE_OUTLINE, SPRITE_OUTLINE).
bool outline_here(ivec3 t) {
#ifdef OUTLINE_QUAD
    return quad_silhouette(t);
#else
    return silhouette(t);
#endif
}

void main() {
#ifdef MODE_OUTLINE
    if (!outline_here(atlas_texel(g_map, g_scale, g_layer, gl_FragCoord.xy))) discard;
    out_color = vec4(u_outline_color.rgb, 1.0);
#elif defined(MODE_HALO)
    // the nearest own texel within the width (squared distance), and its depth
    ivec3 t = atlas_texel(g_map, g_scale, g_layer, gl_FragCoord.xy);
    if (covered(t)) discard;
    int w = u_halo_width, best = w * w + 1;
    float near_depth = 1.0;
    for (int dy = -w; dy <= w; ++dy)
        for (int dx = -w; dx <= w; ++dx) {
            ivec3 s = t + ivec3(dx, dy, 0);
            int r2 = dx * dx + dy * dy;
            if (r2 < best && !outside(s.xy)) {
                float d = texelFetch(u_depth, s, 0).r;
                if (d < 1.0) { best = r2; near_depth = d; }
            }
        }
    float context = texelFetch(u_context_depth, ivec2(gl_FragCoord.xy), 0).r;
    if (best > w * w || context <= near_depth) discard;   // none near, or no context behind
    float a = u_halo_color.a * (1.0 - sqrt(float(best)) / float(w + 1));
    gl_FragDepth = near_depth;     // tested against the focus sprites: a nearer focus object stays clear
    out_color = vec4(u_halo_color.rgb * a, a);
#else
#ifdef SPRITE_OUTLINE
    // before any discard (OUTLINE_QUAD reads the quad partners through derivatives)
    bool outlined = outline_here(atlas_texel(g_map, g_scale, g_layer, gl_FragCoord.xy));
#endif
    Sample o;
    if (!sampled(gl_FragCoord.xy, o)) {
#ifdef SPRITE_OUTLINE
        // an upsampled region's silhouette texel where its bilinear coverage falls short (at
        // one texel per pixel or more a silhouette texel is always sampled): as MODE_OUTLINE draws it
        if (outlined) {
            gl_FragDepth = 0.0;
            out_color = vec4(u_outline_color.rgb, 1.0);
            return;
        }
#endif
        discard;
    }
    float depth = o.depth;
    vec3 rgb = o.rgb;
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
    rgb = painted(rgb, surface_light(normalize(texelFetch(u_normal, o.t, 0).xyz * 2.0 - 1.0)), world.xyz);
#endif
    rgb = shade(rgb, o.post);
#ifdef MODE_SPRITE
    gl_FragDepth = depth;
    out_color = vec4(rgb, 1.0);
#ifdef SPRITE_OUTLINE
    // the outline at depth 0: nothing drawn after (context, halos) covers it, as if drawn last
    if (outlined) {
        gl_FragDepth = 0.0;
        out_color = vec4(u_outline_color.rgb, 1.0);
    }
#endif
#else
    float a = g_opacity;
    float grey = dot(rgb, vec3(0.299, 0.587, 0.114));
    rgb = mix(rgb, vec3(grey), u_desaturate);
#ifdef MODE_COLLECT
    // the node's place is fixed by the pixel's place in B_viewport: no shared counter
    ivec2 p = ivec2(gl_FragCoord.xy);
#ifdef FOCUS_CLIP
    if (depth >= texelFetch(u_focus_depth, p, 0).r) discard;   // behind a focus object (ghosted): hidden
#endif
    ivec2 origin = ivec2(g_map.zw);                 // B_viewport's first pixel
    uint i = g_node_base + uint((p.y - origin.y) * g_vp_width + (p.x - origin.x));
#ifdef FIRST_FETCHED
    uint near = ~floatBitsToUint(depth), colour = packUnorm4x8(vec4(rgb, a));
    int last = gl_LastFragStencilARM, n = last & STENCIL_COUNT;      // surfaces before this one
    // a pixel's first surface writes both attachments: from then on they hold this frame's
    uvec4 first = n > 0 ? fetched_first : uvec4(0u);
    uvec4 more = n > 0 ? fetched_more : uvec4(0u);
    uint nearest = max(max(first.x, first.z), max(more.x, more.w));
    // oit.OrderMarks' flag: this surface lies at or behind the nearest before it
    gl_FragStencilRefARB = (last & STENCIL_FLAG) | (n > 0 && near <= nearest ? STENCIL_FLAG : 0)
                         | min(n + 1, STENCIL_COUNT);
    if (n == 0) first.xy = uvec2(near, colour);
    else if (n == 1) first.zw = uvec2(near, colour);
    else if (n == 2) more.xy = uvec2(near, colour);
    else {
        nodes[i] = uvec4(floatBitsToUint(depth), colour, more.z, 0u);
        more.zw = uvec2(i + 1u, max(more.w, near));
    }
    fetched_first = first;
    fetched_more = more;
#else
    uint next = atomicExchange(heads[p.y * int(u_viewport.x) + p.x], i + 1u);   // 0: none
    nodes[i] = uvec4(floatBitsToUint(depth), packUnorm4x8(vec4(rgb, a)), next, 0u);
#endif
#endif
#if defined(MODE_COLLECT) && !defined(MODE_BLEND)
    out_color = vec4(0.0);
#else
#ifndef FIRST_FETCHED
    gl_FragDepth = depth;
#endif
    out_color = vec4(rgb * a, a);
#endif
#endif
#endif
}
