#version 430
// defines: STAGE BLOCK GROUP OFFSETS
// Compositing's draw order on the GPU (rtta.passes.order_gpu.GpuOrder): objects back to front by
// the view depth of their bounds centre, ties by id (composite.back_to_front's order), as a
// bitonic sort of (key, id) over a power-of-two length; (key, id) pairs are unique, so the
// order is one and the same on every driver. One stage per dispatch:
//   STAGE 1 (per element): the key of each object, an order-preserving uint of its view z
//            (ascending: farthest first); objects not drawn (invisible in R, or a focus object
//            where u_exclude_focus) and the padding keyed last; the drawn ones counted, and
//            those of them captured below u_upsample_below texels per pixel
//   STAGE 2 (per BLOCK elements): the whole bitonic sort of each block, in shared memory
//   STAGE 3 (per element pair): one compare-exchange step (u_k, u_j) with j >= BLOCK
//   STAGE 4 (per BLOCK elements): the steps j < BLOCK of merge u_k, in shared memory
//   STAGE 5 (one invocation): three indirect DrawArrays commands (count, 1, 0, 0), 5 uints
//            apart (moderngl's stride), of which one draws and the others draw none: the
//            list's count where no drawn region is upsampled, where all are, where some are
//            (u_total: that count instead of the drawn one, for a list of every id); and three
//            for a focus list of u_focus ids: its count where every visible focus region is at
//            one texel per pixel (quad outlines), else where none is upsampled, else in the
//            third (each sprite choosing)
// Or a stable LSD radix sort of the keys (ids in ascending order to start: ties stay by id),
// RADIX_BITS a pass, over tiles of TILE = 256 * PER elements (u_tiles of them). The pass is
// counted on the GPU (command[PASS_NOW], zeroed with the buffer; the last work group of stage 8
// to finish moves it on), so the CPU sets no uniform and binds no buffer between passes: even
// passes read keys/ids and write keys_out/ids_out, odd passes the other way round (an even
// number of passes ends in keys/ids). Two dispatches a pass:
//   STAGE 6 (per tile): each digit's count in the tile, into counts[digit * u_tiles + tile]
//   STAGE 8 (per tile): the tile's first place for each digit summed from the counts (those of
//            the smaller digits, and of its digit in the tiles before: no scan dispatch between),
//            the tile sorted by digit in shared memory (each invocation's PER elements in
//            order, its places from a scan of the per-invocation counts), each element written
//            at its tile's place for its digit plus its rank there
// Counts come from shared atomics (their sums do not depend on the order) and places from
// scans: the result is the same on every driver.
// OFFSETS: per-object offsets (x, y, z float triples) added to the bounds centres.
#include "records.glsl"

#define RADIX_BITS 4
#define DIGITS 16
#define PER 8
#define TILE (256 * PER)

#if STAGE == 1 || STAGE == 3 || STAGE >= 6
layout(local_size_x = 256) in;
#elif STAGE == 5
layout(local_size_x = 1) in;
#else
layout(local_size_x = GROUP) in;  // each invocation compares BLOCK / 2 / GROUP pairs a step
#endif

layout(std430, binding = BINDING_SORT_KEYS) buffer KeyBuffer { uint keys[]; };
layout(std430, binding = BINDING_DRAW_LIST) buffer IdBuffer { uint ids[]; };

uniform uint u_k;       // the bitonic merge's size (stages 3, 4)
uniform uint u_j;       // the compare distance (stage 3)
uniform uint u_length;  // elements (>= u_count: a power of two, or a multiple of TILE; stages 1, 3)
uniform uint u_tiles;   // the radix passes' tiles

