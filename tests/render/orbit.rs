//! Animated shadow/reflection test: a red emissive ball orbits (scene-file
//! `orbit`) in front of a flat mirror above a lit floor. One renderer per
//! backend is built at t = 0 and then moved with `Renderer::update_scene` to
//! a quarter and half period; in every frame the ball, its mirror image and
//! its shadow must sit where closed-form geometry puts them. A reflection or
//! shadow left at the previous pose (top level not rebuilt) lands about
//! 20 px from its expected place, a missing one has no pixels; the tolerance
//! is 1.5 px.
//!
//! Also the golden image of the shipped animated Sponza scene.
use crate::common;

use common::toml::*;

use glam::{Quat, Vec2, Vec3};
use hybrid_rt::render::shading::{AaMode, Backend};
use hybrid_rt::render::{FrameOutput, RenderSettings, Renderer};
use hybrid_rt::scene::animation::find_animation;
use hybrid_rt::scene::scene_file::SCENE_ANIMATION;
use hybrid_rt::scene::{Camera, Scene};

const W: u32 = 240;
const H: u32 = 135;
const PERIOD: f32 = 4.0;
/// The ball starts at START and turns about the +Z axis through CENTER,
/// in the plane z = 1 parallel to the mirror (z = 0, facing +Z).
const CENTER: Vec3 = Vec3::new(0.0, 0.0, 1.0);
const START: Vec3 = Vec3::new(0.7, 0.0, 1.0);
const BALL_RADIUS: f32 = 0.2;
/// Mirror: x in [-2, 2], y in [FLOOR_Y, 1.8] at z = 0.
const MIRROR_HALF_WIDTH: f32 = 2.0;
const MIRROR_TOP: f32 = 1.8;
/// Floor: y = FLOOR_Y, x in [-4, 4], z in [0, 8] (only in front of the mirror).
const FLOOR_Y: f32 = -1.2;
/// Lambert floor (albedo 0.8) under a 3 lux sun straight down.
const FLOOR_LIT: f32 = 0.8 * 3.0 / std::f32::consts::PI;
const TOLERANCE_PX: f32 = 1.5;

fn scene_text() -> String {
    let orbit =
        format!("{{ center = {}, axis = [0.0, 0.0, 1.0], period = {PERIOD} }}", shown3(CENTER.into()).toml());
    scene_toml([
        black_sky(),
        camera([2.4, 1.0, 4.2], [0.0, -0.1, 0.2]).yfov(50),
        directional([0.0, -1.0, 0.0], 3.0),
        mirror("mirror", [0.9, 0.9, 0.9]),
        emitter("red", [1.0, 0.0, 0.0]).set("emissive_strength", 4.0).roughness(1.0),
        lambert("floor", [0.8, 0.8, 0.8]),
        plane("mirror", [4.0, 3.0]).rot([90.0, 0.0, 0.0]).at([0.0, 0.3, 0.0]).material("mirror"),
        plane("floor", [8.0, 8.0]).at([0.0, FLOOR_Y, 4.0]).material("floor"),
        sphere("ball", BALL_RADIUS).at(shown3(START.into())).material("red").set("orbit", Raw(orbit)),
    ])
}

/// Where the ball's centre is at time `t`, in closed form.
fn ball_at(t: f32) -> Vec3 {
    CENTER + Quat::from_rotation_z(std::f32::consts::TAU * t / PERIOD) * (START - CENTER)
}

/// Continuous pixel coordinates (pixel (x, y) covers [x, x + 1) x [y, y + 1))
/// of a world point, with the renderer's view-projection.
fn project(cam: &Camera, p: Vec3) -> Vec2 {
    let clip = cam.projection(W as f32 / H as f32) * cam.view().as_mat4() * p.extend(1.0);
    let ndc = Vec2::new(clip.x, clip.y) / clip.w;
    (ndc + 1.0) * 0.5 * Vec2::new(W as f32, H as f32)
}

/// Nearest positive hit distance of a ray (unit `d`) with a sphere.
fn hit_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> Option<f32> {
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    let t = -b - disc.max(0.0).sqrt();
    (disc >= 0.0 && t > 0.0).then_some(t)
}

