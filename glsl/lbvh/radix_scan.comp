#version 460
// LBVH sort, pass part 2: exclusive prefix sum of the histogram, one workgroup (each invocation sums a
// contiguous run, the run totals are scanned in shared memory, then each run is rewritten).
#include "lbvh.glsl"

shared uint run_total[LBVH_GROUP];

void main() {
    uint t = gl_LocalInvocationID.x;
    uint len = RADIX * pc.blocks;
    uint per = (len + LBVH_GROUP - 1u) / LBVH_GROUP;
    uint first = min(len, t * per), end = min(len, first + per);
    uint sum = 0u;
    for (uint j = first; j < end; j++) {
        sum += hist[j];
    }
    run_total[t] = sum;
    barrier();
    if (t == 0u) {
        uint acc = 0u;
        for (uint k = 0u; k < LBVH_GROUP; k++) {
            uint v = run_total[k];
            run_total[k] = acc;
            acc += v;
        }
    }
    barrier();
    uint acc = run_total[t];
    for (uint j = first; j < end; j++) {
        uint v = hist[j];
        hist[j] = acc;
        acc += v;
    }
}
