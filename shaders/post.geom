#version 430
// defines:
// Routes each instance's full-screen triangle to its atlas layer.
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
flat in int v_layer[];

void main() {
    for (int i = 0; i < 3; ++i) {
        gl_Layer = v_layer[0];
        gl_Position = gl_in[i].gl_Position;
        EmitVertex();
    }
    EndPrimitive();
}
