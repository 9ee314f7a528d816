//! No cracks: camera rays of the compute BVH tracer (watertight ray/triangle
//! test, Woop-Benthin-Wald) never miss a closed mesh, including rays through
//! shared vertices and edges; grazing and axis-aligned rays produce no NaN.
use crate::common;

use common::toml::*;

use glam::Vec3;
use hybrid_rt::render::shading::{Backend, Mode};
use hybrid_rt::render::RenderSettings;

// Odd sizes put a pixel centre exactly on the optical axis.
const W: u32 = 161;
const H: u32 = 91;

/// `object` (named "closed mesh"), glowing white on black, seen from
/// `camera_at` (written with `{}`: 3.0 as `3`) looking at the origin.
fn scene(object: Block, camera_at: [f32; 3]) -> String {
    scene_toml([
        black_sky(),
        camera(shown3(camera_at), [0.0; 3]).yfov(40),
        no_light(),
        emitter("glow", [1.0; 3]),
        object.material("glow"),
    ])
}

fn unit_cube() -> Block {
    cube("closed mesh", 1.0)
}

fn rt(backend: Backend) -> RenderSettings {
    RenderSettings { mode: Mode::Rt, backend, ..Default::default() }
}

/// Pixels whose camera ray surely hits the mesh (by `inside`), but rendered
/// as background: cracks.
fn cracks(
    frame: &hybrid_rt::render::FrameOutput,
    cam: &hybrid_rt::scene::Camera,
    inside: impl Fn(Vec3, Vec3) -> bool,
) -> (usize, usize) {
    let (mut checked, mut missed) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let (o, d) = common::pixel_ray(cam, W, H, x, y);
            if inside(o, d) {
                checked += 1;
                if frame.radiance(x, y)[0] < 0.5 {
                    missed += 1;
                }
            }
        }
    }
    (checked, missed)
}

/// Ray against a sphere of radius r at the origin.
fn hits_sphere(o: Vec3, d: Vec3, r: f32) -> bool {
    let b = o.dot(d);
    let c = o.length_squared() - r * r;
    b * b - c > 0.0
}

#[test]
fn rays_through_shared_vertices_and_edges_of_a_cube_hit() {
    // Looking straight at a corner: the centre ray passes through the shared
    // vertex, and the three shared edges run through the image centre.
    let s = common::scene_from_toml("cube_corner", &scene(unit_cube(), [3.0, 3.0, 3.0]));
    let cam = &s.cameras[0];
    for backend in [Backend::Compute, Backend::Query] {
        let f = common::render_scene(&s, W, H, &rt(backend));
        assert!(f.radiance(W / 2, H / 2)[0] > 0.5, "{backend:?}: ray through the corner vertex missed");
        // Rays within the cube's inscribed sphere (radius 0.5) surely hit.
        let (checked, missed) = cracks(&f, cam, |o, d| hits_sphere(o, d, 0.49));
        eprintln!("cube, {backend:?}: {missed} cracks in {checked} pixels");
        assert!(checked > 300);
        assert_eq!(missed, 0, "{backend:?}: {missed} crack pixels");
    }
}

#[test]
fn a_tessellated_sphere_has_no_cracks() {
    let (slices, stacks) = (24u32, 12u32);
    let s = common::scene_from_toml(
        "sphere_cracks",
        &scene(sphere("closed mesh", 1.0).slices(slices, stacks), [0.0, 0.3, 4.0]),
    );
    let f = common::render_scene(&s, W, H, &rt(Backend::Compute));
    // The polyhedron contains the sphere of radius cos(pi/slices) * cos(pi/stacks).
    let inner =
        (std::f32::consts::PI / slices as f32).cos() * (std::f32::consts::PI / stacks as f32).cos() * 0.995;
    let (checked, missed) = cracks(&f, &s.cameras[0], |o, d| hits_sphere(o, d, inner));
    eprintln!("sphere: {missed} cracks in {checked} pixels");
    assert!(checked > 1000);
    assert_eq!(missed, 0);
}

#[test]
fn axis_aligned_and_grazing_rays_stay_finite() {
    // Camera on the x axis looking down -x at an axis-aligned box: rays with
    // zero y/z components at the centre, and rays grazing the box faces.
    let s = common::scene_from_toml("axis_box", &scene(unit_cube(), [4.0, 0.0, 0.0]));
    for backend in [Backend::Compute, Backend::Query, Backend::Pipeline] {
        let f = common::render_scene(&s, W, H, &rt(backend));
        assert!(f.radiance(W / 2, H / 2)[0] > 0.5, "{backend:?}: axis-aligned centre ray missed the box");
    }
}

/// Axis-parallel rays lying exactly in the planes of a cube's faces (and
/// through its edges and corners), with +0.0 and -0.0 in their zero
/// components: each must hit the face it enters through that face's edge.
/// The compute tracer's 4-wide node test gives an axis the ray is parallel
/// to no slab at all (its 1/d is not used: 0 * inf would be NaN, which
/// GLSL's min/max need not ignore). With that rule removed (the slab from
/// the zeroed 1/d, [0, 0]) every one of these rays misses.
#[test]
fn axis_parallel_rays_in_the_face_planes_of_a_cube_hit() {
    use hybrid_rt::app::RayBench;
    use hybrid_rt::render::rays::sets::RayKind;
    use hybrid_rt::render::rays::{BenchRay, Traversal};
    use hybrid_rt::render::shading::Backend;

    let s = common::scene_from_toml("cube_planes", &scene(unit_cube(), [4.0, 0.0, 0.0]));
    let ctx = common::validated_context();
    let bench =
        RayBench::with_traversal(&ctx, &s, Traversal::Lane, Backend::Query).expect("set up both tracers");
    let grid = [-0.5f64, -0.25, 0.0, 0.25, 0.5];
    let mut rays = Vec::new();
    for axis in 0..3 {
        for sign in [1.0f64, -1.0] {
            for (&u, &v) in grid.iter().flat_map(|u| grid.iter().map(move |v| (u, v))) {
                for zeros in [[0.0f32, 0.0], [-0.0, -0.0], [0.0, -0.0]] {
                    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                    let mut o = glam::DVec3::ZERO;
                    o[axis] = -3.0 * sign;
                    o[a] = u;
                    o[b] = v;
                    let mut d = [0.0f32; 3];
                    d[axis] = sign as f32;
                    d[a] = zeros[0];
                    d[b] = zeros[1];
                    let origin = bench.gpu.origin.point(o).to_array();
                    rays.push(BenchRay { origin, tmax: 100.0, dir: d, pad: 0 });
                }
            }
        }
    }
    let report = bench.kind(&ctx, RayKind::Primary, &rays, 1);
    let mut bench = bench;
    bench.destroy(&ctx);
    let report = report.expect("trace the rays");
    let missed: Vec<_> = rays
        .iter()
        .zip(&report.compute.results)
        .filter(|(_, r)| r.hit == 0 || (r.t - 2.5).abs() > 1e-4)
        .map(|(ray, r)| (ray.origin, ray.dir, r.hit, r.t))
        .collect();
    assert!(
        missed.is_empty(),
        "{} of {} rays missed the face they enter: {missed:?}",
        missed.len(),
        rays.len()
    );
    common::assert_validation_clean(&ctx);
}
