#version 450
// defines: EDGE_QUAD EDGES_ONLY
// Atlas post-processing for `ghosted-ao`: per texel, ambient occlusion and edge strength
// from the object's OWN unoccluded depth/normal images, so hidden objects get complete
// shading and silhouettes. Drawn as one quad per object over its atlas rectangle
// (post.geom), where a texel is either the object's or empty; the atlas is depth-keyed
// (targets.py): a texel is empty exactly where its depth is 1, whatever its normal holds.
// A neighbour outside the rectangle counts as empty, so no id is fetched at all, except one
// beyond the viewport (an object cut by the view's edge): nothing is known of it, and the cut is
// no silhouette, so it makes no edge (as AO, which takes no sample from empty texels). The quads
// lie at depth 1 and are tested '>' against the atlas depth, so only covered texels (and
// the helpers of their 2x2 quads) are shaded.
// AO: 8 samples per 2x2 quad of texels, 2 taken by each texel around itself and summed
// over the quad through derivatives, so every texel of the quad gets the same 8-sample
// AO for a quarter of the fetches (the AO is low-frequency enough).
// EDGE_QUAD (edge width 1): the neighbour in the same 2x2 quad comes from the fine
// derivatives of the texel's own fetches, and one depth gather covers the texel and its
// two other neighbours, so two normals and one gather are fetched.
// EDGES_ONLY: no AO (written as 1), for objects shaded with edges alone (--ao-objects focus).

layout(binding = BINDING_ATLAS_DEPTH) uniform sampler2DArray u_depth;    // window depth, 1 where empty
layout(binding = BINDING_ATLAS_NORMAL) uniform sampler2DArray u_normal;   // view normal * 0.5 + 0.5 (RGBA8); stale where empty

uniform vec4 u_proj;           // (P00, P11, P22, P23) of the perspective or orthographic projection
uniform vec2 u_proj_w;         // (P32, P33): (-1, 0) perspective, (0, 1) orthographic
uniform float u_ao_radius;     // pixels
uniform float u_ao_strength;
uniform int u_edge_width;      // pixels

flat in ivec4 g_rect;
flat in vec4 g_map;
flat in float g_scale;

layout(location = 0) out vec4 out_post;   // (ao, edge, 0, 1)

// Globals of the texel being shaded (set once in main, read by the unrolled helpers).
ivec3 g_t;
vec3 g_p, g_n;
float g_dist;

// view distance (along -z) of window depth `d`: ndc z = (P22 z + P23) / (P32 z + P33)
float view_distance(float d) {
    float ndc = d * 2.0 - 1.0;
    return (u_proj.w - ndc * u_proj_w.y) / (u_proj.z - ndc * u_proj_w.x);
}

vec3 normal_at(ivec3 t) { return texelFetch(u_normal, t, 0).xyz * 2.0 - 1.0; }

bool outside(ivec2 t) { return any(lessThan(t, g_rect.xy)) || any(greaterThan(t, g_rect.zw)); }

// whether texel t's centre lies beyond the viewport (its region's border past a cut edge)
bool beyond(ivec2 t) { return any(greaterThan(abs(g_map.xy + (vec2(t) + 0.5) * g_map.zw), vec2(1.0))); }

// texel with window depth `d` -> view-space position
vec3 view_position(ivec2 t, float d) {
    vec2 ndc = g_map.xy + (vec2(t) + 0.5) * g_map.zw;
    float z = -view_distance(d);
    float w = u_proj_w.x * z + u_proj_w.y;     // clip w: the distance, or 1 in an orthographic view
    return vec3(w * ndc.x / u_proj.x, w * ndc.y / u_proj.y, z);
}

// one AO sample at offset `o` (texels); returns (occlusion, used)
vec2 ao_sample(vec2 o) {
    ivec2 s = g_t.xy + ivec2(round(o));
    if (outside(s)) return vec2(0.0);
    float d = texelFetch(u_depth, ivec3(s, g_t.z), 0).r;
    if (d >= 1.0) return vec2(0.0);
    vec3 v = view_position(s, d) - g_p;
    float dist = length(v) + 1e-12;
    return vec2(max(0.0, dot(v, g_n) - 0.002 * abs(g_p.z)) / dist, 1.0);
}

// The 8 spiral samples of a quad: this texel's 2 around itself (occlusion, used), none
// unless it is covered; texel (x & 1, y & 1) = (i, j) takes samples 2k and 2k + 1, k = i + 2j.
vec2 ao_share(bool covered) {
    ivec2 odd = g_t.xy & 1;
    int k = odd.x + 2 * odd.y;
    float R = u_ao_radius * g_scale;
    vec2 o0 = k == 0 ? vec2(0.0548, 0.0300) : k == 1 ? vec2(0.1732, -0.2601)
            : k == 2 ? vec2(-0.4391, -0.3515) : vec2(-0.5613, 0.5875);
    vec2 o1 = k == 0 ? vec2(-0.1821, 0.0449) : k == 1 ? vec2(0.0672, 0.4323)
            : k == 2 ? vec2(0.6860, -0.0457) : vec2(0.0196, -0.9373);
    vec2 acc = ao_sample(R * o0) + ao_sample(R * o1);
    return covered ? acc : vec2(0.0);    // a select: an empty helper's NaN never reaches the sum
}

