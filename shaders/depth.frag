#version 430
// defines:
// Depth only (the projector's shadow map): the depth attachment is all that is written.
void main() {}
