// B_world projected to a viewport rectangle (parameterize.comp, thinned.comp share it): the
// box corners in doubles as rtta.atlas.parameterize computes them, clipped against the near plane.

const ivec2 EDGES[12] = ivec2[12](ivec2(0, 1), ivec2(2, 3), ivec2(4, 5), ivec2(6, 7), ivec2(0, 2), ivec2(1, 3),
                                  ivec2(4, 6), ivec2(5, 7), ivec2(0, 4), ivec2(1, 5), ivec2(2, 6), ivec2(3, 7));

// NDC bounds of box `b` of object i: (lo.xyz, hi.xyz) and whether it is in the frustum
bool project_box(int b, int i, out dvec3 lo, out dvec3 hi) {
    dvec4 c[8];
    bool all_front = true, some_front = false;
    int base = (b * u_count + i) * 24;
    dvec3 moved = u_offsets ? dvec3(offsets[3 * i], offsets[3 * i + 1], offsets[3 * i + 2]) : dvec3(0.0);
    for (int k = 0; k < 8; k++) {
        dvec3 p = dvec3(corners[base + 3 * k], corners[base + 3 * k + 1], corners[base + 3 * k + 2]) + moved;
        c[k] = u_vpm * dvec4(p, 1.0);
        bool front = c[k].z + c[k].w >= 0.0;
        all_front = all_front && front;
        some_front = some_front || front;
    }
    lo = dvec3(1.0e300LF);
    hi = dvec3(-1.0e300LF);
    if (!some_front) {
        lo = hi = dvec3(0.0);
        return false;
    }
    for (int k = 0; k < 8; k++) {
        if (all_front || c[k].z + c[k].w >= 0.0) {
            dvec3 q = c[k].xyz / (all_front ? c[k].w : max(c[k].w, TINY));
            lo = min(lo, q);
            hi = max(hi, q);
        }
    }
    if (!all_front) {  // crossing the near plane: the edges' intersections with it
        for (int e = 0; e < 12; e++) {
            dvec4 a = c[EDGES[e].x], d = c[EDGES[e].y];
            double da = a.z + a.w, db = d.z + d.w;
            if (da * db < 0.0) {
                dvec4 h = a + (da / (da - db)) * (d - a);
                dvec3 q = h.xyz / max(h.w, TINY);
                lo = min(lo, q);
                hi = max(hi, q);
            }
        }
    }
    return lo.x <= 1.0 && hi.x >= -1.0 && lo.y <= 1.0 && hi.y >= -1.0 && lo.z <= 1.0;
}

// The inner B_viewport of object i in pixels (x0, y0, x1, y1), its boxes' projections
// intersected; whether it is in the frustum with at least one pixel (rtta.atlas.parameterize's
// viewport_rects).
bool viewport_rect(int i, out ivec4 rect) {
    bool vis = true;
    dvec2 lo = dvec2(-1.0e300LF), hi = dvec2(1.0e300LF);
    for (int b = 0; b < u_boxes && vis; b++) {
        dvec3 l, h;
        vis = project_box(b, i, l, h);
        lo = max(lo, l.xy);
        hi = min(hi, h.xy);
    }
    vis = vis && all(lessThanEqual(lo, hi));
    dvec2 wh = dvec2(u_viewport);
    dvec2 p0 = (clamp(lo, -1.0, 1.0) + 1.0) * (0.5 * wh), p1 = (clamp(hi, -1.0, 1.0) + 1.0) * (0.5 * wh);
    p0 = clamp(floor(p0 - EPS_PX), dvec2(0.0), wh);
    p1 = clamp(ceil(p1 + EPS_PX), dvec2(0.0), wh);
    p1 = max(p1, min(p0 + 1.0, wh));
    p0 = min(p0, p1 - 1.0);
    rect = ivec4(p0, p1);
    return vis && rect.z > rect.x && rect.w > rect.y;
}
