#version 430
// defines: MODE_COLLECT MODE_HALO HULL_PER_SPRITE
// Point-sprite expansion: a screen-aligned quad over the object's B_viewport (its atlas
// bounds mapped back through T^-1). What the fragments need of the record and the style
// goes as flat values: no fragment reads the buffers (per-fragment loads cost on llvmpipe).
// u_hull: the projected outline of B_world instead (a hexagon or quad, grown by
// u_hull_margin pixels), where it can be had: every pixel the object covers lies inside it, and it
// covers a quarter to a third fewer pixels than B_viewport (fragments outside B_viewport are
// discarded by the fragment shader, which reads nothing outside B_atlas). A uniform, not a
// define: one program draws with and without it (the choice is made per draw).
// HULL_PER_SPRITE (draws from a GPU list, whose objects the CPU does not know): the outline
// per sprite, where u_hull and its own B_viewport covers u_hull_min_area pixels and is not
// upsampled, grown by the margin of its own scale (outlines.hull_margin's rule).
#include "composite.glsl"

layout(points) in;
layout(triangle_strip, max_vertices = 6) out;

flat in int v_object[];
flat out int g_object;
flat out vec4 g_map;       // (B_atlas origin + border, B_viewport origin): see atlas_texel
flat out float g_scale;    // atlas texels per viewport pixel
flat out int g_layer;
flat out ivec4 g_rect;     // B_atlas's first and last texel (x0, y0, x1, y1), border included
flat out float g_opacity;  // the style's opacity
flat out vec2 g_shade;     // the style's (uses AO, uses edges)
#ifdef MODE_COLLECT
layout(std430, binding = BINDING_OIT_BASES) readonly buffer NodeBase { uint node_base[]; };
flat out uint g_node_base; // the object's first node: one per pixel of its B_viewport (oit.glsl)
flat out int g_vp_width;   // B_viewport's width in pixels
#endif

#ifdef MODE_HALO
uniform int u_halo_width;  // the quad reaches this far beyond B_viewport (pixels)
#endif

layout(std430, binding = BINDING_BOUNDS) readonly buffer BoundsBuffer { vec4 bounds[]; };  // B_world (min, max) per object, scene origin at 0
uniform bool u_hull;
uniform mat4 u_view_proj;
uniform vec3 u_eye;        // the camera's position, scene origin at 0
uniform float u_hull_margin;   // pixels: float32 and sub-pixel snapping, and the reach of a texel (CompositePass)
#ifdef HULL_PER_SPRITE
uniform float u_upsample_below;   // sprites.UPSAMPLE_BELOW
uniform float u_hull_min_area;    // outlines.HULL_MIN_AREA
#endif

// The corners (bit 0: x, 1: y, 2: z at the maximum) on the outline of a box seen from each of
// the 27 regions around it (a perspective view: the outline follows from the eye's position) (per axis: 0 within the slab, 1 below, 2 above; region 0, inside,
// has none), in order around the outline; 4 or 6 of them, padded to 6.
const int OUTLINE_COUNT[27] = int[](0, 4, 4, 4, 6, 6, 4, 6, 6, 4, 6, 6, 6, 6, 6, 6, 6, 6, 4, 6, 6, 6, 6, 6, 6, 6, 6);
const int OUTLINE[162] = int[](
    0, 0, 0, 0, 0, 0,  0, 2, 6, 4, 0, 0,  1, 5, 7, 3, 1, 1,  0, 4, 5, 1, 0, 0,  0, 2, 6, 4, 5, 1,
    0, 4, 5, 7, 3, 1,  2, 3, 7, 6, 2, 2,  0, 2, 3, 7, 6, 4,  1, 5, 7, 6, 2, 3,  0, 1, 3, 2, 0, 0,
    0, 1, 3, 2, 6, 4,  0, 1, 5, 7, 3, 2,  0, 4, 5, 1, 3, 2,  1, 3, 2, 6, 4, 5,  0, 4, 5, 7, 3, 2,
    0, 1, 3, 7, 6, 2,  0, 1, 3, 7, 6, 4,  0, 1, 5, 7, 6, 2,  4, 6, 7, 5, 4, 4,  0, 2, 6, 7, 5, 4,
    1, 5, 4, 6, 7, 3,  0, 4, 6, 7, 5, 1,  0, 2, 6, 7, 5, 1,  0, 4, 6, 7, 3, 1,  2, 3, 7, 5, 4, 6,
    0, 2, 3, 7, 5, 4,  1, 5, 4, 6, 2, 3);

