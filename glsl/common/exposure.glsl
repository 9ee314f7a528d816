// Auto exposure adaptation, pure functions so the shading probe can test them
// (the buffer is declared in exposure_state.glsl).
#ifndef EXPOSURE_GLSL
#define EXPOSURE_GLSL

// Mirrored by render/tone.rs `ExposureState` (32 bytes).
struct ExposureState {
    float adapted;        // adapted scene luminance
    float exposure;       // key / adapted * compensation: what tone mapping applies
    float target;         // this frame's measured luminance
    float log_average;    // exp(mean(log(delta + L))) of the finite pixels
    float max_luminance;  // brightest finite luminance
    uint finite_pixels;
    uint valid;           // 1 once a frame was measured
    uint pad;
};

// The PRT document's adaptation. The factor composes over frames (two steps of dt equal one of 2 dt),
// so it is frame-rate independent. dt <= 0 (still or first frame): converged at once.
float adapt_log_average(float adapted, float target, float dt) {
    if (dt <= 0.0) return target;
    return adapted + (target - adapted) * (1.0 - pow(ADAPT_BASE, ADAPT_FPS * dt));
}

// Histogram adaptation in EV (log2 luminance) at a constant speed in EV
// per second, faster when the image has to get brighter (the scene got
// darker) than darker, as Unreal and Bevy do; it stops at the target.
float adapt_histogram(float adapted, float target, float dt, float speed_brighten, float speed_darken) {
    if (dt <= 0.0) return target;
    float ev = log2(adapted);
    float d = log2(target) - ev;
    // d < 0: the scene is darker than adapted to -> the image brightens.
    float step = clamp(d, -speed_brighten * dt, speed_darken * dt);
    return exp2(ev + step);
}

#endif
