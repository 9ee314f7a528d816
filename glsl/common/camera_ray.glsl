// The camera ray as `primary` and `visibility_trace` both trace it: counted as a camera ray, alpha
// mip from the camera-ray cone (g_camera_ray), so cut-outs land where the raster's alpha test puts
// them. Needs primary_hit.glsl, integrator.glsl and a trace backend first.
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
