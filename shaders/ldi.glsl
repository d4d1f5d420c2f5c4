// Volumetric parity tests on a layered depth image (seed 003). q is a point in the LDI's crop
// space (LayeredDepthImage.crop_matrix: texels of the crop in x, y; linear depth in z); it is
// inside when an odd number of surfaces lie in front of it along its texel's ray. Points
// outside the LDI's box or crop are outside. Layers are sorted, NIL (> 1) after the last.
// The plain layers are read as an image (r32f, image unit 0): on llvmpipe an image load is
// cheaper than a texel fetch.
layout(binding = 0, r32f) readonly uniform image2DArray u_ldi_layers;

bool ldi_in_box(vec3 q, ivec2 crop_size) {
    return all(greaterThanEqual(q, vec3(0.0))) && q.x < float(crop_size.x) && q.y < float(crop_size.y)
           && q.z < 1.0;
}

// plain LDI: one image layer per depth layer, read front to back until the first layer at or
// behind q.z (a linear loop beat a binary search on llvmpipe: most points meet NIL or a layer
// behind them after one or two loads)
bool ldi_inside(int depth, vec3 q, ivec2 crop_size) {
    if (!ldi_in_box(q, crop_size)) return false;
    ivec2 texel = ivec2(q.xy);
    bool inside = false;
    for (int i = 0; i < depth; ++i) {
        if (imageLoad(u_ldi_layers, ivec3(texel, i)).r >= q.z) break;
        inside = !inside;
    }
    return inside;
}

// compressed LDI (RG32UI): texel L of the crop holds (offset, count) of its depth ranges;
// range k is at offset + k as (start, end) float bits; offset 0 means no range
bool ldi_inside_compressed(usampler2D ranges, vec3 q, ivec2 crop_size) {
    if (!ldi_in_box(q, crop_size)) return false;
    ivec2 texel = ivec2(q.xy);
    int width = textureSize(ranges, 0).x;
    int linear = texel.y * crop_size.x + texel.x;
    uvec2 index = texelFetch(ranges, ivec2(linear % width, linear / width), 0).rg;
    for (uint k = 0u; k < index.y; ++k) {
        int at = int(index.x + k);
        vec2 dr = uintBitsToFloat(texelFetch(ranges, ivec2(at % width, at / width), 0).rg);
        if (q.z <= dr.x) break;          // ranges are sorted: the rest lie behind the point
        if (q.z <= dr.y) return true;    // start < z <= end
    }
    return false;
}
