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
void region_clip_distances(vec4 clip_pos, vec4 r, out float d[4]) {
    d[0] = clip_pos.x - r.x * clip_pos.w;
    d[1] = r.z * clip_pos.w - clip_pos.x;
    d[2] = clip_pos.y - r.y * clip_pos.w;
    d[3] = r.w * clip_pos.w - clip_pos.y;
}
