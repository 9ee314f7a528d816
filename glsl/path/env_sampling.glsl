// Environment importance sampling for the path tracer: a map by the piecewise-constant table of
// gpu/env_sampling.rs (luminance x sin(theta); layout SCENE_ENV_CDF), marginal row then texel; a
// constant sky uniformly. Inverts env_uv, rotation included, so env_pdf(env_sample(..)) is exact.
#ifndef ENV_SAMPLING_GLSL
#define ENV_SAMPLING_GLSL
#include "../common/env.glsl"
#include "../common/sampling.glsl"

layout(set = SET_SCENE, binding = SCENE_ENV_CDF, scalar) readonly buffer EnvCdf { float env_cdf[]; };

bool env_has_table() {
    return frame.has_env_map != 0u && env_cdf[2] > 0.5;
}

// Else no light sample is spent on it.
bool env_emits() {
    return frame.env_intensity > 0.0 && (env_has_table() || max3(frame.env_color) > 0.0);
}

// The last i < n with cdf[base + i] <= u (cdf[base] = 0, cdf[base + n] = 1).
uint cdf_find(uint base, uint n, float u) {
    uint lo = 0u, hi = n;
    while (lo + 1u < hi) {
        uint mid = (lo + hi) >> 1u;
        if (env_cdf[base + mid] <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// env_uv's inverse.
vec3 env_direction(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * PI - frame.env_rotation;
    float theta = uv.y * PI;
    float st = sin(theta);
    return vec3(st * sin(phi), cos(theta), -st * cos(phi));
}

// Solid-angle pdf of the table's cell (col, row) at polar sine st.
float env_cell_pdf(uint col, uint row, float st) {
    uint w = uint(env_cdf[0]), h = uint(env_cdf[1]);
    uint marg = ENV_CDF_HEADER;
    uint cond = marg + h + 1u + row * (w + 1u);
    float p_uv = (env_cdf[marg + row + 1u] - env_cdf[marg + row]) * float(h)
        * (env_cdf[cond + col + 1u] - env_cdf[cond + col]) * float(w);
    return p_uv / (2.0 * PI * PI * max(st, 1e-6));
}

// The pdf env_sample draws d with.
float env_pdf(vec3 d) {
    if (!env_has_table()) return 1.0 / (4.0 * PI);
    uint w = uint(env_cdf[0]), h = uint(env_cdf[1]);
    vec2 uv = env_uv(d);
    uint col = min(uint(fract(uv.x) * float(w)), w - 1u);
    uint row = min(uint(uv.y * float(h)), h - 1u);
    return env_cell_pdf(col, row, sqrt(max(1.0 - d.y * d.y, 0.0)));
}

vec3 env_sample(inout uint rng, out float pdf) {
    float u1 = next_random(rng), u2 = next_random(rng);
    if (!env_has_table()) {
        pdf = 1.0 / (4.0 * PI);
        return uniform_sphere(u1, u2);
    }
    uint w = uint(env_cdf[0]), h = uint(env_cdf[1]);
    uint marg = ENV_CDF_HEADER;
    uint row = cdf_find(marg, h, u1);
    float c0 = env_cdf[marg + row], c1 = env_cdf[marg + row + 1u];
    uint cond = marg + h + 1u + row * (w + 1u);
    uint col = cdf_find(cond, w, u2);
    float d0 = env_cdf[cond + col], d1 = env_cdf[cond + col + 1u];
    float fv = clamp((u1 - c0) / max(c1 - c0, 1e-30), 0.0, 1.0);
    float fu = clamp((u2 - d0) / max(d1 - d0, 1e-30), 0.0, 1.0);
    vec2 uv = vec2((float(col) + fu) / float(w), (float(row) + fv) / float(h));
    pdf = env_cell_pdf(col, row, sin(uv.y * PI));
    return env_direction(uv);
}

#endif
