// Per-pixel lists of the objects' front surfaces (`--order pixel`): composite.frag's
// MODE_COLLECT writes one node per covered pixel and object, oit_resolve.frag sorts and
// blends each pixel's list. heads[y * width + x]: the pixel's first node + 1 (0: none, so
// the heads are cleared by a memset: a 0xFFFFFFFF pattern took 8 ms at 1024² on llvmpipe);
// a node: (window depth bits, unorm8 (rgb, opacity), next node + 1 (0: none), 0). Object o's
// nodes start at node_base[o] (composite.geom), one per pixel of its B_viewport, so no
// counter is shared.
layout(std430, binding = BINDING_OIT_HEADS) buffer Heads { uint heads[]; };
layout(std430, binding = BINDING_OIT_NODES) buffer Nodes { uvec4 nodes[]; };
const uint NO_NODE = 0u;    // links are node index + 1
// FIRST_FETCHED (oit.OrderMarks with fetch): the stencil's low bits count a pixel's surfaces
// (saturating), its high bit flags one that came at or behind the nearest before it
const int STENCIL_COUNT = 127;
const int STENCIL_FLAG = 128;
