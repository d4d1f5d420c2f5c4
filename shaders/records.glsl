// The record buffer R shared by capture, post-processing and compositing (one entry per object ID).
struct Record {
    vec4 transform;   // T as (sx, sy, tx, ty): ndc_atlas = s * ndc_viewport + t
    vec4 clip;        // inner B_viewport in viewport NDC (x0, y0, x1, y1): the clip planes
    vec4 atlas;       // B_atlas in texels (x, y, w, h), border included
    vec4 viewport;    // inner B_viewport in pixels (x0, y0, x1, y1)
    ivec4 info;       // (layer, visible, border, floatBitsToInt(scale))
};
#ifdef RECORDS_WRITE  // parameterize.comp writes R
layout(std430, binding = BINDING_RECORDS) writeonly buffer RecordBuffer { Record records[]; };
#else
layout(std430, binding = BINDING_RECORDS) readonly buffer RecordBuffer { Record records[]; };
#endif
layout(std430, binding = BINDING_OBJECTS) readonly buffer ObjectBuffer { vec4 object_colors[]; };

// Screen-space vertex displacement, done in clip space: T is affine in NDC, so
// (T * (v / w)) * w == (s * v.xy + t * v.w, v.z, v.w), exact and safe for any w.
vec4 displace(vec4 clip_pos, vec4 T) {
    return vec4(T.xy * clip_pos.xy + T.zw * clip_pos.w, clip_pos.zw);
}

// Distances to the four planes of the object's inner viewport rectangle (>= 0 inside).
// REGION_GUARD (an extreme zoom: rtta.passes.guard): the planes stand u_region_guard NDC
// further out, beyond float32's error in clipping huge triangles to them, and scene.frag
// keeps the fragments inside the rectangle itself (region_holds).
#ifdef REGION_GUARD
uniform float u_region_guard;
#endif
void region_clip_distances(vec4 clip_pos, vec4 r, out float d[4]) {
#ifdef REGION_GUARD
    r += vec4(-u_region_guard, -u_region_guard, u_region_guard, u_region_guard);
#endif
    d[0] = clip_pos.x - r.x * clip_pos.w;
    d[1] = r.z * clip_pos.w - clip_pos.x;
    d[2] = clip_pos.y - r.y * clip_pos.w;
    d[3] = r.w * clip_pos.w - clip_pos.y;
}

#ifdef REGION_GUARD
// Whether the texel centre at atlas pixel `frag` (gl_FragCoord.xy) lies in the object's inner
// B_viewport (record r), the planes' own test made per fragment: T^-1 back to viewport NDC.
uniform vec2 u_atlas_size;
bool region_holds(vec2 frag, Record r) {
    vec2 ndc = (frag / u_atlas_size * 2.0 - 1.0 - r.transform.zw) / r.transform.xy;
    return all(greaterThanEqual(ndc, r.clip.xy)) && all(lessThanEqual(ndc, r.clip.zw));
}
#endif