// AO from the shares of the whole 2x2 quad: with a = this texel's share, dx, dy its fine
// derivatives and dxy the derivative of dy along x, the quad's sum is
// 4a + 2 sx dx + 2 sy dy + sx sy dxy, with s = +1 on even and -1 on odd coordinates.
float quad_ambient_occlusion(bool covered) {
    vec2 share = ao_share(covered);
    vec2 dx = dFdxFine(share), dy = dFdyFine(share), dxy = dFdxFine(dy);
    vec2 s = vec2(1 - 2 * (g_t.xy & 1));
    vec2 acc = 4.0 * share + 2.0 * s.x * dx + 2.0 * s.y * dy + s.x * s.y * dxy;
    return acc.y > 0.5 ? clamp(1.0 - u_ao_strength * acc.x / acc.y, 0.0, 1.0) : 1.0;
}

// edge strength against a covered neighbour's (normal, view distance) `q`: depth
// discontinuity or crease (an empty neighbour makes a silhouette: 1)
float edge_with(vec4 q) {
    float jump = abs(q.w - g_dist) / g_dist;
    float bend = 1.0 - dot(g_n, normalize(q.xyz));
    return max(smoothstep(0.01, 0.03, jump), smoothstep(0.2, 0.5, bend));
}

// edge strength towards the texel at offset `o` whose depth is `d` (none beyond the view)
float edge_at(ivec2 o, float d) {
    ivec3 s = ivec3(g_t.xy + o, g_t.z);
    if (beyond(s.xy)) return 0.0;
    return outside(s.xy) || d >= 1.0 ? 1.0 : edge_with(vec4(normal_at(s), view_distance(d)));
}

float edge_towards(ivec2 o) {
    ivec3 s = ivec3(g_t.xy + o, g_t.z);
    return edge_at(o, outside(s.xy) ? 1.0 : texelFetch(u_depth, s, 0).r);   // (fetched inside alone)
}

void main() {
    // the depth test passed: this texel is covered (the quads lie at depth 1), unless it is
    // a helper of a covered one in its quad (maybe outside the rectangle, or the texture)
    g_t = ivec3(gl_FragCoord.xy, gl_Layer);
    ivec3 own = ivec3(min(g_t.xy, textureSize(u_normal, 0).xy - 1), g_t.z);
#ifdef EDGE_QUAD
    // every fragment of a 2x2 quad (helpers too) fetches its own (normal, view distance) and
    // emptiness before any branch, so that the fine derivatives are defined; an empty
    // partner's normal is stale, so its emptiness (0 or 1, exact in a difference) decides
    // one gather reads the depths of this texel and of the two neighbours on the far side
    // from its quad partner: the 2x2 footprint with corner `lo`, components
    // x (lo.x, lo.y+1), y (lo.x+1, lo.y+1), z (lo.x+1, lo.y), w (lo.x, lo.y)
    ivec2 odd = g_t.xy & 1, away = 2 * odd - 1;
    ivec2 lo = min(g_t.xy, g_t.xy + away);
    vec4 g = textureGather(u_depth, vec3((vec2(lo) + 1.0) / vec2(textureSize(u_depth, 0).xy), float(g_t.z)), 0);
    vec2 row0 = odd.y == 1 ? g.wz : g.xy, row1 = odd.y == 1 ? g.xy : g.wz;   // own row, the other row
    float depth = odd.x == 1 ? row0.x : row0.y;
    float depth_x = odd.x == 1 ? row0.y : row0.x;       // at (x + away.x, y)
    float depth_y = odd.x == 1 ? row1.x : row1.y;       // at (x, y + away.y)
    vec4 nd = vec4(normal_at(own), view_distance(depth));
    float empty = depth >= 1.0 ? 1.0 : 0.0;
    vec4 ddx = dFdxFine(nd), ddy = dFdyFine(nd);
    vec2 partner_empty = vec2(dFdxFine(empty), dFdyFine(empty));
#else
    float depth = texelFetch(u_depth, own, 0).r;
    vec4 nd = vec4(normal_at(own), view_distance(depth));
#endif
    g_n = normalize(nd.xyz);
    g_dist = nd.w;
    g_p = view_position(g_t.xy, depth);
#ifdef EDGES_ONLY
    float ao = 1.0;
#else
    float ao = quad_ambient_occlusion(!outside(g_t.xy) && depth < 1.0);
#endif
#ifdef EDGE_QUAD
    // the quad partner (x ^ 1, y ^ 1) from the derivatives, the other side fetched
    ivec2 partner = g_t.xy + 1 - 2 * odd;
    float ex = beyond(ivec2(partner.x, g_t.y)) ? 0.0
             : partner.x < g_rect.x || partner.x > g_rect.z || partner_empty.x != 0.0 ? 1.0
             : edge_with(odd.x == 0 ? nd + ddx : nd - ddx);
    float ey = beyond(ivec2(g_t.x, partner.y)) ? 0.0
             : partner.y < g_rect.y || partner.y > g_rect.w || partner_empty.y != 0.0 ? 1.0
             : edge_with(odd.y == 0 ? nd + ddy : nd - ddy);
    float edge = max(max(ex, ey), max(edge_at(ivec2(away.x, 0), depth_x), edge_at(ivec2(0, away.y), depth_y)));
#else
    int w = u_edge_width;
    float edge = max(max(edge_towards(ivec2(w, 0)), edge_towards(ivec2(-w, 0))),
                     max(edge_towards(ivec2(0, w)), edge_towards(ivec2(0, -w))));
#endif
    out_post = vec4(ao, edge, 0.0, 1.0);
}
