#version 430
// defines: AO_PASS
// Atlas post-processing for `ghosted-ao`: per texel, ambient occlusion and edge strength
// from the object's OWN unoccluded depth/normal/id images, so hidden objects get complete
// shading and silhouettes. Border texels (id -1) separate regions: no bleeding.
// AO_PASS: ambient occlusion at half resolution (at the even texels), low-frequency enough;
// the full-resolution pass adds edges and takes AO from the half-resolution texel of the
// same object (1 where none is: a one-texel band at region borders).
#include "records.glsl"

layout(binding = 0) uniform sampler2DArray u_depth;
layout(binding = 1) uniform sampler2DArray u_normal;
layout(binding = 2) uniform isampler2DArray u_ids;

uniform vec4 u_proj;           // (P00, P11, P22, P23) of the perspective projection
uniform vec2 u_viewport;
uniform float u_ao_radius;     // pixels
uniform float u_ao_strength;
uniform int u_edge_width;      // pixels

layout(binding = 3) uniform sampler2DArray u_ao;   // half-resolution AO (full pass only)

layout(location = 0) out vec4 out_post;   // AO_PASS: (ao, 0, 0, 1); else (ao, edge, 0, 1)

// texel -> view-space position: `origin` and `step` map atlas texels to viewport NDC
vec3 view_position(ivec3 t, vec2 origin, vec2 step) {
    vec2 ndc = origin + (vec2(t.xy) + 0.5) * step;
    float z = -u_proj.w / (texelFetch(u_depth, t, 0).r * 2.0 - 1.0 + u_proj.z);
    return vec3(-z * ndc.x / u_proj.x, -z * ndc.y / u_proj.y, z);
}

// Globals of the texel being shaded (set once in main, read by the unrolled helpers).
int g_id;
ivec3 g_t;
ivec2 g_size;
vec2 g_origin, g_step;
vec3 g_p, g_n;

ivec3 neighbour(ivec2 o) { return ivec3(clamp(g_t.xy + o, ivec2(0), g_size - 1), g_t.z); }

// one AO sample at offset `o` (texels); returns (occlusion, used)
vec2 ao_sample(vec2 o) {
    ivec3 s = neighbour(ivec2(round(o)));
    if (texelFetch(u_ids, s, 0).r != g_id) return vec2(0.0);
    vec3 v = view_position(s, g_origin, g_step) - g_p;
    float dist = length(v) + 1e-12;
    return vec2(max(0.0, dot(v, g_n) - 0.002 * abs(g_p.z)) / dist, 1.0);
}

// edge strength towards offset `o`: silhouette, depth discontinuity or crease
float edge_towards(ivec2 o) {
    ivec3 s = neighbour(o);
    if (texelFetch(u_ids, s, 0).r != g_id) return 1.0;
    vec3 q = view_position(s, g_origin, g_step);
    float jump = abs(q.z - g_p.z) / max(abs(g_p.z), 1e-12);
    float bend = 1.0 - dot(g_n, normalize(texelFetch(u_normal, s, 0).xyz));
    return max(smoothstep(0.01, 0.03, jump), smoothstep(0.2, 0.5, bend));
}

void setup(ivec3 t) {
    g_t = t;
    Record r = records[g_id];
    float scale = intBitsToFloat(r.info.w);
    g_step = 2.0 / (scale * u_viewport);
    g_origin = (r.viewport.xy - (r.atlas.xy + float(r.info.z)) / scale) / u_viewport * 2.0 - 1.0;
    g_p = view_position(g_t, g_origin, g_step);
    g_n = normalize(texelFetch(u_normal, g_t, 0).xyz);
}

float ambient_occlusion() {
    // 8 samples on a golden-angle spiral (unrolled: no dynamic indexing)
    float R = u_ao_radius * intBitsToFloat(records[g_id].info.w);
    vec2 acc = ao_sample(R * vec2(0.0548, 0.0300)) + ao_sample(R * vec2(-0.1821, 0.0449))
             + ao_sample(R * vec2(0.1732, -0.2601)) + ao_sample(R * vec2(0.0672, 0.4323))
             + ao_sample(R * vec2(-0.4391, -0.3515)) + ao_sample(R * vec2(0.6860, -0.0457))
             + ao_sample(R * vec2(-0.5613, 0.5875)) + ao_sample(R * vec2(0.0196, -0.9373));
    return acc.y > 0.0 ? clamp(1.0 - u_ao_strength * acc.x / acc.y, 0.0, 1.0) : 1.0;
}

// AO of the half-resolution texel `h` when it was computed for this object, else -1
float ao_from(ivec2 h) {
    ivec3 rep = ivec3(min(h * 2, g_size - 1), g_t.z);
    return texelFetch(u_ids, rep, 0).r == g_id ? texelFetch(u_ao, ivec3(h, g_t.z), 0).r : -1.0;
}

void main() {
    g_size = textureSize(u_ids, 0).xy;
#ifdef AO_PASS
    ivec3 t = ivec3(min(ivec2(gl_FragCoord.xy) * 2, g_size - 1), gl_Layer);
    g_id = texelFetch(u_ids, t, 0).r;
    if (g_id < 0) { out_post = vec4(1.0, 0.0, 0.0, 1.0); return; }
    setup(t);
    out_post = vec4(ambient_occlusion(), 0.0, 0.0, 1.0);
#else
    ivec3 t = ivec3(gl_FragCoord.xy, gl_Layer);
    g_id = texelFetch(u_ids, t, 0).r;
    if (g_id < 0) { out_post = vec4(1.0, 0.0, 0.0, 1.0); return; }
    setup(t);
    float ao = ao_from(t.xy / 2);
    if (ao < 0.0) ao = ao_from((t.xy + 1) / 2);     // the next even texel, for odd coordinates
    int w = u_edge_width;
    float edge = max(max(edge_towards(ivec2(w, 0)), edge_towards(ivec2(-w, 0))),
                     max(edge_towards(ivec2(0, w)), edge_towards(ivec2(0, -w))));
    out_post = vec4(ao < 0.0 ? 1.0 : ao, edge, 0.0, 1.0);
#endif
}
