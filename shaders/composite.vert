#version 430
// defines:
// One point per object, in draw order (gl_VertexID indexes the order buffer); no vertex buffer.
#include "composite.glsl"

flat out int v_object;

void main() {
    v_object = order[gl_VertexID];
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