/// What the camera ray through a pixel sees first, in closed form.
enum Seen {
    Ball,
    /// The mirror, and whether the reflected ray hits the ball.
    Mirror {
        shows_ball: bool,
    },
    /// The floor, and whether that point is in the ball's shadow (the sun is
    /// straight overhead, so the shadow is the disk under the ball).
    Floor {
        shadowed: bool,
    },
    Nothing,
}

fn seen(cam: &Camera, x: u32, y: u32, ball: Vec3) -> Seen {
    let (o, d) = common::pixel_ray(cam, W, H, x, y);
    if hit_sphere(o, d, ball, BALL_RADIUS).is_some() {
        return Seen::Ball;
    }
    if d.z < 0.0 {
        let m = o + d * (-o.z / d.z);
        if m.x.abs() <= MIRROR_HALF_WIDTH && (FLOOR_Y..=MIRROR_TOP).contains(&m.y) {
            let r = Vec3::new(d.x, d.y, -d.z);
            return Seen::Mirror { shows_ball: hit_sphere(m, r, ball, BALL_RADIUS).is_some() };
        }
    }
    if d.y < 0.0 {
        let g = o + d * ((FLOOR_Y - o.y) / d.y);
        if g.x.abs() <= 4.0 && (0.0..=8.0).contains(&g.z) {
            let shadowed = Vec2::new(g.x - ball.x, g.z - ball.z).length() < BALL_RADIUS;
            return Seen::Floor { shadowed };
        }
    }
    Seen::Nothing
}

/// Pixel count and centroid (pixel centres) of a set of pixels.
#[derive(Default, Debug)]
struct Blob {
    count: u32,
    sum: Vec2,
}

impl Blob {
    fn add(&mut self, x: u32, y: u32) {
        self.count += 1;
        self.sum += Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    }
    fn centroid(&self) -> Vec2 {
        self.sum / self.count.max(1) as f32
    }
}

/// Rendered vs predicted blobs of one frame.
#[derive(Default, Debug)]
struct Blobs {
    /// Red pixels where the camera sees the ball / the mirror, and red ones
    /// anywhere else.
    direct: Blob,
    reflection: Blob,
    stray_red: u32,
    /// Dark pixels of the directly seen floor.
    shadow: Blob,
    /// The same, predicted.
    direct_expected: Blob,
    reflection_expected: Blob,
    shadow_expected: Blob,
}

fn blobs(frame: &FrameOutput, cam: &Camera, ball: Vec3) -> Blobs {
    let mut b = Blobs::default();
    for y in 0..H {
        for x in 0..W {
            let l = frame.radiance(x, y);
            let red = l[0] > 1.0 && l[1] < 0.2 * l[0] && l[2] < 0.2 * l[0];
            match seen(cam, x, y, ball) {
                Seen::Ball => {
                    b.direct_expected.add(x, y);
                    if red {
                        b.direct.add(x, y);
                    }
                }
                Seen::Mirror { shows_ball } => {
                    if shows_ball {
                        b.reflection_expected.add(x, y);
                    }
                    if red {
                        b.reflection.add(x, y);
                    }
                }
                Seen::Floor { shadowed } => {
                    if shadowed {
                        b.shadow_expected.add(x, y);
                    }
                    if l[1] < 0.3 * FLOOR_LIT {
                        b.shadow.add(x, y);
                    }
                    b.stray_red += red as u32;
                }
                Seen::Nothing => b.stray_red += red as u32,
            }
        }
    }
    b
}

/// Checks one blob: centroid within the tolerance of `expected`, and about
/// as many pixels as predicted. Returns the centroid error in pixels.
fn check_blob(what: &str, got: &Blob, predicted: &Blob, expected: Vec2) -> f32 {
    assert!(predicted.count >= 8, "{what}: the set-up predicts only {} pixels", predicted.count);
    let ratio = got.count as f32 / predicted.count as f32;
    assert!(
        (0.75..=1.33).contains(&ratio),
        "{what}: {} pixels rendered, {} predicted (centroid {} vs {expected})",
        got.count,
        predicted.count,
        got.centroid()
    );
    let error = got.centroid().distance(expected);
    assert!(error <= TOLERANCE_PX, "{what}: centroid {} is {error:.2} px from {expected}", got.centroid());
    error
}

