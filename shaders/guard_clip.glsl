// The capture's triangle cut to its region's guard planes (capture.geom with REGION_GUARD):
// Sutherland-Hodgman over the four planes, in clip space, the corners' barycentric weights
// carried for the attributes. An edge is cut from its lexicographically smaller end, so two
// triangles sharing it cut it at the same point (no cracks). At most 3 + 4 corners.
const int GUARD_CORNERS = 7;
vec4 g_pos[GUARD_CORNERS];
vec3 g_bary[GUARD_CORNERS];
int g_count;

// One corner of the cut triangle: its clip position and barycentric weights.
void emit_cut(Record r, vec4 clip_pos, vec3 b) {
    float d[4];
    region_clip_distances(clip_pos, r.clip, d);
    for (int k = 0; k < 4; ++k) gl_ClipDistance[k] = d[k];
    gl_Layer = r.info.x;
    gl_Position = displace(clip_pos, r.transform);
    gs_out.normal = b.x * gs_in[0].normal + b.y * gs_in[1].normal + b.z * gs_in[2].normal;
    gs_out.object = gs_in[0].object;
    gs_out.color = gs_in[0].color;
#ifdef SECTIONS
    gs_out.world = b.x * gs_in[0].world + b.y * gs_in[1].world + b.z * gs_in[2].world;
#endif
#ifdef TEXTURED
    g_uv = b.x * v_uv[0] + b.y * v_uv[1] + b.z * v_uv[2];
    g_material_rect = v_material_rect[0];
    g_material_layer = v_material_layer[0];
#endif
    EmitVertex();
}

bool comes_before(vec4 a, vec4 b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    if (a.z != b.z) return a.z < b.z;
    return a.w < b.w;
}

float guard_distance(vec4 p, vec4 r, int k) {
    float d[4];
    region_clip_distances(p, r, d);
    return d[k];
}

void cut_by(vec4 r, int k) {
    vec4 pos[GUARD_CORNERS];
    vec3 bary[GUARD_CORNERS];
    float dist[GUARD_CORNERS];  // each corner's distance to plane k, once
    for (int i = 0; i < g_count; ++i) dist[i] = guard_distance(g_pos[i], r, k);
    int m = 0;
    for (int i = 0; i < g_count; ++i) {
        int j = i + 1 == g_count ? 0 : i + 1;
        float di = dist[i], dj = dist[j];
        if (di >= 0.0) {
            pos[m] = g_pos[i];
            bary[m] = g_bary[i];
            ++m;
        }
        if ((di >= 0.0) != (dj >= 0.0)) {
            bool s = comes_before(g_pos[i], g_pos[j]);
            int a = s ? i : j, b = s ? j : i;
            float t = (s ? di : dj) / ((s ? di : dj) - (s ? dj : di));
            pos[m] = g_pos[a] + t * (g_pos[b] - g_pos[a]);
            bary[m] = g_bary[a] + t * (g_bary[b] - g_bary[a]);
            ++m;
        }
    }
    for (int i = 0; i < m; ++i) {
        g_pos[i] = pos[i];
        g_bary[i] = bary[i];
    }
    g_count = m;
}

// false: the triangle lies inside every guard plane (drawn as it is); true: cut here and
// emitted as a strip (nothing when no part of it is inside).
bool guard_cut(Record r) {
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
        float d[4];
        region_clip_distances(gl_in[i].gl_Position, r.clip, d);
        inside = inside && min(min(d[0], d[1]), min(d[2], d[3])) >= 0.0;
    }
    if (inside) return false;
    g_count = 3;
    for (int i = 0; i < 3; ++i) {
        g_pos[i] = gl_in[i].gl_Position;
        g_bary[i] = vec3(i == 0, i == 1, i == 2);
    }
    for (int k = 0; k < 4 && g_count >= 3; ++k) cut_by(r.clip, k);
    if (g_count < 3) return true;
    // the convex polygon as a strip: 0, 1, n-1, 2, n-2, ...
    int lo = 1, hi = g_count - 1;
    emit_cut(r, g_pos[0], g_bary[0]);
    for (int i = 1; i < g_count; ++i) {
        int c = (i % 2 == 1) ? lo++ : hi--;
        emit_cut(r, g_pos[c], g_bary[c]);
    }
    EndPrimitive();
    return true;
}
