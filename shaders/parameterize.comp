#version 430
// defines: STAGE LOCAL_SIZE
// Algorithm 1 on the GPU (rtta.passes.atlas_gpu), one stage per dispatch, in doubles as the CPU
// reference (rtta.atlas.parameterize) computes it. A round (stages 1-4) packs; it runs again,
// every region smaller, while the layers do not suffice (none dropped):
//   STAGE 1 (per object): cull, project B_world (clipped against the near plane), viewport
//            rectangle, scale, region size, height class; an offset in its class's strip
//   STAGE 2 (one invocation): the classes' strips laid end to end, tallest class first, and
//            cut into shelves of max_w; each shelf as tall as the class at its start; layers
//            next-fit over the shelves
//   STAGE 3 (per object): a region in one shelf placed; one that would cross a shelf's end
//            takes an offset in the second strip instead
//   STAGE 4 (one invocation): the second strip's shelves (cap = max_w - its widest region, so
//            none crosses an end), then a shelf per wide region; enough layers, or a smaller
//            scale for the next round
//   STAGE 5 (per object): the second strip's and the wide regions placed; the used width
//   STAGE 6 (per object): T and the record (records.glsl), written where capture reads it
//   STAGES 7, 8 (before the rounds, fast navigation only): the smallest objects left out
//   STAGE 9 (one work group, few objects): stages 1-6 in turn, u_rounds rounds, barriers between
//            (each object stays with one invocation: items need no coherence across them)
// This is next-fit decreasing height (the CPU path's packing) with the strips' order in a
// class given by atomics and the regions that cross a shelf's end moved to the second strip.
// Narrow: w <= max_w / 2; a wide region gets a shelf of its own. Height classes: exact below
// 16 texels, then 2^(1/8) steps.
#define RECORDS_WRITE 1
#include "records.glsl"

layout(local_size_x = LOCAL_SIZE) in;

#define CLASSES 128
#define EPS_PX 1.0e-3LF  // parameterize.EPS_PX
#define TINY 2.2250738585072014e-308LF

