#version 430
// defines: COUNT
// Depth peeling into linear depth (orthographic: gl_FragCoord.z is linear). Pass k keeps
// fragments strictly behind layer k-1; MIN blending on the float target keeps the nearest,
// exactly (no depth buffer quantization). COUNT: every fragment adds 1 (depth complexity).
layout(binding = BINDING_PEEL_PREVIOUS) uniform sampler2D u_prev;   // layer k-1, NIL (> 1) where it has no surface
uniform int u_pass;
layout(location = 0) out float out_depth;

void main() {
#ifdef COUNT
    out_depth = 1.0;
#else
    float z = gl_FragCoord.z;
    if (u_pass > 0 && z <= texelFetch(u_prev, ivec2(gl_FragCoord.xy), 0).r) discard;
    out_depth = z;
#endif
}
