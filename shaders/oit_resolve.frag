#version 430
// defines:
// `--order pixel`: each pixel's list of object surfaces (oit.glsl), sorted by depth and
// blended, so nested and interpenetrating objects blend in the order their surfaces have
// at that pixel. Up to K surfaces are kept and sorted exactly; beyond K (more objects
// overlapping one pixel than that) the farthest ones are merged into one layer behind the
// kept ones, with their opacity-weighted mean colour and their combined opacity 1 - prod(1 - a)
// (weighted blended transparency, order-independent), so nothing is dropped (up to
// MAX_LIST surfaces at one pixel; a 4097th object over one pixel is left out). Output:
// premultiplied (colour, alpha), blended ONE, ONE_MINUS_SRC_ALPHA over the background.
#include "oit.glsl"

#define K 8
#define MAX_LIST 4096
uniform int u_width;
layout(location = 0) out vec4 out_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint i = heads[p.y * u_width + p.x];
    if (i == NO_NODE) discard;
    float dk[K];
    vec4 ck[K];
    int n = 0;
    vec3 tail_c = vec3(0.0);       // sum of a * rgb of the surfaces that did not fit
    float tail_w = 0.0, tail_t = 1.0;
    // at most MAX_LIST surfaces per pixel are walked (a bound of 8192 or more made llvmpipe's
    // LLVM 15 run every later loop of the shader once: measured, see BENCHMARKS.md)
    for (int guard = 0; i != NO_NODE && guard < MAX_LIST; ++guard) {
        uvec4 node = nodes[i];
        float d = uintBitsToFloat(node.x);
        vec4 c = unpackUnorm4x8(node.y);
        i = node.z;
        if (n < K) {
            dk[n] = d;
            ck[n] = c;
            ++n;
        } else {
            int far = 0;
            for (int k = 1; k < K; ++k)
                if (dk[k] > dk[far]) far = k;
            if (d < dk[far]) {       // keep the nearer one, the farthest kept goes behind
                vec4 e = ck[far];
                dk[far] = d;
                ck[far] = c;
                c = e;
            }
            tail_c += c.a * c.rgb;
            tail_w += c.a;
            tail_t *= 1.0 - c.a;
        }
    }
    // selection sort over fixed bounds, nearest first
    for (int a = 0; a < K - 1; ++a)
        for (int b = a + 1; b < K; ++b)
            if (b < n && dk[b] < dk[a]) {
                float d = dk[a];
                dk[a] = dk[b];
                dk[b] = d;
                vec4 c = ck[a];
                ck[a] = ck[b];
                ck[b] = c;
            }
    vec3 acc = vec3(0.0);
    float t = 1.0;                   // transmittance so far, front to back
    for (int k = 0; k < K; ++k) {
        float a = k < n ? ck[k].a : 0.0;
        acc += t * a * ck[k].rgb;
        t *= 1.0 - a;
    }
    if (tail_w > 0.0) {
        acc += t * (1.0 - tail_t) * tail_c / tail_w;
        t *= tail_t;
    }
    out_color = vec4(acc, 1.0 - t);
}
