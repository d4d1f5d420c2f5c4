#version 430
// defines: STAGE LOCAL_SIZE
// Algorithm 1 on the GPU (rtta.passes.atlas_gpu), one stage per dispatch, in doubles as the CPU
// reference (rtta.atlas.parameterize) computes it:
//   STAGE 1 (per object): cull, project B_world (clipped against the near plane), viewport
//            rectangle, scale, region size, height class; a place in its class by atomics
//   STAGE 2 (one invocation): shelves per class, layers by a scan over the classes tallest
//            first; more layers than allowed: a smaller scale for the next round
//   STAGE 3 (per object): x, y, layer of each region; the used atlas width
//   STAGE 4 (per object): T and the record (records.glsl), written where capture reads it
// Packing: regions of one height class (exact below 16 texels, then 2^(1/8) steps) share
// shelves as tall as the class's tallest. A narrow region (w <= max_w / 2) takes its offset
// in the class's strip of widths (one atomicAdd: a prefix sum in any order); its shelf is
// offset / max_w unless it would cross that shelf's end. Those that would (one per shelf at
// most) take an offset in a second strip, whose shelves hold cap = max_w - the widest of them,
// so none crosses an end there. A wide region gets a shelf of its own.
#define RECORDS_WRITE 1
#include "records.glsl"

layout(local_size_x = LOCAL_SIZE) in;

#define CLASSES 128
#define EPS_PX 1.0e-3LF  // parameterize.EPS_PX
#define TINY 2.2250738585072014e-308LF

struct Class {
    uint height;     // the tallest region (its shelves' height), 0: no region this round
    uint narrow_w;   // the widest region of the second strip
    uint strip;      // the narrow regions' widths summed (their offsets, by atomicAdd)
    uint wide;       // wide regions counted
    uint cap;        // shelf capacity of the second strip
    uint shelves;    // shelves of the first strip (the second's follow, then the wide ones)
    uint layer;      // the layer and height its first shelf starts at
    uint y;
    uint first;      // shelves that fit in that layer
    uint per_layer;  // shelves per later layer
    uint strip2;     // the second strip's widths summed
    uint shelves2;   // its shelves
    uint wide_w;     // the wide regions' widths summed
    uint pad0;
    uint pad1;
    uint pad2;
};

struct Item {
    ivec4 rect;   // inner B_viewport x0, y0, x1, y1 (pixels)
    ivec4 size;   // w, h (border included), class, visible
    ivec4 place;  // offset in its strip or wide index, -, -, 0 wide / 1 first strip / 2 second
    ivec4 at;     // x, y, layer, -
    dvec2 scale;  // the scale wanted before the rounds' factor, -
};

layout(std430, binding = BINDING_PARAM_CORNERS) readonly buffer Corners { double corners[]; };
layout(std430, binding = BINDING_PARAM_SCALES) readonly buffer Scales { double wanted[]; };  // 0: hidden
layout(std430, binding = BINDING_PARAM_ITEMS) buffer Items { Item items[]; };
layout(std430, binding = BINDING_PARAM_CLASSES) coherent buffer Classes { Class classes[CLASSES]; };
layout(std430, binding = BINDING_PARAM_STATE) coherent buffer State {
    uint done;       // 1: the regions fit
    uint layers;
    uint used_w;     // the atlas's used width and height
    uint used_h;
    uint rounds;
    uint pad2;
    double factor;   // the scale-down of every region, 1 until the layers run out
};

uniform dmat4 u_vpm;          // world to clip
uniform int u_count;
uniform int u_boxes;          // enclosing boxes per object (1: AABB, 2: with the OBB)
uniform ivec2 u_viewport;
uniform int u_border;
uniform ivec2 u_atlas_max;
uniform int u_max_layers;

const ivec2 EDGES[12] = ivec2[12](ivec2(0, 1), ivec2(2, 3), ivec2(4, 5), ivec2(6, 7), ivec2(0, 2), ivec2(1, 3),
                                  ivec2(4, 6), ivec2(5, 7), ivec2(0, 4), ivec2(1, 5), ivec2(2, 6), ivec2(3, 7));

