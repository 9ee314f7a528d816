// Random numbers and direction sampling shared by the Monte-Carlo passes
// (`reference`, `path`, `glossy`): PCG-hash streams (scene.glsl's pcg_hash), an
// orthonormal basis about a normal, cosine and uniform-sphere directions, GGX visible normals.
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL
#include "scene.glsl"
#include "math.glsl"

// Uniform in [0, 1): the hash's top 24 bits.
float next_random(inout uint rng) {
    rng = pcg_hash(rng);
    return float(rng >> 8u) * (1.0 / 16777216.0);
}

// Tangent t and bitangent b completing the unit normal n to a right-handed
// basis, without a division by ~0 anywhere (Duff et al. 2017).
void basis_of(vec3 n, out vec3 t, out vec3 b) {
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + sgn * n.x * n.x * a, sgn * c, -sgn * n.x);
    b = vec3(c, sgn + n.y * n.y * a, -n.y);
}

// Cosine-weighted direction about the unit normal n (pdf cos / pi).
vec3 cosine_direction(vec3 n, inout uint rng) {
    float u1 = next_random(rng), u2 = next_random(rng);
    float r = sqrt(u1), phi = 2.0 * PI * u2;
    vec3 t, b;
    basis_of(n, t, b);
    return normalize(t * (r * cos(phi)) + b * (r * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0)));
}

// Uniform direction on the sphere (pdf 1 / 4pi).
vec3 uniform_sphere(float u1, float u2) {
    float z = 1.0 - 2.0 * u1;
    float r = sqrt(max(1.0 - z * z, 0.0));
    float phi = 2.0 * PI * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// A visible normal for the local viewer v (v.z > 0), Heitz 2018.
vec3 sample_vndf(vec3 v, float a, float u1, float u2) {
    vec3 vh = normalize(vec3(a * v.x, a * v.y, v.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u1), phi = 2.0 * PI * u2;
    float p1 = r * cos(phi), p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return normalize(vec3(a * nh.x, a * nh.y, max(nh.z, 1e-6)));
}

// Power heuristic (beta 2) weight of a technique with pdf a against one with pdf b.
float power_heuristic(float a, float b) {
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

#endif
