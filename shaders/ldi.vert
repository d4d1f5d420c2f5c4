#version 430
// defines:
// A closed mesh seen by the LDI's orthographic camera: texture space -> NDC in one matrix.
in vec3 in_position;
uniform mat4 u_matrix;

void main() {
    gl_Position = u_matrix * vec4(in_position, 1.0);
}
