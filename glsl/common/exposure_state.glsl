// Set 0's exposure buffer (render/tone.rs `exposure_buffer_bytes`): the
// state kept across frames, then the luminance reduction's per-group
// partial sums and histograms (scratch, rewritten every frame).
#ifndef EXPOSURE_STATE_GLSL
#define EXPOSURE_STATE_GLSL
#include "exposure.glsl"

struct LuminancePartial {
    float sum_log;   // sum of log(delta + L) over the group's finite pixels
    uint finite;     // finite pixels
    float max_luminance;
    uint pad;
};

layout(set = SET_SCENE, binding = SCENE_EXPOSURE, std430) buffer ExposureBlock {
    ExposureState exposure_state;
    LuminancePartial lum_partials[LUMINANCE_GROUPS];
    uint lum_histograms[LUMINANCE_GROUPS * HIST_BINS];
};

#endif