// commands at 0, 5, 10; then the drawn objects' count, the upsampled ones', the upsampled
// focus objects' and the focus objects' not at one texel per pixel; then the focus list's
// commands at 20 (every one at one texel per pixel), 25 (none upsampled) and 30 (some)
#define DRAWN 15
#define UPSAMPLED 16
#define FOCUS_UPSAMPLED 17
#define FOCUS_SCALED 18
#define PASS_NOW 35   // the radix pass stages 6 and 8 count and sort by
#define PASS_DONE 36  // stage 8's work groups done with the pass (the last resets it)
layout(std430, binding = BINDING_COMPOSITE_COMMAND) buffer CommandBuffer { uint command[37]; };

bool after(uint ka, uint ia, uint kb, uint ib) { return ka > kb || (ka == kb && ia > ib); }

#if STAGE == 1
struct Style { vec4 params; };  // composite.glsl's: (opacity, focus, uses AO, uses edges)
layout(std430, binding = BINDING_STYLES) readonly buffer StyleBuffer { Style styles[]; };
layout(std430, binding = BINDING_BOUNDS) readonly buffer BoundsBuffer { vec4 bounds[]; };
#ifdef OFFSETS
layout(std430, binding = BINDING_SORT_OFFSETS) readonly buffer OffsetBuffer { float offsets[]; };
#endif
uniform uint u_count;          // objects
uniform vec4 u_depth_row;      // the view matrix's third row: view z = dot(row.xyz, p) + row.w
uniform bool u_focus_flags;    // the style buffer is bound: its focus flags name the focus (counted)
uniform bool u_exclude_focus;  // with u_focus_flags: the focus objects are not drawn
uniform float u_upsample_below;  // sprites.UPSAMPLE_BELOW

// float -> uint with the same order (-0 as +0, so that they tie as numpy's keys do)
uint ordered(float f) {
    uint u = f == 0.0 ? 0u : floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : u | 0x80000000u;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= u_length) return;
    uint key = 0xFFFFFFFFu;
    if (i < u_count) {
        bool focus = u_focus_flags && styles[i].params.y > 0.5;
        float scale = intBitsToFloat(records[i].info.w);
        bool upsampled = scale < u_upsample_below;
        if (focus && records[i].info.y != 0) {
            if (upsampled) atomicAdd(command[FOCUS_UPSAMPLED], 1u);
            if (scale != 1.0) atomicAdd(command[FOCUS_SCALED], 1u);
        }
        bool drawn = records[i].info.y != 0 && !(focus && u_exclude_focus);
        if (drawn) {
            vec3 c = (bounds[2 * i].xyz + bounds[2 * i + 1].xyz) * 0.5;
#ifdef OFFSETS
            c += vec3(offsets[3 * i], offsets[3 * i + 1], offsets[3 * i + 2]);
#endif
            precise float z = dot(u_depth_row.xyz, c) + u_depth_row.w;
            key = min(ordered(z), 0xFFFFFFFEu);  // a drawn key stays before every undrawn one
            atomicAdd(command[DRAWN], 1u);
            if (upsampled) atomicAdd(command[UPSAMPLED], 1u);
        }
    }
    keys[i] = key;
    ids[i] = i;  // the padding's ids (>= u_count) stay after every object's
}

#elif STAGE == 5
uniform uint u_total;   // 0: the drawn count
uniform uint u_focus;   // the focus list's length (a list of the CPU's: composite's focus draw)
void main() {
    uint drawn = command[DRAWN], up = command[UPSAMPLED];
    uint focus_up = command[FOCUS_UPSAMPLED], focus_scaled = command[FOCUS_SCALED];
    uint count = u_total > 0u ? u_total : drawn;
    bool classes[3] = bool[](drawn > 0u && up == 0u, drawn > 0u && up == drawn, up > 0u && up < drawn);
    uint counts[6] = uint[](classes[0] ? count : 0u, classes[1] ? count : 0u, classes[2] ? count : 0u,
                            focus_scaled == 0u ? u_focus : 0u, focus_scaled > 0u && focus_up == 0u ? u_focus : 0u,
                            focus_up > 0u ? u_focus : 0u);
    for (int c = 0; c < 6; ++c) {
        uint at = c < 3 ? uint(5 * c) : uint(20 + 5 * (c - 3));
        command[at] = counts[c];
        command[at + 1u] = 1u;
        command[at + 2u] = 0u;
        command[at + 3u] = 0u;
    }
}

