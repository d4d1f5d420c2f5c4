// Per-pixel lists of the objects' front surfaces (`--order pixel`): composite.frag's
// MODE_COLLECT appends one node per covered pixel and object, oit_resolve.frag sorts and
// blends each pixel's list. heads[y * width + x]: the pixel's first node (0xFFFFFFFF: none);
// a node: (window depth bits, unorm8 (rgb, opacity), next node, 0).
layout(std430, binding = 5) buffer Heads { uint heads[]; };
layout(std430, binding = 6) buffer Nodes {
    uint node_count;      // nodes appended (may pass the capacity: those are dropped)
    uint node_capacity;
    uint node_pad0, node_pad1;
    uvec4 nodes[];
};
const uint NO_NODE = 0xFFFFFFFFu;
