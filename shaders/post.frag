#version 430
// defines:
// Atlas post-processing for `ghosted-ao`: per texel, ambient occlusion and edge strength
// from the object's OWN unoccluded depth/normal/id images, so hidden objects get complete
// shading and silhouettes. Border texels (id -1) separate regions: no bleeding.
#include "records.glsl"

layout(binding = 0) uniform sampler2DArray u_depth;
layout(binding = 1) uniform sampler2DArray u_normal;
layout(binding = 2) uniform isampler2DArray u_ids;

uniform mat4 u_inv_proj;
uniform vec2 u_viewport;
uniform float u_ao_radius;     // pixels
uniform float u_ao_strength;
uniform int u_edge_width;      // pixels

layout(location = 0) out vec4 out_post;   // (ao, edge, 0, 1)

vec3 view_position(ivec3 t, Record r) {
    float scale = intBitsToFloat(r.info.w);
    vec2 px = r.viewport.xy + (vec2(t.xy) + 0.5 - r.atlas.xy - float(r.info.z)) / scale;
    float d = texelFetch(u_depth, t, 0).r;
    vec4 v = u_inv_proj * vec4(px / u_viewport * 2.0 - 1.0, d * 2.0 - 1.0, 1.0);
    return v.xyz / v.w;
}

void main() {
    ivec3 t = ivec3(gl_FragCoord.xy, gl_Layer);
    int id = texelFetch(u_ids, t, 0).r;
    if (id < 0) { out_post = vec4(1.0, 0.0, 0.0, 1.0); return; }
    Record r = records[id];
    float scale = intBitsToFloat(r.info.w);
    vec3 p = view_position(t, r);
    vec3 n = normalize(texelFetch(u_normal, t, 0).xyz);
    ivec2 size = textureSize(u_ids, 0).xy;

    // ambient occlusion: 16 samples on a spiral, own object only
    float occlusion = 0.0;
    int used = 0;
    for (int i = 0; i < 16; ++i) {
        float a = float(i) * 2.39996 + 0.5;
        float rad = u_ao_radius * scale * (float(i) + 0.5) / 16.0;
        ivec2 o = ivec2(round(vec2(cos(a), sin(a)) * rad));
        ivec3 s = ivec3(clamp(t.xy + o, ivec2(0), size - 1), t.z);
        if (texelFetch(u_ids, s, 0).r != id) continue;
        vec3 v = view_position(s, r) - p;
        float dist2 = dot(v, v) + 1e-12;
        occlusion += max(0.0, dot(v, n) - 0.002 * abs(p.z)) / dist2 * sqrt(dist2);
        used += 1;
    }
    float ao = used > 0 ? clamp(1.0 - u_ao_strength * occlusion / float(used), 0.0, 1.0) : 1.0;

    // edges: object silhouette, depth discontinuity or crease within the edge width
    float edge = 0.0;
    ivec2 dirs[4] = ivec2[](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    for (int k = 0; k < 4; ++k) {
        ivec3 s = ivec3(clamp(t.xy + dirs[k] * u_edge_width, ivec2(0), size - 1), t.z);
        if (texelFetch(u_ids, s, 0).r != id) { edge = 1.0; break; }
        vec3 q = view_position(s, r);
        float jump = abs(q.z - p.z) / max(abs(p.z), 1e-12);
        float bend = 1.0 - dot(n, normalize(texelFetch(u_normal, s, 0).xyz));
        edge = max(edge, max(smoothstep(0.01, 0.03, jump), smoothstep(0.2, 0.5, bend)));
    }
    out_post = vec4(ao, edge, 0.0, 1.0);
}
