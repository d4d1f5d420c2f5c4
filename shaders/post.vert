#version 430
// defines:
// Full-screen triangle, one instance per atlas layer (no vertex buffer).
flat out int v_layer;

void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    v_layer = gl_InstanceID;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
