// The budget's partial specular share, reconstructed (render/budget/effects.rs): a partial pair traces
// its reflection or refraction chain on the pixels of an ordered-dither lattice (budget_rank), and an
// untraced pixel of that object takes the traced lattice corners around it, weighted bilinearly and by
// how well they agree with it (same object, normal, plane): a lower-resolution effect upsampled with
// the G-buffer as guide (joint bilateral upsampling), instead of tiles of traced and fallback shading.
#ifndef BUDGET_FILL_GLSL
#define BUDGET_FILL_GLSL
#include "gbuffer_read.glsl"

// Specular effects a partial pair left untraced at px; 0 where nothing is missing.
uint budget_partial_missing(uint instance, ivec2 px) {
    if ((frame.flags & FRAME_BUDGET) == 0u) return 0u;
    uint word = budget_mask[instances[instance].object_id];
    uint partial = (word >> EFFECT_PARTIAL_SHIFT) & EFFECT_ALL;
    uint specular = (1u << EFFECT_BIT_REFLECTIONS) | (1u << EFFECT_BIT_REFRACTIONS);
    return partial & ~budget_partial_here(word, px) & ~word & specular;
}

// The spacing of the traced lattice for `word`'s share: ranks below 4^k are the multiples of 8 / 2^k.
int budget_lattice_period(uint word) {
    uint ranks = word >> EFFECT_FRACTION_SHIFT;
    return ranks >= 16u ? 2 : (ranks >= 4u ? 4 : 8);
}

// The specular chain's radiance at px (p: its primary hit) from the traced lattice corners around it,
// read from the includer's `specular_in`; false where none agrees with it (an object edge, a crease):
// the pixel keeps its fallback.
bool budget_fill(ivec2 px, PrimaryHit p, out vec3 filled) {
    uint object = instances[p.instance].object_id;
    int period = budget_lattice_period(budget_mask[object]);
    ivec2 base = (px / period) * period;
    vec2 f = vec2(px - base) / float(period);
    // The pixel's footprint on its surface, times the lattice spacing: how far off its plane a corner
    // on the same surface can lie.
    float footprint = pixel_spread_angle() * distance(frame.camera_pos, p.s.position) * float(period);
    vec3 sum = vec3(0.0);
    float weights = 0.0;
    for (int i = 0; i < 4; ++i) {
        ivec2 corner = ivec2(i & 1, i >> 1);
        ivec2 q = base + corner * period;
        if (outside_frame(q)) continue;
        PrimaryHit c;
        if (!read_primary(q, c) || instances[c.instance].object_id != object) continue;
        // A floor keeps the far corners in play where the near ones lie on another surface.
        vec2 bilinear = mix(1.0 - f, f, vec2(corner)) + 1.0 / 16.0;
        float wn = pow(max(dot(p.s.normal, c.s.normal), 0.0), 32.0);
        float wp = exp(-abs(dot(p.s.normal, c.s.position - p.s.position)) / max(footprint, 1e-30));
        float w = bilinear.x * bilinear.y * wn * wp;
        sum += w * imageLoad(specular_in, q).rgb;
        weights += w;
    }
    filled = sum / max(weights, 1e-30);
    return weights > 1e-4;
}

#endif
