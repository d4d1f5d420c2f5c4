// Projective texturing (seed 004, second half): (s, t, r, q) = bias * P_projector * V_projector
// * world, divided by q per fragment; nothing behind the projector (q <= 0) or outside its
// frustum; optionally shadowed by a depth map rendered from the projector (render-to-texture).
uniform mat4 u_projector;            // bias * P * V, for world positions relative to the scene origin
uniform float u_projector_strength;  // 1: the image replaces the surface's albedo where it is opaque
uniform int u_projector_shadows;
uniform vec2 u_projector_range;      // the projector's (near, far): window depth -> distance
uniform float u_projector_bias;      // relative shadow bias: occluded when nearer by more than this fraction
layout(binding = BINDING_PROJECTOR_IMAGE) uniform sampler2D u_projector_image;
layout(binding = BINDING_PROJECTOR_DEPTH) uniform sampler2D u_projector_depth;

float surface_light(vec3 view_normal) {
    return 0.25 + 0.75 * abs(view_normal.z);   // the headlight of scene.frag
}

// Eye-space distance along the projector's axis for a window depth in [0, 1].
float projector_distance(float window_depth) {
    float n = u_projector_range.x, f = u_projector_range.y;
    return 2.0 * n * f / (f + n - (2.0 * window_depth - 1.0) * (f - n));
}

// `lit` is the shaded surface colour, `light` its shading factor: the image paints the albedo.
vec3 painted(vec3 lit, float light, vec3 world) {
    vec4 p = u_projector * vec4(world, 1.0);
    if (p.w <= 0.0) return lit;                           // behind the projector
    vec3 str = p.xyz / p.w;
    if (any(lessThan(str, vec3(0.0))) || any(greaterThan(str, vec3(1.0)))) return lit;
    if (u_projector_shadows != 0) {
        float here = projector_distance(str.z);
        float nearest = projector_distance(textureLod(u_projector_depth, str.xy, 0.0).r);
        if (here > nearest * (1.0 + u_projector_bias)) return lit;   // something nearer to the projector
    }
    // level 0: derivatives are not usable in the composite (a sprite's 2x2 pixel quads span
    // other objects' depths), and STD must paint the same way
    vec4 image = textureLod(u_projector_image, str.xy, 0.0);
    return mix(lit, image.rgb * light, image.a * u_projector_strength);
}
