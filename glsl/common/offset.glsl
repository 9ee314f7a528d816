// Ray origin offset against self-intersection after Wächter & Binder (Ray Tracing Gems ch. 6): move
// along the geometric normal by OFFSET_ULPS ULPs. Unlike their per-coordinate form, the ULP is of the
// triangle's largest coordinate (`extent`): an interpolated point is only as precise as its vertices
// (a tilted ground plane at x1e3 showed acne), and a fixed 256-ULP move reached metres at 1e5.
#ifndef OFFSET_GLSL
#define OFFSET_GLSL

// x finite, > 0.
float ulp_at(float x) {
    return intBitsToFloat(floatBitsToInt(x) + 1) - x;
}

vec3 offset_ray(vec3 p, vec3 n, float extent) {
    vec3 a = abs(p);
    // 1e-30: degenerate triangles at the origin still move off it.
    float m = max(max(max(a.x, a.y), max(a.z, extent)), 1e-30);
    // >= OFFSET_ULPS ULPs of every coordinate, so rounding never leaves the origin on the surface.
    return p + n * (OFFSET_ULPS * ulp_at(m));
}

float triangle_extent(vec3 p0, vec3 p1, vec3 p2) {
    vec3 m = max(abs(p0), max(abs(p1), abs(p2)));
    return max(m.x, max(m.y, m.z));
}

#endif