// The object's projected outline grown by u_hull_margin, in viewport pixels, in strip order
// (0, 1, n-1, 2, n-2, ...); returns its vertex count, 0 where B_viewport's rectangle is drawn
// instead: the camera inside the box, a corner behind the near plane or far off screen, a
// flat box (an edge of no length) or a corner too sharp to grow by a small step.
int hull(int object, float margin, out vec2 strip[6]) {
    vec3 lo = bounds[2 * object].xyz, hi = bounds[2 * object + 1].xyz;
    ivec3 side = ivec3(lessThan(u_eye, lo)) + 2 * ivec3(greaterThan(u_eye, hi));
    int region = side.x + 3 * side.y + 9 * side.z;
    int n = OUTLINE_COUNT[region];
    if (n == 0) return 0;
    vec2 p[6];
    for (int i = 0; i < 6; ++i) {
        int k = OUTLINE[6 * region + i];
        vec4 q = u_view_proj * vec4(mix(lo, hi, vec3(k & 1, (k >> 1) & 1, (k >> 2) & 1)), 1.0);
        if (q.z < -q.w || q.w <= 0.0) return 0;
        p[i] = (q.xy / q.w * 0.5 + 0.5) * u_viewport;
        if (any(greaterThan(abs(p[i]), vec2(1e5)))) return 0;
    }
    float area = 0.0;                      // twice the signed area: the outline's orientation
    for (int i = 0; i < 6; ++i) {
        vec2 a = p[i], b = i == n - 1 ? p[0] : p[min(i + 1, 5)];
        area += i < n ? a.x * b.y - a.y * b.x : 0.0;
    }
    float s = area < 0.0 ? -1.0 : 1.0;
    vec2 grown[6];
    for (int i = 0; i < 6; ++i) {
        vec2 prev = i == 0 ? (n == 4 ? p[3] : p[5]) : p[i - 1];
        vec2 next = i == n - 1 ? p[0] : p[min(i + 1, 5)];
        vec2 d0 = p[i] - prev, d1 = next - p[i];
        float l0 = length(d0), l1 = length(d1);
        if (i < n && min(l0, l1) < 1e-4) return 0;
        vec2 n0 = s * vec2(d0.y, -d0.x) / l0, n1 = s * vec2(d1.y, -d1.x) / l1;   // outward
        float c = 1.0 + dot(n0, n1);
        if (i < n && c < 0.01) return 0;
        grown[i] = p[i] + margin * (n0 + n1) / max(c, 0.01);
    }
    strip[0] = grown[0];
    strip[1] = grown[1];
    strip[2] = n == 4 ? grown[3] : grown[5];
    strip[3] = grown[2];
    strip[4] = grown[4];
    strip[5] = grown[3];
    return n;
}

void main() {
    Record r = records[v_object[0]];
    if (r.info.y == 0) return;
#ifdef MODE_HALO
    vec4 ndc = (r.viewport + vec4(-u_halo_width, -u_halo_width, u_halo_width, u_halo_width)) / u_viewport.xyxy * 2.0 - 1.0;
#else
    vec4 ndc = r.viewport / u_viewport.xyxy * 2.0 - 1.0;
#endif
    vec2 corners[6] = vec2[](ndc.xy, ndc.zy, ndc.xw, ndc.zw, ndc.zw, ndc.zw);
    int count = 4;
    bool outlined = u_hull;
    float margin = u_hull_margin;
#ifdef HULL_PER_SPRITE
    float scale = intBitsToFloat(r.info.w);
    vec2 size = r.viewport.zw - r.viewport.xy;
    outlined = outlined && scale >= u_upsample_below && size.x * size.y >= u_hull_min_area;
    margin = scale == 1.0 ? 1.0 / 16.0 : 1.0 / 16.0 + 0.75 / scale;
#endif
    if (outlined) {
        vec2 strip[6];
        int n = hull(v_object[0], margin, strip);
        if (n > 0) {
            count = n;
            for (int i = 0; i < 6; ++i) corners[i] = strip[i] / u_viewport * 2.0 - 1.0;
        }
    }
    for (int i = 0; i < count; ++i) {
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
