#version 430
// defines:
// One point per object (gl_VertexID is its id); no vertex buffer. post.geom expands it.
flat out int v_object;

void main() {
    v_object = gl_VertexID;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
