#version 430
// defines: OVER FIRST_FETCHED
// `--order pixel`: each pixel's list of object surfaces (oit.glsl) blended front to back in
// the order of their depths (ties: by packed colour, so the blend depends on the surfaces
// alone, not on the order their fragments arrived in). The K = 8 nearest surfaces are sorted
// exactly in registers (each through a fixed chain of compare-and-swap selects; no local
// arrays: on llvmpipe an array indexed per lane is scattered lane by lane, and a sort over
// one cost 4 s a frame). With more than K surfaces over one pixel, each further one goes
// through the same chain and what leaves it (the farthest of the K + 1) is merged into one
// layer behind the K kept, with the opacity-weighted mean colour and combined opacity
// 1 - prod(1 - a) (weighted blended, up to MAX_LIST surfaces). Both are independent of the
// list's order, which on a GPU is the order fragments arrived in. The list's first K nodes
// are taken in a loop short enough to unroll: walking every node in one long loop cost 10x
// more on llvmpipe (487 ms against 45 ms on the demo at 1024²), so the long loop below runs
// only where a list holds more than K.
// Output: premultiplied (colour, alpha), blended ONE, ONE_MINUS_SRC_ALPHA over the background;
// OVER: the blend over u_background written as it is (the pixels the object-order blend left out
// of depth order hold that blend, which this replaces: oit.OrderMarks).
#include "oit.glsl"

#define K 8
// a loop bound of 8192 or more made llvmpipe (LLVM 15) run every later loop once
#define MAX_LIST 4096
uniform int u_width;
#ifdef FIRST_FETCHED
// the first three surfaces and the list of the later ones as composite.frag's FIRST_FETCHED left
// them: this frame's, where the stencil test lets the shader run (a pixel's first surface
// writes both), an empty one 0
layout(binding = BINDING_OIT_FIRST) uniform usampler2D u_first;
layout(binding = BINDING_OIT_MORE) uniform usampler2D u_more;
#endif
#ifdef OVER
uniform vec3 u_background;
#endif
#if defined(OVER) || defined(FIRST_FETCHED)
// drawn with a stencil test for the marked (or covered) pixels: tested first (else llvmpipe
// tests after the shader)
layout(early_fragment_tests) in;
#endif
layout(location = 0) out vec4 out_color;

// slot j holds (depth, colour); an empty slot has depth 2
#define SLOT(j) float d##j = 2.0; uint c##j = 0u;
// keep the nearer of (d, c) and slot j in the slot, carry the other on. Equal depths (coplanar
// faces of two parts) go by colour: a tie by node (draw order) cost a tenth of the composite
// more, and on a GPU, whose fragments reach the lists in no fixed order, would still be stable
// only through the node numbers; equal colours blend alike in either order.
#define SWAP(j) { bool s = d < d##j || (d == d##j && c < c##j); \
    float td = s ? d##j : d; d##j = s ? d : d##j; d = td; \
    uint tc = s ? c##j : c; c##j = s ? c : c##j; c = tc; }
#define BLEND(j) { vec4 q = d##j < 1.5 ? unpackUnorm4x8(c##j) : vec4(0.0); acc += t * q.a * q.rgb; t *= 1.0 - q.a; }

#define TAKE(g) SWAP(0) if (g >= 1) SWAP(1) if (g >= 2) SWAP(2) if (g >= 3) SWAP(3) \
    if (g >= 4) SWAP(4) if (g >= 5) SWAP(5) if (g >= 6) SWAP(6) if (g >= 7) SWAP(7)

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    SLOT(0) SLOT(1) SLOT(2) SLOT(3) SLOT(4) SLOT(5) SLOT(6) SLOT(7)
    vec3 tail_c = vec3(0.0);
    float tail_w = 0.0, tail_t = 1.0;
    float d;
    uint c;
#ifdef FIRST_FETCHED
    uvec4 first = texelFetch(u_first, p, 0);
    if (first.x == 0u) discard;
    uvec4 more = first.z != 0u ? texelFetch(u_more, p, 0) : uvec4(0u);
    uint next = more.z;
    d = uintBitsToFloat(~first.x); c = first.y; TAKE(0)
    if (first.z != 0u) { d = uintBitsToFloat(~first.z); c = first.w; TAKE(1) }
    if (more.x != 0u) { d = uintBitsToFloat(~more.x); c = more.y; TAKE(2) }
    for (int g = 3; next != NO_NODE && g < K; ++g) {
#else
    uint next = heads[p.y * u_width + p.x];
    if (next == NO_NODE) discard;
    for (int g = 0; next != NO_NODE && g < K; ++g) {
#endif
        uvec4 node = nodes[next - 1u];
        d = uintBitsToFloat(node.x);
        c = node.y;
        next = node.z;
        // slots g.. are empty: node g is carried past the g filled ones and lands in slot g
        // (the loop unrolls, so each copy keeps only its own swaps: 36 for 8 nodes, not 64)
        TAKE(g)
    }
    for (int g = 0; next != NO_NODE && g < MAX_LIST; ++g) {     // more than K: the farthest merged behind
        uvec4 node = nodes[next - 1u];
        d = uintBitsToFloat(node.x);
        c = node.y;
        next = node.z;
        SWAP(0) SWAP(1) SWAP(2) SWAP(3) SWAP(4) SWAP(5) SWAP(6) SWAP(7)
        vec4 q = unpackUnorm4x8(c);
        tail_c += q.a * q.rgb;
        tail_w += q.a;
        tail_t *= 1.0 - q.a;
    }
    vec3 acc = vec3(0.0);
    float t = 1.0;                   // light passing so far, front to back
    BLEND(0) BLEND(1) BLEND(2) BLEND(3) BLEND(4) BLEND(5) BLEND(6) BLEND(7)
    if (tail_w > 0.0) {
        acc += t * (1.0 - tail_t) * tail_c / tail_w;
        t *= tail_t;
    }
#ifdef OVER
    out_color = vec4(acc + t * u_background, 1.0);
#else
    out_color = vec4(acc, 1.0 - t);
#endif
}
