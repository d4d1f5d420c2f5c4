#version 430
// defines: SECTIONS
// Depth only (the projector's shadow map): the depth attachment is all that is written.
// SECTIONS: what the section planes cut away casts no shadow (section.glsl).
#ifdef SECTIONS
#define SECTION_FRAGMENT
#include "section.glsl"
in VertexData { vec3 normal; flat int object; flat vec3 color; vec3 world; } fs_in;
#endif

void main() {
#ifdef SECTIONS
    if (int(placement[fs_in.object].w) % 2 == 1 && section_removed(fs_in.world)) discard;
#endif
}
