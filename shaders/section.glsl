// Cutaways and exploded views, for scene.vert / scene.frag (capture, STD, RTT).
// PLACED: each vertex moved by its object's offset (explode). SECTIONS: fragments beyond a
// section plane discarded on cut objects. Caps (closed parts, caps on; rtta/passes/sections.py):
// the cap lies where the view ray enters the kept region, on the plane it crosses there, when
// that point is inside the part: CAP_COUNT counts the part's surfaces beyond it into the
// stencil (back +1, front -1: its winding number), CAP_DRAW draws the cap, flat-lit with the
// plane's normal, from the part's back faces where the count is not 0.
#if defined(PLACED) || defined(SECTIONS)
// xyz: the object's world offset (scene origin at 0); w: flags, 1 cut, 2 capped
layout(std430, binding = BINDING_PLACEMENT) readonly buffer PlacementBuffer { vec4 placement[]; };
#endif

#if defined(SECTIONS) && defined(SECTION_FRAGMENT)
uniform vec4 u_sections[6];     // (n, d), scene origin at 0: n.p > d is removed
uniform int u_section_count;
uniform int u_caps;             // 1 solid, 2 hatched
uniform float u_hatch_spacing;  // world units between hatch lines
uniform mat4 u_view;            // the pass's, as scene.vert's
uniform mat4 u_proj;
uniform mat4 u_section_inverse; // (P V)^-1: viewport NDC + depth -> world (origin at 0)
uniform vec3 u_section_near[6]; // n.q - d of the near-plane point q under viewport NDC (x, y): affine

// Whether p lies beyond the view ray's entry into the kept region (false without an entry):
// every plane the ray enters (its near-plane point q removed) keeps p. Cheaper than
// section_entry: what the count pass asks of every surface.
bool section_beyond(vec3 p) {
    vec4 c = u_proj * (u_view * vec4(p, 1.0));
    vec3 ndc = vec3(c.xy / c.w, 1.0);
    bool entered = false;
    for (int i = 0; i < u_section_count; ++i) {
        if (dot(u_section_near[i], ndc) > 0.0) {
            entered = true;
            if (dot(u_sections[i].xyz, p) > u_sections[i].w) return false;
        }
    }
    return entered;
}

bool section_removed(vec3 p) {
    for (int i = 0; i < u_section_count; ++i)
        if (dot(u_sections[i].xyz, p) > u_sections[i].w) return true;
    return false;
}

// Where the view ray through p (from the near plane on: perspective or orthographic alike)
// enters the kept region: false when it starts inside it (no plane crossed before p).
// `enter`: where along q -> p (p at 1) that is; a fragment lies beyond the entry when enter < 1.
bool section_entry(vec3 p, out vec3 hit, out int plane, out float enter) {
    vec4 c = u_proj * (u_view * vec4(p, 1.0));
    vec4 q4 = u_section_inverse * vec4(c.xy / c.w, -1.0, 1.0);
    vec3 q = q4.xyz / q4.w;
    vec3 d = p - q;
    enter = 0.0;
    plane = -1;
    for (int i = 0; i < u_section_count; ++i) {
        float above = dot(u_sections[i].xyz, q) - u_sections[i].w, along = dot(u_sections[i].xyz, d);
        if (above > 0.0 && along < 0.0 && -above / along > enter) {
            enter = -above / along;
            plane = i;
        }
    }
    hit = q + enter * d;
    return plane >= 0;
}

float section_depth(vec3 hit) {
    vec4 c = u_proj * (u_view * vec4(hit, 1.0));
    return clamp(0.5 * c.z / c.w + 0.5, 0.0, 1.0);
}

// The cap's colour: the part's, darker; hatched across the plane with u_caps == 2.
vec3 cap_color(vec3 base, vec3 hit, vec3 n) {
    vec3 rgb = base * 0.6;
    if (u_caps == 2) {
        vec3 t = normalize(abs(n.x) < 0.9 ? cross(n, vec3(1.0, 0.0, 0.0)) : cross(n, vec3(0.0, 1.0, 0.0)));
        vec3 b = cross(n, t);
        float s = (dot(hit, t) + dot(hit, b)) / u_hatch_spacing;
        if (fract(s) < 0.35) rgb = base * 0.25;
    }
    return rgb;
}
#endif
