#version 460
// Pass `luminance` (render/passes/luminance.rs), two kernels by SPEC_LUMINANCE_STAGE:
//  0: LUMINANCE_GROUPS groups stride over the image writing partial sums and a histogram each; a fixed
//     grid keeps the scratch fixed-size and the sum order (so the result) the same every run.
//  1: one group sums the partials, finds the target luminance and adapts the kept state.
// Non-finite pixels are left out of every sum (tone mapping counts them).
#extension GL_EXT_scalar_block_layout : require
#include "common/scene.glsl"
#include "common/exposure_state.glsl"
#include "common/tonemap.glsl"

layout(local_size_x = LUMINANCE_THREADS) in;
layout(constant_id = SPEC_LUMINANCE_STAGE) const uint STAGE = 0;
layout(set = SET_PASS, binding = LUMINANCE_IN, rgba32f) uniform readonly image2D hdr_in;

shared float s_sum[LUMINANCE_THREADS];
shared uint s_count[LUMINANCE_THREADS];
shared float s_max[LUMINANCE_THREADS];
shared uint s_hist[HIST_BINS];

uint histogram_bin(float l) {
    // Black (log2 0 = -inf) lands in bin 0.
    float t = (log2(max(l, 1e-30)) - HIST_MIN_LOG2) / (HIST_MAX_LOG2 - HIST_MIN_LOG2);
    return uint(clamp(t * float(HIST_BINS), 0.0, float(HIST_BINS - 1u)));
}

void reduce_shared(uint t) {
    for (uint stride = LUMINANCE_THREADS / 2u; stride > 0u; stride >>= 1u) {
        barrier();
        if (t < stride) {
            s_sum[t] += s_sum[t + stride];
            s_count[t] += s_count[t + stride];
            s_max[t] = max(s_max[t], s_max[t + stride]);
        }
    }
    barrier();
}

void partials() {
    uint g = gl_WorkGroupID.x, t = gl_LocalInvocationID.x;
    for (uint b = t; b < HIST_BINS; b += LUMINANCE_THREADS) s_hist[b] = 0u;
    barrier();
    uvec2 res = frame.resolution;
    uint n = res.x * res.y;
    float sum = 0.0, mx = 0.0;
    uint count = 0u;
    for (uint i = g * LUMINANCE_THREADS + t; i < n; i += LUMINANCE_GROUPS * LUMINANCE_THREADS) {
        vec3 c = imageLoad(hdr_in, ivec2(i % res.x, i / res.x)).rgb;
        if (any(isnan(c)) || any(isinf(c))) continue;
        float l = max(tone_luminance(c), 0.0);
        sum += log(LOG_AVERAGE_DELTA + l);
        mx = max(mx, l);
        count += 1u;
        atomicAdd(s_hist[histogram_bin(l)], 1u);
    }
    s_sum[t] = sum;
    s_count[t] = count;
    s_max[t] = mx;
    reduce_shared(t);
    if (t == 0u) lum_partials[g] = LuminancePartial(s_sum[0], s_count[0], s_max[0], 0u);
    for (uint b = t; b < HIST_BINS; b += LUMINANCE_THREADS) lum_histograms[g * HIST_BINS + b] = s_hist[b];
}

// Between the low and high percentiles (bin centres); `fallback` when the window is empty.
float histogram_mean_log2(uint total, float fallback) {
    float lo = frame.hist_low * float(total), hi = frame.hist_high * float(total);
    float below = 0.0, weight = 0.0, sum = 0.0;
    float width = (HIST_MAX_LOG2 - HIST_MIN_LOG2) / float(HIST_BINS);
    for (uint b = 0u; b < HIST_BINS; b++) {
        float c = float(s_hist[b]);
        float overlap = max(0.0, min(below + c, hi) - max(below, lo));
        sum += overlap * (HIST_MIN_LOG2 + (float(b) + 0.5) * width);
        weight += overlap;
        below += c;
    }
    return weight > 0.0 ? sum / weight : fallback;
}

void finalize() {
    uint t = gl_LocalInvocationID.x;
    float sum = 0.0, mx = 0.0;
    uint count = 0u;
    for (uint g = t; g < LUMINANCE_GROUPS; g += LUMINANCE_THREADS) {
        LuminancePartial p = lum_partials[g];
        sum += p.sum_log;
        count += p.finite;
        mx = max(mx, p.max_luminance);
    }
    s_sum[t] = sum;
    s_count[t] = count;
    s_max[t] = mx;
    for (uint b = t; b < HIST_BINS; b += LUMINANCE_THREADS) {
        uint h = 0u;
        for (uint g = 0u; g < LUMINANCE_GROUPS; g++) h += lum_histograms[g * HIST_BINS + b];
        s_hist[b] = h;
    }
    reduce_shared(t);
    if (t != 0u) return;
    ExposureState s = exposure_state;
    uint finite = s_count[0];
    // No finite pixel: keep what was adapted to (or 1 on a first frame).
    float log_average = finite > 0u ? exp(s_sum[0] / float(finite)) : (s.valid != 0u ? s.adapted : 1.0);
    float target = log_average;
    if (frame.auto_exposure == AUTO_EXPOSURE_HISTOGRAM && finite > 0u) {
        target = exp2(histogram_mean_log2(finite, log2(log_average)));
    }
    // Keeps the exposure finite on black and blinding frames (the log-average, unlike the histogram,
    // has no range limit).
    target = clamp(target, 1e-30, 1e30);
    float dt = s.valid != 0u ? frame.adapt_dt : 0.0;
    float adapted = frame.auto_exposure == AUTO_EXPOSURE_HISTOGRAM
        ? adapt_histogram(s.adapted, target, dt, frame.speed_brighten, frame.speed_darken)
        : adapt_log_average(s.adapted, target, dt);
    s.adapted = adapted;
    s.exposure = frame.key / adapted * frame.exposure;
    s.target = target;
    s.log_average = log_average;
    s.max_luminance = s_max[0];
    s.finite_pixels = finite;
    s.valid = 1u;
    exposure_state = s;
}

void main() {
    if (STAGE == 0u) {
        partials();
    } else {
        finalize();
    }
}
