// Volumetric parity tests on a layered depth image (seed 003). T is a point in LDI texture
// space; it is inside when an odd number of surfaces lie in front of it along its texel's ray.
// Points outside the LDI's box or crop are outside. Layers are sorted, NIL (> 1) after the last.

ivec2 ldi_texel(vec3 T, ivec2 size, ivec4 crop, out bool ok) {
    ivec2 texel = ivec2(floor(T.xy * vec2(size))) - crop.xy;
    ok = all(greaterThanEqual(T, vec3(0.0))) && all(lessThan(T, vec3(1.0)))
         && all(greaterThanEqual(texel, ivec2(0))) && all(lessThan(texel, crop.zw));
    return texel;
}

// plain LDI: one texture-array layer per depth layer, read front to back until the first
// layer at or behind T.z (a linear loop beat a binary search on llvmpipe: most points meet
// NIL or a layer behind them after one or two fetches)
bool ldi_inside(sampler2DArray layers, int depth, vec3 T, ivec2 size, ivec4 crop) {
    bool ok;
    ivec2 texel = ldi_texel(T, size, crop, ok);
    if (!ok) return false;
    bool inside = false;
    for (int i = 0; i < depth; ++i) {
        if (texelFetch(layers, ivec3(texel, i), 0).r >= T.z) break;
        inside = !inside;
    }
    return inside;
}

// compressed LDI (RG32UI): texel L of the crop holds (offset, count) of its depth ranges;
// range k is at offset + k as (start, end) float bits; offset 0 means no range
bool ldi_inside_compressed(usampler2D ranges, vec3 T, ivec2 size, ivec4 crop) {
    bool ok;
    ivec2 texel = ldi_texel(T, size, crop, ok);
    if (!ok) return false;
    int width = textureSize(ranges, 0).x;
    int linear = texel.y * crop.z + texel.x;
    uvec2 index = texelFetch(ranges, ivec2(linear % width, linear / width), 0).rg;
    for (uint k = 0u; k < index.y; ++k) {
        int at = int(index.x + k);
        vec2 dr = uintBitsToFloat(texelFetch(ranges, ivec2(at % width, at / width), 0).rg);
        if (T.z <= dr.x) break;          // ranges are sorted: the rest lie behind the point
        if (T.z <= dr.y) return true;    // start < z <= end
    }
    return false;
}
