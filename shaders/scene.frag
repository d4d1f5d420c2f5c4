#version 430
// defines:
// Multiple render targets: shaded colour, view-space normal, object id (depth is the depth attachment).
#include "records.glsl"

in VertexData { vec3 normal; flat int object; } fs_in;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out int out_id;

void main() {
    float len_n = length(fs_in.normal);
    vec3 n = len_n > 1e-20 ? fs_in.normal / len_n : vec3(0.0, 0.0, 1.0);
    if (!gl_FrontFacing) n = -n;
    // headlight: light from the camera, two-sided
    float diffuse = abs(n.z);
    vec3 base = object_colors[fs_in.object].rgb;
    out_color = vec4(base * (0.25 + 0.75 * diffuse), 1.0);
    out_normal = vec4(n, 1.0);
    out_id = fs_in.object;
}