#elif STAGE >= 6
layout(std430, binding = BINDING_SORT_COUNTS) buffer CountBuffer { uint counts[]; };
layout(std430, binding = BINDING_SORT_KEYS_OUT) buffer KeyOutBuffer { uint keys_out[]; };
layout(std430, binding = BINDING_SORT_IDS_OUT) buffer IdOutBuffer { uint ids_out[]; };
shared uint s_part[256];

uint pass_index;  // set first in main: the pass this dispatch belongs to
uint digit(uint key) { return (key >> (uint(RADIX_BITS) * pass_index)) & uint(DIGITS - 1); }
uint key_in(uint i) { return (pass_index & 1u) == 0u ? keys[i] : keys_out[i]; }
uint id_in(uint i) { return (pass_index & 1u) == 0u ? ids[i] : ids_out[i]; }
void put(uint i, uint key, uint id) {
    if ((pass_index & 1u) == 0u) {
        keys_out[i] = key;
        ids_out[i] = id;
    } else {
        keys[i] = key;
        ids[i] = id;
    }
}

// s_part's inclusive prefix sums (256 invocations, each its own entry)
void scan_parts(uint t) {
    for (uint off = 1u; off < 256u; off <<= 1) {
        uint v = t >= off ? s_part[t - off] : 0u;
        barrier();
        s_part[t] += v;
        memoryBarrierShared();
        barrier();
    }
}

#if STAGE == 6
shared uint s_count[DIGITS];
void main() {
    uint t = gl_LocalInvocationID.x, tile = gl_WorkGroupID.x;
    pass_index = command[PASS_NOW];
    if (t < uint(DIGITS)) s_count[t] = 0u;
    memoryBarrierShared();
    barrier();
    for (uint e = 0u; e < uint(PER); ++e) atomicAdd(s_count[digit(key_in(tile * uint(TILE) + e * 256u + t))], 1u);
    memoryBarrierShared();
    barrier();
    if (t < uint(DIGITS)) counts[t * u_tiles + tile] = s_count[t];
}

#else
shared uint s_place[DIGITS * 256];  // digit-major: [digit][invocation]
shared uint s_total[DIGITS], s_before[DIGITS], s_first[DIGITS];

// s_first: the tile's first place for each digit (the counts of the smaller digits, then of
// its digit in the tiles before), each invocation summing a few counts
void first_places(uint t, uint tile) {
    if (t < uint(DIGITS)) s_total[t] = s_before[t] = 0u;
    memoryBarrierShared();
    barrier();
    for (uint i = t; i < uint(DIGITS) * u_tiles; i += 256u) {
        uint d = i / u_tiles, c = counts[i];
        atomicAdd(s_total[d], c);
        if (i - d * u_tiles < tile) atomicAdd(s_before[d], c);
    }
    memoryBarrierShared();
    barrier();
    if (t < uint(DIGITS)) {
        uint at = s_before[t];
        for (uint d = 0u; d < t; ++d) at += s_total[d];
        s_first[t] = at;
    }
}

