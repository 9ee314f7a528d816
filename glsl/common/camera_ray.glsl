// The camera ray through pixel `px`'s centre, traced to its closest hit the
// way `primary` (pure RT) and `visibility_trace` (hybrid, traced primary
// visibility) both need it: counted as a camera ray, its alpha test picking
// the mip from the camera-ray cone (hit.glsl's g_camera_ray), so the two
// passes put alpha-masked cut-outs where the raster's alpha test does.
// Needs primary_hit.glsl and integrator.glsl (and a trace backend) first.
#ifndef CAMERA_RAY_GLSL
#define CAMERA_RAY_GLSL

bool trace_camera_ray(ivec2 px, out vec3 dir, out RayHit h) {
    dir = camera_ray_dir(vec2(px) + 0.5);
    count_ray(RAY_KIND_CAMERA);
    g_camera_ray = true;
    g_camera_pixel = px;
    bool hit = trace_closest(frame.camera_pos, dir, RAY_TMAX, h);
    g_camera_ray = false;
    return hit;
}
#endif
