// Volumetric parity tests on a layered depth image (seed 003). q is a point in the LDI's crop
// space (LayeredDepthImage.crop_matrix: texels of the crop in x, y; linear depth in z); it is
// inside when an odd number of surfaces lie in front of it along its texel's ray. Points
// outside the LDI's box or crop are outside. Layers are sorted, NIL (> 1) after the last.
// The plain layers are read as an image (r32f, image unit 0): on llvmpipe an image load is
// cheaper than a texel fetch. They lie texel-major: the `depth` layers of crop texel (x, y)
// are consecutive image texels, from ((x % per_row) * depth, y * k + x / per_row), where
// per_row (crop texels per image row: the crop width when it fits) keeps the image within
// the size limit and k = ceil(crop width / per_row). One point's loads then share a cache
// line: random points over a layer-major array missed the cache once per layer (the test
// ran ~30% slower). The division is done in float (exact for x < 2^16): an integer division
// per point is scalarized on llvmpipe and cost more than the layout gained.
layout(binding = BINDING_LDI_LAYERS, r32f) readonly uniform image2D u_ldi_layers;

bool ldi_in_box(vec3 q, ivec2 crop_size) {
    return all(greaterThanEqual(q, vec3(0.0))) && q.x < float(crop_size.x) && q.y < float(crop_size.y)
           && q.z < 1.0;
}

// plain LDI: the texel's layers read front to back until the first one at or behind q.z (a
// linear loop beat a binary search on llvmpipe: most points meet NIL or a layer behind them
// after one or two loads). A constant `depth` (ldi_classify.comp) lets the loop unroll.
bool ldi_inside(int depth, int per_row, vec3 q, ivec2 crop_size) {
    if (!ldi_in_box(q, crop_size)) return false;
    vec2 texel = floor(q.xy);
    float row = float(per_row);
    float part = floor((texel.x + 0.5) / row);
    ivec2 at = ivec2(int(texel.x - part * row) * depth,
                     int(texel.y * ceil(float(crop_size.x) / row) + part));
    bool inside = false;
    for (int i = 0; i < depth; ++i) {
        if (imageLoad(u_ldi_layers, ivec2(at.x + i, at.y)).r >= q.z) break;
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