void main() {
    uint t = gl_LocalInvocationID.x, tile = gl_WorkGroupID.x, base = tile * uint(TILE) + t * uint(PER);
    pass_index = command[PASS_NOW];
    first_places(t, tile);
    uint k[PER], id[PER], n[DIGITS];
    for (uint d = 0u; d < uint(DIGITS); ++d) n[d] = 0u;
    for (uint e = 0u; e < uint(PER); ++e) {
        k[e] = key_in(base + e);
        id[e] = id_in(base + e);
        n[digit(k[e])] += 1u;
    }
    // the invocation's counts at [digit][t]; a scan over them in that order gives, for each
    // digit and invocation, the place of its first element in the tile sorted by digit
    for (uint d = 0u; d < uint(DIGITS); ++d) s_place[d * 256u + t] = n[d];
    memoryBarrierShared();
    barrier();
    uint sum = 0u;  // invocation t scans the DIGITS entries from t * DIGITS
    for (uint i = 0u; i < uint(DIGITS); ++i) sum += s_place[t * uint(DIGITS) + i];
    s_part[t] = sum;
    memoryBarrierShared();
    barrier();
    scan_parts(t);
    uint at = s_part[t] - sum;
    for (uint i = 0u; i < uint(DIGITS); ++i) {
        uint c = s_place[t * uint(DIGITS) + i];
        s_place[t * uint(DIGITS) + i] = at;
        at += c;
    }
    memoryBarrierShared();
    barrier();
    for (uint d = 0u; d < uint(DIGITS); ++d) n[d] = 0u;
    for (uint e = 0u; e < uint(PER); ++e) {
        uint d = digit(k[e]);
        // the tile's place for the digit, plus the element's rank among the tile's of that digit
        uint place = s_first[d] + s_place[d * 256u + t] - s_place[d * 256u] + n[d];
        n[d] += 1u;
        put(place, k[e], id[e]);
    }
    // the last work group to finish moves the pass on: every group read it at its start
    memoryBarrierBuffer();
    barrier();
    if (t == 0u && atomicAdd(command[PASS_DONE], 1u) == u_tiles - 1u) {
        command[PASS_DONE] = 0u;
        command[PASS_NOW] = pass_index + 1u;
    }
}
#endif

#elif STAGE == 3
void main() {
    uint g = gl_GlobalInvocationID.x;
    uint i = 2u * u_j * (g / u_j) + (g % u_j), l = i + u_j;
    if (l >= u_length) return;
    bool ascending = (i & u_k) == 0u;
    uint ka = keys[i], kb = keys[l], ia = ids[i], ib = ids[l];
    if (after(ka, ia, kb, ib) == ascending) {
        keys[i] = kb; keys[l] = ka;
        ids[i] = ib; ids[l] = ia;
    }
}

#else
shared uint s_key[BLOCK];
shared uint s_id[BLOCK];

// compare-exchange of thread t's pair at distance j in merge k (block starting at `base`)
void exchange(uint t, uint k, uint j, uint base) {
    uint i = 2u * j * (t / j) + (t % j), l = i + j;
    bool ascending = ((base + i) & k) == 0u;
    uint ka = s_key[i], kb = s_key[l], ia = s_id[i], ib = s_id[l];
    if (after(ka, ia, kb, ib) == ascending) {
        s_key[i] = kb; s_key[l] = ka;
        s_id[i] = ib; s_id[l] = ia;
    }
}

void main() {
    uint t = gl_LocalInvocationID.x, base = gl_WorkGroupID.x * uint(BLOCK);
    for (uint e = t; e < uint(BLOCK); e += uint(GROUP)) {
        s_key[e] = keys[base + e];
        s_id[e] = ids[base + e];
    }
    memoryBarrierShared();
    barrier();
#if STAGE == 2
    for (uint k = 2u; k <= uint(BLOCK); k <<= 1) {
#else
    for (uint k = u_k; k == u_k; k = 0u) {  // one merge: its steps below BLOCK
#endif
        for (uint j = min(k, uint(BLOCK)) >> 1; j > 0u; j >>= 1) {
            for (uint p = t; p < uint(BLOCK / 2); p += uint(GROUP)) exchange(p, k, j, base);
            memoryBarrierShared();
            barrier();
        }
    }
    for (uint e = t; e < uint(BLOCK); e += uint(GROUP)) {
        keys[base + e] = s_key[e];
        ids[base + e] = s_id[e];
    }
}
#endif
