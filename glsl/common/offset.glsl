// Ray origin offset against self-intersection, after Wächter & Binder ("A
// Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems
// ch. 6): the origin moves along the geometric normal by a fixed number of
// ULPs, so the offset grows with the coordinates' rounding error. Unlike
// their per-coordinate form, the ULP is taken of the hit triangle's largest
// world coordinate (`extent`), not of the point's own coordinates: a point
// near the middle of a large triangle, or on an axis where one coordinate is
// ~0, is only as precise as the vertices it was interpolated from (a tilted
// ground plane at x1e3 showed acne with the per-coordinate form), and a
// fixed 256-ULP move of each coordinate reached metres 1e5 from the origin.
#ifndef OFFSET_GLSL
#define OFFSET_GLSL

// OFFSET_ULPS (shared_values.rs): ULPs of the extent the origin moves.

// Spacing of floats at |x| (x finite, > 0).
float ulp_at(float x) {
    return intBitsToFloat(floatBitsToInt(x) + 1) - x;
}

vec3 offset_ray(vec3 p, vec3 n, float extent) {
    vec3 a = abs(p);
    // 1e-30: degenerate triangles at the origin still move off it.
    float m = max(max(max(a.x, a.y), max(a.z, extent)), 1e-30);
    // The move along n is >= 16 ULPs of every coordinate, so rounding the
    // sum never leaves the origin on the surface.
    return p + n * (OFFSET_ULPS * ulp_at(m));
}

// Largest world-space coordinate magnitude of a triangle (offset_ray's extent).
float triangle_extent(vec3 p0, vec3 p1, vec3 p2) {
    vec3 m = max(abs(p0), max(abs(p1), abs(p2)));
    return max(m.x, max(m.y, m.z));
}

#endif
