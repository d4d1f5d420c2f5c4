#version 430
// defines:
// Two triangles over u_rect (x0, y0, x1, y1 in viewport NDC), the union of the drawn objects'
// B_viewport: pixels no object covers are not visited (no vertex buffer).
uniform vec4 u_rect;
void main() {
    int v = gl_VertexID < 3 ? gl_VertexID : 6 - gl_VertexID;     // 0 1 2, 3 2 1 -> corners
    vec2 c = vec2(v & 1, v >> 1);                                  // (0,0) (1,0) (0,1) (1,1)
    gl_Position = vec4(mix(u_rect.xy, u_rect.zw, c), 0.0, 1.0);
}
