#version 450
// defines: WITH_AO DEPTH_TESTED SPAN
// Object-order blending in a compute pass (rtta.passes.blend_tiles): the ghosted context, or
// `transparent` in object order, drawn as composite.frag's MODE_BLEND sprites would draw them
// (UPSAMPLE_DYNAMIC: each object upsampled where its own scale asks), without the raster
// pipeline: one workgroup of 16x16 invocations per tile of the composite, each invocation
// blending SPAN x SPAN pixels (a tile is 16 SPAN pixels a side).
// The list (composite.glsl's `order`, back to front, its length in the command buffer's DRAWN
// word, order_gpu.GpuOrder) is read in batches of 256; each batch is compacted, in order, to the
// objects whose B_viewport meets the tile (a scan in shared memory), and each pixel blends
// those that cover it (B_viewport, then the atlas texels as `sampled` reads them), over the
// colour the target holds (the focus sprites), premultiplied: dst = src + (1 - src.a) dst in
// the 8-bit steps of an RGBA8 target's blend unit. DEPTH_TESTED (the ghosted
// context): a sample at or behind the target's depth (the focus sprites', 0 under their
// outlines) is hidden, as the sprite's depth test ("<", no depth written) hides it.
// Why: a GPU with few raster units (NVIDIA's H100 has 8 ROPs) blends some 2 billion sprite
// fragments a second; its compute units do not queue behind them.
#define UPSAMPLE_DYNAMIC 1
#include "composite.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
#define BATCH 256
#ifndef SPAN
#define SPAN 1
#endif
#define PIXELS (SPAN * SPAN)
#define DRAWN 15   // order_gpu.DRAWN

layout(std430, binding = BINDING_COMPOSITE_COMMAND) readonly buffer CommandBuffer { uint command[30]; };
layout(binding = BINDING_TARGET_DEPTH) uniform sampler2D u_target_depth;   // DEPTH_TESTED
layout(binding = BINDING_TARGET_COLOR, rgba8) uniform image2D u_target;
uniform float u_desaturate;     // context desaturation in [0, 1]
uniform vec4 u_edge_color;      // WITH_AO

// the object being blended: what composite.geom hands composite.frag
int g_object;
vec4 g_map;
float g_scale;
int g_layer;
ivec4 g_rect;
float g_opacity;
vec2 g_shade;
#include "sprite_sample.glsl"

shared uint s_scan[BATCH];
shared int s_ids[BATCH];
shared ivec4 s_viewport[BATCH];

// the ids of this batch whose B_viewport meets the tile [lo, hi), compacted in list order
int batch(uint base, uint total, ivec2 lo, ivec2 hi) {
    uint t = gl_LocalInvocationIndex;
    bool hit = false;
    int id = 0;
    ivec4 vp = ivec4(0);
    if (base + t < total) {
        id = order[base + t];
        Record r = records[id];
        vp = ivec4(r.viewport);
        hit = r.info.y != 0 && vp.x < hi.x && vp.z > lo.x && vp.y < hi.y && vp.w > lo.y;
    }
    s_scan[t] = hit ? 1u : 0u;
    barrier();
    for (uint step = 1u; step < BATCH; step <<= 1) {   // inclusive scan (Hillis-Steele)
        uint add = t >= step ? s_scan[t - step] : 0u;
        barrier();
        s_scan[t] += add;
        barrier();
    }
    if (hit) {
        s_ids[s_scan[t] - 1u] = id;
        s_viewport[s_scan[t] - 1u] = vp;
    }
    int count = int(s_scan[BATCH - 1]);
    barrier();
    return count;
}

// the object `id` as composite.geom hands it to composite.frag
void object(int id) {
    Record r = records[id];
    g_object = id;
    g_map = vec4(r.atlas.xy + float(r.info.z), r.viewport.xy);
    g_scale = intBitsToFloat(r.info.w);
    g_layer = r.info.x;
    g_rect = ivec4(r.atlas.xy, r.atlas.xy + r.atlas.zw - 1.0);
    g_opacity = styles[id].params.x;
    g_shade = styles[id].params.zw;
}

// the object over `dst` at pixel centre `px` where it covers the pixel and is not hidden
vec4 blended(ivec4 vp, vec2 px, float behind, vec4 dst) {
    if (px.x < float(vp.x) || px.x > float(vp.z) || px.y < float(vp.y) || px.y > float(vp.w)) return dst;
    Sample o;
    if (!sampled(px, o)) return dst;
#ifdef DEPTH_TESTED
    if (!(o.depth < behind)) return dst;
#endif
    vec3 rgb = shade(o.rgb, o.post);
    rgb = mix(rgb, vec3(dot(rgb, vec3(0.299, 0.587, 0.114))), u_desaturate);
    float a = g_opacity;
    // in 8-bit steps, as a blend unit of an RGBA8 target works: the source rounded to 8 bits,
    // the destination's share rounded, the sum saturated
    vec4 src = round(clamp(vec4(rgb * a, a), 0.0, 1.0) * 255.0);
    return min(src + round(dst * (255.0 - src.a)), 255.0) / 255.0;
}

void main() {
    ivec2 size = ivec2(u_viewport);
    ivec2 lo = ivec2(gl_WorkGroupID.xy) * (16 * SPAN), hi = min(lo + 16 * SPAN, size);
    ivec2 first = lo + ivec2(gl_LocalInvocationID.xy) * SPAN;
    vec4 dst[PIXELS];
    float behind[PIXELS];
    for (int j = 0; j < PIXELS; ++j) {
        ivec2 p = first + ivec2(j % SPAN, j / SPAN);
        bool inside = all(lessThan(p, size));
        dst[j] = inside ? imageLoad(u_target, p) : vec4(0.0);
        behind[j] = 1.0;
#ifdef DEPTH_TESTED
        if (inside) behind[j] = texelFetch(u_target_depth, p, 0).r;
#endif
    }
    bool some = all(lessThan(first, size));
    uint total = command[DRAWN];
    for (uint base = 0u; base < total; base += BATCH) {
        int count = batch(base, total, lo, hi);
        for (int k = 0; k < count && some; ++k) {
            object(s_ids[k]);
            ivec4 vp = s_viewport[k];
            for (int j = 0; j < PIXELS; ++j)
                dst[j] = blended(vp, vec2(first + ivec2(j % SPAN, j / SPAN)) + 0.5, behind[j], dst[j]);
        }
        barrier();
    }
    for (int j = 0; j < PIXELS; ++j) {
        ivec2 p = first + ivec2(j % SPAN, j / SPAN);
        if (all(lessThan(p, size))) imageStore(u_target, p, dst[j]);
    }
}
