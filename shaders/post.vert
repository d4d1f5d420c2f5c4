#version 430
// defines:
// One point per object to shade (gl_VertexID indexes the list); no vertex buffer. post.geom expands it.
layout(std430, binding = BINDING_DRAW_LIST) readonly buffer ObjectList { int objects[]; };
flat out int v_object;

void main() {
    v_object = objects[gl_VertexID];
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