struct Class {
    uint height;     // the tallest region, 0: no region this round
    uint strip;      // the narrow regions' widths summed (their offsets, by atomicAdd)
    uint strip2;     // the second strip's
    uint wide;       // wide regions counted
    uint wide_w;     // their widths summed
    uint base;       // where the class's strip starts in the strips laid end to end
    uint base2;      // likewise in the second strip
    uint layer;      // the layer and height the class's first wide shelf starts at
    uint y;
    uint first;      // wide shelves that fit in that layer
    uint per_layer;  // wide shelves per later layer
    uint pad0;
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
layout(std430, binding = BINDING_PARAM_OFFSETS) readonly buffer Offsets { double offsets[]; };  // explode, xyz
layout(std430, binding = BINDING_PARAM_ITEMS) buffer Items { Item items[]; };
layout(std430, binding = BINDING_PARAM_CLASSES) coherent buffer Classes { Class classes[CLASSES]; };
#if STAGE == 9  // one work group: the classes in shared memory (thread 0's layout loops wait on L2 otherwise)
shared Class cls[CLASSES];
#define CLASS cls
#else
#define CLASS classes
#endif
layout(std430, binding = BINDING_PARAM_SHELVES) coherent buffer Shelves { uvec2 shelves[]; };  // layer, y
layout(std430, binding = BINDING_PARAM_STATE) coherent buffer State {
    uint done;       // 1: the regions fit
    uint layers;
    uint used_w;     // the atlas's used width and height
    uint used_h;
    uint rounds;
    uint cursor_layer;  // next-fit's layer and height after the first strip's shelves
    uint cursor_y;
    uint shelves1;   // the first strip's shelves (the second's follow in Shelves)
    uint wide2;      // the widest region of the second strip
    uint cap2;       // its shelves' width
    uint demand;     // the layers the first round needed, before any scale-down
    uint pad;
    double factor;   // the scale-down of every region, 1 until the layers run out
    double area;     // the regions' area, each as tall as its class (for the scale-down)
};

// the next round's dispatch sizes (glDispatchComputeIndirect): per object, then one invocation;
// 0 groups once the regions fit, so the rounds dispatched ahead cost nothing
layout(std430, binding = BINDING_PARAM_DISPATCH) buffer Dispatch { uint next_round[8]; };

// fast navigation's thinning (rtta.passes.thin_gpu): per object its area class, the classes'
// triangles and objects, the class below which objects are left out, and how many are
#define THIN_BINS 128
#define NOT_RANKED 0xFFFFFFFFu
#define PROTECT 0x80000000u
layout(std430, binding = BINDING_PARAM_THIN) coherent buffer Thin {
    uint thin_hist[2 * THIN_BINS];  // triangles per class, then objects per class
    uint thin_cut;
    uint thin_left;
    uint thin_pad[2];
    uint thin_bin[];  // per object: floor(4 log2(area)) of B_viewport, THIN_BINS - 1 protected
};
layout(std430, binding = BINDING_PARAM_WEIGHTS) readonly buffer Weights { uint weight[]; };  // triangles | PROTECT
uniform bool u_thin;          // thin_cut leaves objects out (stages 7 and 8 ran)
uniform float u_keep;         // the share of the visible triangles kept

uniform dmat4 u_vpm;          // world to clip
uniform int u_count;
uniform int u_boxes;          // enclosing boxes per object (1: AABB, 2: with the OBB)
uniform bool u_offsets;       // the objects moved by Offsets (an exploded view)
uniform ivec2 u_viewport;
uniform int u_border;
uniform ivec2 u_atlas_max;
uniform int u_max_layers;
uniform ivec2 u_extent;       // the atlas extent T maps to; (0, 0): the extent used

#include "project_box.glsl"

int height_class(int h) {
    return h <= 16 ? h : min(CLASSES - 1, 16 + int(floor(8.0 * log2(float(h) / 16.0))));
}

void project(int i) {
    ivec4 rect;
    bool vis = wanted[i] > 0.0 && !(u_thin && thin_bin[i] < thin_cut) && viewport_rect(i, rect);
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
        atomicMax(CLASS[c].height, uint(size.y));
        if (2 * size.x <= u_atlas_max.x) {
            it.place = ivec4(int(atomicAdd(CLASS[c].strip, uint(size.x))), 0, 0, 1);
        } else {
            it.place = ivec4(int(atomicAdd(CLASS[c].wide, 1u)), 0, 0, 0);
            atomicAdd(CLASS[c].wide_w, uint(size.x));
        }
        it.size = ivec4(size, c, 1);
        it.scale = dvec2(first, 0.0);
    }
    items[i] = it;
}

// next-fit: a shelf of height h at the cursor (layer, y), or at the top of the next layer
uvec2 next_fit(uint h, inout uint layer, inout uint y, inout uint top) {
    if (y + h > uint(u_atlas_max.y)) {
        layer += 1u;
        y = 0u;
    }
    uvec2 at = uvec2(layer, y);
    y += h;
    top = max(top, y);
    return at;
}

// the shelves of a strip laid end to end (tallest class first), cut every `width` texels,
// stored from `first`; each as tall as the class whose strip covers its start
void strip_shelves(bool second, uint width, uint first, inout uint layer, inout uint y, inout uint top) {
    uint base = 0u;
    for (int c = CLASSES - 1; c >= 0; c--) {
        if (second) CLASS[c].base2 = base; else CLASS[c].base = base;
        base += second ? CLASS[c].strip2 : CLASS[c].strip;
    }
    uint count = (base + width - 1u) / width;
    int c = CLASSES - 1;
    for (uint s = 0u; s < count; s++) {
        uint at = s * width;
        while (c > 0 && (second ? CLASS[c].base2 + CLASS[c].strip2 : CLASS[c].base + CLASS[c].strip) <= at) c--;
        shelves[first + s] = next_fit(CLASS[c].height, layer, y, top);
    }
    if (!second) shelves1 = count;
}

