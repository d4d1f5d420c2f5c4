// Shared by composite.frag and blend_tiles.comp: an object's atlas images sampled at a
// viewport pixel. The includer declares the object's values first (composite.geom's flat
// outputs: g_map, g_scale, g_layer, g_rect, g_shade) and defines UPSAMPLE, UPSAMPLE_DYNAMIC
// and WITH_AO as its variant asks.
layout(binding = BINDING_ATLAS_COLOR) uniform sampler2DArray u_color;
layout(binding = BINDING_ATLAS_DEPTH) uniform sampler2DArray u_depth;
layout(binding = BINDING_ATLAS_POST) uniform sampler2DArray u_post;   // (ao, edge) per atlas texel, WITH_AO only
#ifdef UPSAMPLE_DYNAMIC
uniform float u_upsample_below;  // sprites.UPSAMPLE_BELOW
#endif
uniform vec2 u_ortho_depth;     // an orthographic view: (1, near / (far - near)); perspective: (0, 0)

vec3 shade(vec3 rgb, vec2 post) {
#ifdef WITH_AO
    rgb *= mix(1.0, post.r, g_shade.x);
    rgb = mix(rgb, u_edge_color.rgb, post.g * g_shade.y * u_edge_color.a);
#endif
    return rgb;
}

bool outside(ivec2 s) { return any(lessThan(s, g_rect.xy)) || any(greaterThan(s, g_rect.zw)); }

// What a pixel takes from its object's atlas images: colour, window depth, (ao, edge), and
// the texel it is nearest to (normals for the projector).
struct Sample { vec3 rgb; float depth; vec2 post; ivec3 t; };

// Depth-aware upsampling of a region captured below one texel per pixel (context objects
// at the context scale): the 2x2 texels around the pixel's atlas position, bilinear
// weights over the texels that are the object's own (inside B_atlas, depth < 1) and lie on
// the same surface as the nearest of them (view distance within 2%: 1 - window depth is
// about proportional to 1 / distance in perspective; in an orthographic view window depth is
// linear in distance, which is (depth + near / (far - near)) (far - near)), renormalised. The pixel is covered where the own texels
// hold at least half the weight, so the silhouette follows the bilinear coverage: no
// background, no neighbouring region and no surface behind a depth edge ever blends in.
bool upsampled(vec2 px, out Sample o) {
    vec2 a = g_map.xy + g_scale * (px - g_map.zw) - 0.5;
    ivec2 lo = ivec2(floor(a));
    vec2 f = a - vec2(lo);
    // gather components: x (lo.x, lo.y+1), y (lo.x+1, lo.y+1), z (lo.x+1, lo.y), w (lo.x, lo.y)
    vec4 d = textureGather(u_depth, vec3((vec2(lo) + 1.0) / vec2(textureSize(u_depth, 0).xy), float(g_layer)), 0);
    // which of the 2x2 lie inside B_atlas: column lo.x (x, w) or lo.x + 1 (y, z), row lo.y (z, w) or lo.y + 1 (x, y)
    bvec2 col = bvec2(lo.x >= g_rect.x && lo.x <= g_rect.z, lo.x + 1 >= g_rect.x && lo.x + 1 <= g_rect.z);
    bvec2 row = bvec2(lo.y >= g_rect.y && lo.y <= g_rect.w, lo.y + 1 >= g_rect.y && lo.y + 1 <= g_rect.w);
    vec4 inside = vec4(col.x && row.y, col.y && row.y, col.y && row.x, col.x && row.x);
    vec4 w = vec4((1.0 - f.x) * f.y, f.x * f.y, f.x * (1.0 - f.y), (1.0 - f.x) * (1.0 - f.y))
           * inside * vec4(lessThan(d, vec4(1.0)));
    if (w.x + w.y + w.z + w.w < 0.5) return false;
    float m = max(max(w.x, w.y), max(w.z, w.w));
    float dref = w.x == m ? d.x : w.y == m ? d.y : w.z == m ? d.z : d.w;
    float reach = u_ortho_depth.x > 0.5 ? dref + u_ortho_depth.y : 1.0 - dref;
    w *= vec4(lessThanEqual(abs(d - dref), vec4(0.02 * reach)));
    w /= w.x + w.y + w.z + w.w;       // the nearest texel is always in: the sum is > 0
    ivec3 t00 = ivec3(lo, g_layer);
    ivec3 tx = t00 + ivec3(0, 1, 0), ty = t00 + ivec3(1, 1, 0), tz = t00 + ivec3(1, 0, 0);
    o.t = w.x == m ? tx : w.y == m ? ty : w.z == m ? tz : t00;
    o.rgb = w.x * texelFetch(u_color, tx, 0).rgb + w.y * texelFetch(u_color, ty, 0).rgb
          + w.z * texelFetch(u_color, tz, 0).rgb + w.w * texelFetch(u_color, t00, 0).rgb;
    o.depth = dot(w, d);
#ifdef WITH_AO
    o.post = w.x * texelFetch(u_post, tx, 0).rg + w.y * texelFetch(u_post, ty, 0).rg
           + w.z * texelFetch(u_post, tz, 0).rg + w.w * texelFetch(u_post, t00, 0).rg;
    // an edge texel spans 1 / scale pixels: keep its middle only, nearer the 1-pixel lines of
    // a full-scale capture (share of pixels over 8/255 on the demo's ghosted-ao at 0.5: 3.2 -> 2.4%)
    o.post.g = clamp((o.post.g - 0.5) * 2.0, 0.0, 1.0);
#else
    o.post = vec2(1.0, 0.0);
#endif
    return true;
}

// The pixel's sample: upsampled, or the nearest texel at one texel per pixel or more.
bool sampled(vec2 px, out Sample o) {
#ifdef UPSAMPLE
    return upsampled(px, o);
#elif defined(UPSAMPLE_DYNAMIC)
    if (g_scale < u_upsample_below) return upsampled(px, o);
#endif
    o.t = atlas_texel(g_map, g_scale, g_layer, px);
    if (outside(o.t.xy)) return false;
    o.depth = texelFetch(u_depth, o.t, 0).r;
    if (o.depth >= 1.0) return false;
    o.rgb = texelFetch(u_color, o.t, 0).rgb;
#ifdef WITH_AO
    o.post = texelFetch(u_post, o.t, 0).rg;
#else
    o.post = vec2(1.0, 0.0);
#endif
    return true;
}