#[test]
fn orbiting_ball_reflection_and_shadow_follow_the_orbit() {
    let mut scene = common::scene_from_toml("orbit_mirror", &scene_text());
    let anim = find_animation(&scene, SCENE_ANIMATION).unwrap();
    assert_eq!(scene.animations[anim].duration, PERIOD);
    let cam = scene.cameras[0].clone();
    let times = [0.0, 0.25 * PERIOD, 0.5 * PERIOD];

    // The closed-form positions move far more than the tolerance between
    // frames, so a reflection or shadow stuck at the previous pose fails.
    let mirror_image = |t: f32| project(&cam, ball_at(t) * Vec3::new(1.0, 1.0, -1.0));
    for w in times.windows(2) {
        let moved = mirror_image(w[0]).distance(mirror_image(w[1]));
        assert!(moved > 10.0 * TOLERANCE_PX, "the mirror image moves only {moved} px");
    }

    let extent = ash::vk::Extent2D { width: W, height: H };
    for backend in [Backend::Query, Backend::Pipeline, Backend::Compute] {
        let settings = RenderSettings { backend, ..Default::default() };
        let ctx = common::validated_context();
        scene.animate(anim, times[0]);
        let mut renderer = Renderer::new(&ctx, &scene, extent).unwrap();
        for (i, &t) in times.iter().enumerate() {
            if i > 0 {
                scene.animate(anim, t);
                renderer.update_scene(&ctx, &scene).unwrap();
            }
            let ball = ball_at(t);
            let placed = scene.instances.iter().find(|inst| inst.object == 2).unwrap().world;
            assert!(
                placed.w_axis.truncate().as_vec3().distance(ball) < 1e-4,
                "t = {t}: the ball is not on its orbit"
            );

            let frame = renderer.render(&ctx, &scene, &cam, &settings).unwrap();
            assert!(frame.all_finite(), "{backend:?} t = {t}: NaN or Inf");
            let name = format!("orbit_{backend:?}_t{t}");
            frame.save_png(&common::out_dir().join(format!("{name}.png"))).unwrap();
            let b = blobs(&frame, &cam, ball);
            let what = |part: &str| format!("{backend:?} t = {t} s: {part}");

            let direct = check_blob(&what("ball"), &b.direct, &b.direct_expected, project(&cam, ball));
            // The mirror image of the ball is the ball reflected across z = 0.
            let mirrored = ball * Vec3::new(1.0, 1.0, -1.0);
            let reflection = check_blob(
                &what("reflection"),
                &b.reflection,
                &b.reflection_expected,
                project(&cam, mirrored),
            );
            // The shadow disk's image is not a projected circle's centre:
            // compare with the centroid of the predicted shadow pixels.
            let shadow_expected = b.shadow_expected.centroid();
            let shadow = check_blob(&what("shadow"), &b.shadow, &b.shadow_expected, shadow_expected);
            assert!(
                b.stray_red <= 2,
                "{backend:?} t = {t} s: {} red pixels off ball and mirror",
                b.stray_red
            );
            eprintln!(
                "{backend:?} t = {t:.1} s: centroid error ball {direct:.2} px ({} px), reflection \
                 {reflection:.2} px ({} px), shadow {shadow:.2} px ({} px)",
                b.direct.count, b.reflection.count, b.shadow.count
            );
        }
        renderer.destroy(&ctx);
        common::assert_validation_clean(&ctx);
    }
}

/// The shipped animated Sponza scene (spheres orbiting the courtyard) at
/// t = 2 s, a quarter turn, against a committed reference (UPDATE_GOLDEN=1
/// rewrites it, never under CI) with the per-pixel tolerance of
/// `common::check_golden`: a re-render is bit-identical on lavapipe.
#[test]
fn animated_sponza_matches_reference() {
    let mut scene = Scene::load(&common::repo_path("assets/sponza_animated.toml")).unwrap();
    let anim = find_animation(&scene, SCENE_ANIMATION).unwrap();
    scene.animate(anim, 2.0);
    // The golden pins the shading before anti-aliasing.
    let settings = RenderSettings { aa: AaMode::None, ..Default::default() };
    let frame = common::render_scene(&scene, 320, 180, &settings);
    common::check_golden(&frame, "sponza_animated_t2_320x180");
}