void layout_first() {
    uint layer = 0u, y = 0u, top = 0u;
    double total = 0.0;
    for (int c = 0; c < CLASSES; c++) {
        total += (double(CLASS[c].strip) + double(CLASS[c].wide_w)) * double(CLASS[c].height);
    }
    area = total;
    strip_shelves(false, uint(u_atlas_max.x), 0u, layer, y, top);
    cursor_layer = layer;
    cursor_y = y;
    used_h = top;
}

void place_first(int i) {
    Item it = items[i];
    if (it.size.w == 0 || it.place.w != 1) return;
    uint W = uint(u_atlas_max.x), w = uint(it.size.x);
    uint at = CLASS[it.size.z].base + uint(it.place.x);
    if (at / W != (at + w - 1u) / W) {  // would cross its shelf's end: to the second strip
        atomicMax(wide2, w);
        items[i].place = ivec4(int(atomicAdd(CLASS[it.size.z].strip2, w)), 0, 0, 2);
        return;
    }
    uvec2 shelf = shelves[at / W];
    items[i].at = ivec4(int(at % W), int(shelf.y), int(shelf.x), 0);
}

void layout_second() {
    uint layer = cursor_layer, y = cursor_y, top = used_h;
    uint W = uint(u_atlas_max.x), H = uint(u_atlas_max.y);
    bool some = shelves1 > 0u;
    cap2 = W - wide2;
    if (wide2 > 0u) {
        strip_shelves(true, cap2, shelves1, layer, y, top);
        some = true;
    }
    for (int c = CLASSES - 1; c >= 0; c--) {  // a shelf per wide region, class by class
        uint hc = CLASS[c].height, count = CLASS[c].wide;
        if (count == 0u) continue;
        if (y + hc > H) {
            layer += 1u;
            y = 0u;
        }
        uint per = H / hc, first = (H - y) / hc;
        CLASS[c].layer = layer;
        CLASS[c].y = y;
        CLASS[c].first = first;
        CLASS[c].per_layer = per;
        some = true;
        if (count <= first) {
            y += count * hc;
        } else {
            top = max(top, y + first * hc);
            uint rest = count - first;
            layer += 1u + (rest - 1u) / per;
            if (rest > per) top = max(top, per * hc);
            y = ((rest - 1u) % per + 1u) * hc;
        }
        top = max(top, y);
    }
    uint count = some ? layer + 1u : 0u;
    if (rounds == 0u) demand = count;
    if (count <= uint(u_max_layers)) {
        next_round[0] = 0u;  // the rounds after this one: none
        next_round[4] = 0u;
        done = 1u;
        layers = count;
        used_h = top;
        used_w = 0u;
        return;
    }
    // too many layers: every region smaller next round (none dropped), by the CPU path's rule
    double capacity = double(W) * double(H) * double(u_max_layers);
    factor *= min(0.9LF, sqrt(capacity / area) * 0.95LF);
    rounds += 1u;
    wide2 = 0u;
    for (int c = 0; c < CLASSES; c++) {
        CLASS[c].height = CLASS[c].strip = CLASS[c].strip2 = CLASS[c].wide = CLASS[c].wide_w = 0u;
    }
}

void place_second(int i) {
    Item it = items[i];
    if (it.size.w == 0) return;
    Class k = CLASS[it.size.z];
    if (it.place.w == 2) {
        uint at = k.base2 + uint(it.place.x);
        uvec2 shelf = shelves[shelves1 + at / cap2];
        it.at = ivec4(int(at % cap2), int(shelf.y), int(shelf.x), 0);
    } else if (it.place.w == 0) {
        uint shelf = uint(it.place.x), layer, y;
        if (shelf < k.first) {
            layer = k.layer;
            y = k.y + shelf * k.height;
        } else {
            uint rest = shelf - k.first;
            layer = k.layer + 1u + rest / k.per_layer;
            y = (rest % k.per_layer) * k.height;
        }
        it.at = ivec4(0, int(y), int(layer), 0);
    }
    items[i].at = it.at;
    atomicMax(used_w, uint(it.at.x + it.size.x));
}