// NDC bounds of box `b` of object i: (lo.xyz, hi.xyz) and whether it is in the frustum
bool project_box(int b, int i, out dvec3 lo, out dvec3 hi) {
    dvec4 c[8];
    bool all_front = true, some_front = false;
    int base = (b * u_count + i) * 24;
    for (int k = 0; k < 8; k++) {
        dvec3 p = dvec3(corners[base + 3 * k], corners[base + 3 * k + 1], corners[base + 3 * k + 2]);
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

int height_class(int h) {
    return h <= 16 ? h : min(CLASSES - 1, 16 + int(floor(8.0 * log2(float(h) / 16.0))));
}

void project(int i) {
    bool vis = wanted[i] > 0.0;
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
    ivec4 rect = ivec4(p0, p1);
    vis = vis && rect.z > rect.x && rect.w > rect.y;
    Item it;
    it.rect = vis ? rect : ivec4(0);
    it.size = ivec4(0);
    it.place = ivec4(0);
    it.at = ivec4(0);
    it.scale = dvec2(0.0);
    if (vis) {
        dvec2 inner = dvec2(rect.zw - rect.xy);
        dvec2 room = dvec2(u_atlas_max - 2 * u_border);
        double first = min(wanted[i], min(room.x / inner.x, room.y / inner.y));
        ivec2 size = ivec2(max(ceil(inner * (first * factor) - 1.0e-9LF), dvec2(1.0))) + 2 * u_border;
        int c = height_class(size.y);
        bool narrow = 2 * size.x <= u_atlas_max.x;
        atomicMax(classes[c].height, uint(size.y));
        uint W = uint(u_atlas_max.x);
        if (narrow) {
            uint start = atomicAdd(classes[c].strip, uint(size.x));
            it.place = ivec4(int(start), 0, 0, 1);
            if (start / W != (start + uint(size.x) - 1u) / W) {  // would cross the shelf's end
                atomicMax(classes[c].narrow_w, uint(size.x));
                it.place = ivec4(int(atomicAdd(classes[c].strip2, uint(size.x))), 0, 0, 2);
            }
        } else {
            it.place = ivec4(int(atomicAdd(classes[c].wide, 1u)), 0, 0, 0);
            atomicAdd(classes[c].wide_w, uint(size.x));
        }
        it.size = ivec4(size, c, 1);
        it.scale = dvec2(first, 0.0);
    }
    items[i] = it;
}

void layout_classes() {
    uint layer = 0u, y = 0u, used_h_ = 0u;
    double area = 0.0;  // the regions' area, each as tall as its class
    bool any = false;
    uint W = uint(u_atlas_max.x), H = uint(u_atlas_max.y);
    for (int c = CLASSES - 1; c >= 0; c--) {
        uint hc = classes[c].height;
        if (hc == 0u) continue;
        uint cap = W - classes[c].narrow_w;
        uint narrow = (classes[c].strip + W - 1u) / W;
        uint second = classes[c].narrow_w == 0u ? 0u : (classes[c].strip2 + cap - 1u) / cap;
        uint total = narrow + second + classes[c].wide;
        area += (double(classes[c].strip) + double(classes[c].wide_w)) * double(hc);
        uint per = H / hc, first = (H - y) / hc;
        classes[c].cap = cap;
        classes[c].shelves = narrow;
        classes[c].shelves2 = second;
        classes[c].layer = layer;
        classes[c].y = y;
        classes[c].first = first;
        classes[c].per_layer = per;
        any = true;
        if (total <= first) {
            y += total * hc;
        } else {
            used_h_ = max(used_h_, y + first * hc);
            uint rest = total - first;
            layer += 1u + (rest - 1u) / per;
            if (rest > per) used_h_ = max(used_h_, per * hc);
            y = ((rest - 1u) % per + 1u) * hc;
        }
        used_h_ = max(used_h_, y);
    }
    uint count = any ? layer + 1u : 0u;
    if (count <= uint(u_max_layers)) {
        done = 1u;
        layers = count;
        used_h = used_h_;
        used_w = 0u;
        return;
    }
    // too many layers: every region smaller next round (none dropped), by the CPU path's rule
    double capacity = double(W) * double(H) * double(u_max_layers);
    factor *= min(0.9LF, sqrt(capacity / area) * 0.95LF);
    rounds += 1u;
    for (int c = 0; c < CLASSES; c++) {
        classes[c].height = classes[c].narrow_w = classes[c].strip = classes[c].strip2 = 0u;
        classes[c].wide = classes[c].wide_w = 0u;
    }
}

void place(int i) {
    Item it = items[i];
    if (it.size.w == 0) return;
    Class k = classes[it.size.z];
    uint shelf, x;
    uint W = uint(u_atlas_max.x);
    if (it.place.w == 1) {
        shelf = uint(it.place.x) / W;
        x = uint(it.place.x) % W;
    } else if (it.place.w == 2) {
        shelf = k.shelves + uint(it.place.x) / k.cap;
        x = uint(it.place.x) % k.cap;
    } else {
        shelf = k.shelves + k.shelves2 + uint(it.place.x);
        x = 0u;
    }
    uint layer, y;
    if (shelf < k.first) {
        layer = k.layer;
        y = k.y + shelf * k.height;
    } else {
        uint rest = shelf - k.first;
        layer = k.layer + 1u + rest / k.per_layer;
        y = (rest % k.per_layer) * k.height;
    }
    items[i].at = ivec4(int(x), int(y), int(layer), 0);
    atomicMax(used_w, x + uint(it.size.x));
}

void write_record(int i) {
    Item it = items[i];
    Record r;
    r.info = ivec4(0, 0, u_border, 0);
    r.transform = r.clip = r.atlas = r.viewport = vec4(0.0);
    if (it.size.w == 1) {
        double s = it.scale.x * factor;
        dvec2 vp = dvec2(u_viewport), at = dvec2(max(uvec2(used_w, used_h), uvec2(1u)));
        dvec2 x0 = dvec2(it.rect.xy);
        dvec2 t = (s * (vp - 2.0 * x0) + 2.0 * (dvec2(it.at.xy) + double(u_border))) / at - 1.0;
        r.transform = vec4(vec2(s * vp / at), vec2(t));
        r.clip = vec4(dvec4(it.rect) / dvec4(vp, vp) * 2.0 - 1.0);
        r.atlas = vec4(it.at.xy, it.size.xy);
        r.viewport = vec4(it.rect);
        r.info = ivec4(it.at.z, 1, u_border, floatBitsToInt(float(s)));
    }
    records[i] = r;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
#if STAGE == 2
    if (i == 0 && done == 0u) layout_classes();
#else
    if (i >= u_count) return;
#if STAGE == 1
    if (done == 0u) project(i);
#elif STAGE == 3
    if (done == 1u) place(i);
#else
    if (done == 1u) write_record(i);  // else the CPU dispatches more rounds first
#endif
#endif
}
