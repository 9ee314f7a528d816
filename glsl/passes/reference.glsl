// Pass `reference`: ray-traced diffuse environment light at the primary hit, REFERENCE_SAMPLES_PER_FRAME
// cosine directions per pixel. A miss brings the full-resolution environment, a hit occludes, or with
// Frame.accum_bounces K > 1 continues as a diffuse path of up to K rays (emission plus diffuse albedo;
// punctual lights stay in `direct`). With pdf cos/pi the mean is E/pi, what ambient_radiance(n)
// approximates; `composite` divides the sum by the count. PCG-seeded by pixel and Frame.accum_frame so
// every backend traces the same rays.
#include "../common/gbuffer_read.glsl"
#include "../common/integrator.glsl"
#include "../common/sampling.glsl"

layout(set = SET_PASS, binding = REFERENCE_OUT, rgba32f) uniform image2D reference_accum;

// `gn` on the side the hemisphere samples.
vec3 reference_path(Surface s, vec3 gn, inout uint rng) {
    vec3 throughput = vec3(1.0), radiance = vec3(0.0);
    uint bounces = max(frame.accum_bounces, 1u);
    for (uint b = 0u; b < bounces; ++b) {
        vec3 d = cosine_direction(s.normal, rng);
        // Below the geometry (a normal map tilted the lobe): self-occluded, as in direct_light.
        if (dot(d, gn) <= 0.0) break;
        vec3 o = offset_ray(s.position, gn, s.extent);
        RayHit h;
        count_ray(RAY_KIND_SECONDARY);
        if (!trace_closest(o, d, RAY_TMAX, h)) {
            radiance += throughput * environment(d);
            break;
        }
        if (b + 1u == bounces) break;  // occluded: the path ends
        bool back_face;
        s = hit_surface(h, o, d, 0.0, gn, back_face);
        radiance += throughput * s.emissive;
        throughput *= (1.0 - s.metallic) * (1.0 - s.transmission) * s.base_color;
        if (max3(throughput) <= 0.0) break;
    }
    return radiance;
}

void reference_pixel(ivec2 px) {
    PrimaryHit p;
    if (outside_frame(px) || !read_primary(px, p)) return;
    face_viewer(p.s, -p.dir);
    uint rng = pcg_hash(uint(px.x) + pcg_hash(uint(px.y) + pcg_hash(frame.accum_frame)));
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < REFERENCE_SAMPLES_PER_FRAME; ++i) {
        sum += reference_path(p.s, p.gn, rng);
    }
    vec4 acc = vec4(sum, float(REFERENCE_SAMPLES_PER_FRAME));
    if (frame.accum_frame != 0u) acc += imageLoad(reference_accum, px);
    imageStore(reference_accum, px, acc);
}