void write_record(int i) {
    Item it = items[i];
    Record r;
    r.info = ivec4(0, 0, u_border, 0);
    r.transform = r.clip = r.atlas = r.viewport = vec4(0.0);
    if (it.size.w == 1 && done == 1u) {
        double s = it.scale.x * factor;
        uvec2 extent = u_extent.x > 0 ? uvec2(u_extent) : uvec2(used_w, used_h);
        dvec2 vp = dvec2(u_viewport), at = dvec2(max(extent, uvec2(1u)));
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

// STAGE 7 (per object): its area class, counted; rtta.atlas.thinning.left_out ranks by area too
void thin_rank(int i) {
    ivec4 rect;
    uint bin = NOT_RANKED;  // culled or hidden: never left out (they cost nothing)
    if (wanted[i] > 0.0 && viewport_rect(i, rect)) {
        uint w = weight[i];
        float area = float(rect.z - rect.x) * float(rect.w - rect.y);
        bin = (w & PROTECT) != 0u ? uint(THIN_BINS - 1) : uint(clamp(int(floor(4.0 * log2(area))), 0, THIN_BINS - 2));
        atomicAdd(thin_hist[bin], w & ~PROTECT);
        atomicAdd(thin_hist[THIN_BINS + int(bin)], 1u);
    }
    thin_bin[i] = bin;
}

// STAGE 8 (one invocation): from the largest class down, every class that starts within the
// budget is kept (left_out's rule, a class at a time); the classes below are left out
void thin_cut_classes() {
    double total = 0.0, before = 0.0;
    for (int b = 0; b < THIN_BINS; b++) total += double(thin_hist[b]);
    double budget = double(u_keep) * total;
    uint cut = 0u, left = 0u;
    for (int b = THIN_BINS - 1; b >= 0; b--) {
        if (before > budget) {
            cut = uint(b + 1);
            break;
        }
        before += double(thin_hist[b]);
    }
    for (uint b = 0u; b < cut; b++) left += thin_hist[THIN_BINS + int(b)];
    thin_cut = cut;
    thin_left = left;
}

#if STAGE == 9
uniform int u_rounds;

// what the invocations wrote to the coherent buffers (shelves, state) and the classes seen by all
void stage_done() {
    memoryBarrierBuffer();
    memoryBarrierShared();
    barrier();
}

void main() {
    int t = int(gl_LocalInvocationIndex);
    for (int c = t; c < CLASSES; c += LOCAL_SIZE) cls[c] = classes[c];
    stage_done();
    for (int r = 0; r < u_rounds; r++) {  // rounds after the fit change nothing (done), as dispatched ones
        for (int i = t; i < u_count; i += LOCAL_SIZE) if (done == 0u) project(i);
        stage_done();
        if (t == 0 && done == 0u) layout_first();
        stage_done();
        for (int i = t; i < u_count; i += LOCAL_SIZE) if (done == 0u) place_first(i);
        stage_done();
        if (t == 0 && done == 0u) layout_second();
        stage_done();
    }
    for (int i = t; i < u_count; i += LOCAL_SIZE) if (done == 1u) place_second(i);
    stage_done();
    for (int i = t; i < u_count; i += LOCAL_SIZE) write_record(i);
    for (int c = t; c < CLASSES; c += LOCAL_SIZE) classes[c] = cls[c];
}
#else
void main() {
    int i = int(gl_GlobalInvocationID.x);
#if STAGE == 8
    if (i == 0) thin_cut_classes();
#elif STAGE == 2 || STAGE == 4
    if (i != 0 || done != 0u) return;
#if STAGE == 2
    layout_first();
#else
    layout_second();
#endif
#else
    if (i >= u_count) return;
#if STAGE == 1
    if (done == 0u) project(i);
#elif STAGE == 3
    if (done == 0u) place_first(i);
#elif STAGE == 5
    if (done == 1u) place_second(i);
#elif STAGE == 7
    thin_rank(i);
#else
    write_record(i);  // no region while the regions do not fit yet (more rounds follow)
#endif
#endif
}
#endif
