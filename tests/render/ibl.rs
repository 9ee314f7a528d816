//! Image-based lighting (gpu/env_sh.rs, glsl/common/env.glsl): the ambient
//! term is the environment's SH irradiance at the surface normal.
//!
//! - A map lit only around +X lights a +X-facing wall and not a -X-facing
//!   one; rotations move the light to the axis R_y(r) says (+90: -Z, -90:
//!   +Z, 180: -X). Catches a mirrored basis, map or rotation. Hybrid on the
//!   raster path and pure RT (the integrator's path) on every backend.
//! - A constant map: --ambient sh and --ambient constant give the same image
//!   within 1/255.
//! - Sun maps (venice_sunset, studio_small_03): no negative irradiance after
//!   the Hann window (the coefficients the frame uploads, at 20k normals;
//!   the shader clamps at 0, so the GPU image alone could not tell), and
//!   the frames they light are non-negative and finite.
use crate::common;

use common::toml::*;

use std::path::Path;

use ash::vk::Extent2D;
use glam::{Quat, Vec3, Vec4};
use hybrid_rt::app::{EnvOverrides, ViewArgs};
use hybrid_rt::gpu::env_sh::{irradiance_uniform, project_environment};
use hybrid_rt::render::shading::Mode;
use hybrid_rt::render::{AmbientMode, FrameOutput, RenderSettings, Renderer};
use hybrid_rt::scene::sh::{eval_basis, fibonacci_sphere};
use hybrid_rt::scene::{Camera, EnvLayout, Environment, Scene};

const W: u32 = 96;
const H: u32 = 54;

/// Four walls facing the centre (normals +X, -X, +Z, -Z), a sphere in the
/// middle, camera 0 at +Z looking at -Z and camera 1 the other way. No
/// light, and white is pure Lambert (IOR 1: no specular lobe, whose split-sum
/// albedo depends on the view): the frame is the diffuse ambient alone.
fn box_toml() -> String {
    let wall = |name, at, rot| plane(name, [4.0, 4.0]).at(at).rot(rot).material("white");
    scene_toml([
        camera([0.0, 0.0, 1.5], [0.0, 0.0, -2.0]).yfov(90),
        camera([0.0, 0.0, -1.5], [0.0, 0.0, 2.0]).yfov(90),
        no_light(),
        lambert("white", [0.8, 0.8, 0.8]).ior(1.0),
        wall("faces +X", [-2.0, 0.0, 0.0], [0.0, 0.0, -90.0]),
        wall("faces -X", [2.0, 0.0, 0.0], [0.0, 0.0, 90.0]),
        wall("faces +Z", [0.0, 0.0, -2.0], [90.0, 0.0, 0.0]),
        wall("faces -Z", [0.0, 0.0, 2.0], [-90.0, 0.0, 0.0]),
        sphere("ball", 0.4).material("white"),
    ])
}

/// The box scene lit by the map at `map` (an equirect .hdr).
fn box_scene(name: &str, map: &Path) -> Scene {
    let mut scene = common::scene_from_toml(name, &box_toml());
    EnvOverrides { map: Some((map.to_path_buf(), EnvLayout::Equirect)), ..Default::default() }
        .apply(&mut scene)
        .unwrap();
    scene
}

/// A map of radiance 1 within 60 degrees of +X, 0 elsewhere.
fn plus_x_map() -> std::path::PathBuf {
    let (w, h) = (128, 64);
    common::write_hdr("ibl_plus_x", w, h, |x, y| {
        let d = hybrid_rt::scene::sh::texel_dir(x, y, w, h, 0.0);
        if d.x > 0.5 {
            [1.0; 3]
        } else {
            [0.0; 3]
        }
    })
}

/// The pixel a world point projects to (the inverse of common::pixel_ray).
fn pixel_of(cam: &Camera, p: Vec3) -> (u32, u32) {
    let clip = cam.projection(W as f32 / H as f32) * cam.view().as_mat4() * Vec4::new(p.x, p.y, p.z, 1.0);
    let (nx, ny) = (clip.x / clip.w, clip.y / clip.w);
    (((nx + 1.0) * 0.5 * W as f32) as u32, ((ny + 1.0) * 0.5 * H as f32) as u32)
}

/// Mean linear red radiance of a 3x3 block around the point `p`.
fn radiance_at(frame: &FrameOutput, cam: &Camera, p: Vec3) -> f32 {
    let (x, y) = pixel_of(cam, p);
    let mut s = 0.0;
    for dy in 0..3 {
        for dx in 0..3 {
            let (px, py) = (x + dx - 1, y + dy - 1);
            s += frame.hdr[((py * W + px) * 4) as usize];
        }
    }
    s / 9.0
}

/// One renderer, many frames: the environment's rotation is read per frame.
struct Bench {
    ctx: common::ValidatedContext,
    renderer: Renderer,
}

impl Bench {
    fn new(scene: &Scene) -> Bench {
        let ctx = common::validated_context();
        let renderer = Renderer::new(&ctx, scene, Extent2D { width: W, height: H }).unwrap();
        Bench { ctx, renderer }
    }

    fn render(&mut self, scene: &Scene, camera: usize, settings: &RenderSettings) -> FrameOutput {
        let out = self.renderer.render(&self.ctx, scene, &scene.cameras[camera], settings).unwrap();
        assert!(out.all_finite(), "NaN or Inf reached the frame");
        out
    }

    fn finish(mut self) {
        self.renderer.destroy(&self.ctx);
        drop(self.ctx); // validation errors, teardown included, fail here
    }
}

/// The wall centres' radiance (+X, -X, +Z, -Z facing): the first three
/// seen from camera 0, the -Z-facing wall from camera 1 (points part way
/// along the side walls, where both cameras see them).
fn walls(b: &mut Bench, scene: &Scene, settings: &RenderSettings) -> [f32; 4] {
    let f0 = b.render(scene, 0, settings);
    let f1 = b.render(scene, 1, settings);
    let (c0, c1) = (&scene.cameras[0], &scene.cameras[1]);
    [
        radiance_at(&f0, c0, Vec3::new(-2.0, 0.3, -1.0)),
        radiance_at(&f0, c0, Vec3::new(2.0, 0.3, -1.0)),
        radiance_at(&f0, c0, Vec3::new(0.0, 1.2, -2.0)),
        radiance_at(&f1, c1, Vec3::new(0.0, 1.2, 2.0)),
    ]
}

/// The lit wall for each rotation: +X at 0, -Z at +90 (R_y(90) takes +X to
/// -Z), +Z at -90, -X at 180. The lit wall gets more than twice the light
/// of every other (3-band Hann irradiance of a 60-degree cap: E(axis) /
/// E(side) = 2.38, E(opposite) = 0 after the clamp), on every path.
#[test]
fn light_from_plus_x_lights_the_wall_facing_it_and_rotations_move_it() {
    let mut scene = box_scene("ibl_plus_x", &plus_x_map());
    let mut b = Bench::new(&scene);
    // The unshadowed SH irradiance is what this checks (the traced visibility's walls shade each other).
    let sh = RenderSettings { ambient: AmbientMode::Sh, ..Default::default() };
    let mut variants = vec![("hybrid".to_string(), sh)];
    for backend in common::BACKENDS {
        let s = RenderSettings { mode: Mode::Rt, backend, ..sh };
        variants.push((format!("rt {backend:?}"), s));
    }
    // (rotation in degrees, index of the lit wall in `walls`, the wall opposite it)
    for (deg, lit, opposite) in [(0.0f32, 0, 1), (90.0, 3, 2), (-90.0, 2, 3), (180.0, 1, 0)] {
        scene.environment.rotation = deg.to_radians();
        let mut hybrid = None;
        for (name, settings) in &variants {
            let e = walls(&mut b, &scene, settings);
            println!("rotation {deg}: {name}: walls +X -X +Z -Z {e:?}");
            for (i, v) in e.iter().enumerate() {
                if i != lit {
                    assert!(
                        e[lit] > 2.0 * v,
                        "rotation {deg}, {name}: wall {i} ({v}) vs lit wall {lit}: {e:?}"
                    );
                }
            }
            assert!(e[lit] > 8.0 * e[opposite], "rotation {deg}, {name}: {e:?}");
            // Pure RT shades the same normals with the same SH: equal to
            // the raster path within 1%.
            let h = *hybrid.get_or_insert(e);
            for i in 0..4 {
                assert!(
                    (e[i] - h[i]).abs() <= 0.01 * h[lit],
                    "rotation {deg}, {name} vs hybrid: {e:?} vs {h:?}"
                );
            }
        }
    }
    // The constant ambient sees no direction: every wall alike.
    scene.environment.rotation = 0.0;
    let e = walls(&mut b, &scene, &RenderSettings { ambient: AmbientMode::Constant, ..Default::default() });
    assert!(e.iter().all(|v| (v - e[0]).abs() < 1e-3 * e[0]), "--ambient constant: {e:?}");
    b.finish();
}

/// A constant map: E(n) = pi L for every n, so the SH ambient equals the
/// constant one (the map's mean) within 1/255 on the default scene (lights,
/// mirrors and glass included), hybrid and pure RT.
#[test]
fn constant_map_gives_the_same_image_with_sh_and_constant_ambient() {
    let map = common::write_hdr("ibl_constant", 64, 32, |_, _| [0.6, 0.45, 0.3]);
    let mut scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), rotation_deg: Some(37.0), intensity: Some(1.3) }
        .apply(&mut scene)
        .unwrap();
    let mut b = Bench::new(&scene);
    for mode in [Mode::Hybrid, Mode::Rt] {
        let sh =
            b.render(&scene, 0, &RenderSettings { mode, ambient: AmbientMode::Sh, ..Default::default() });
        let constant = b.render(
            &scene,
            0,
            &RenderSettings { mode, ambient: AmbientMode::Constant, ..Default::default() },
        );
        let worst = sh.ldr.iter().zip(&constant.ldr).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
        println!("{mode:?}: largest LDR difference {worst}/255");
        assert!(worst <= 1, "{mode:?}: --ambient sh and constant differ by {worst}/255");
        // And the lit image is not black (the comparison compares something).
        assert!(sh.ldr.chunks_exact(4).filter(|p| p[0] > 40).count() > (W * H / 2) as usize);
    }
    b.finish();
}

/// `--env-rotation` and `--env-intensity` as the command line parses them
/// (the `render` subcommand's view options), with `--env map`.
fn env_flags(map: &Path, flags: &[&str]) -> EnvOverrides {
    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        view: ViewArgs,
    }
    let args = ["render", "--env", map.to_str().unwrap()].into_iter().chain(flags.iter().copied());
    let cli = <Cli as clap::Parser>::try_parse_from(args).unwrap_or_else(|e| panic!("{flags:?}: {e}"));
    cli.view.job().unwrap().env
}

/// A map whose colour encodes its azimuth phi = atan2(d.x, -d.z), by the
/// equirect convention (env.glsl: u = 0.5 looks down -Z, u grows towards
/// +X): column x is phi = 2 pi ((x + 0.5) / w - 0.5), and its radiance
/// (1 + cos(phi) / 2, 1 + sin(phi) / 2, 1) gives phi back.
fn azimuth_map() -> std::path::PathBuf {
    let (w, h) = (256, 128);
    common::write_hdr("ibl_azimuth", w, h, |x, _| {
        let phi = std::f32::consts::TAU * ((x as f32 + 0.5) / w as f32 - 0.5);
        [1.0 + 0.5 * phi.cos(), 1.0 + 0.5 * phi.sin(), 1.0]
    })
}

/// The signed difference of two angles (radians), in (-pi, pi].
fn angle_between(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::TAU);
    if d > std::f32::consts::PI {
        d - std::f32::consts::TAU
    } else {
        d
    }
}

/// The camera looks down -Z at the sky, a white ball below the centre lit
/// by it alone (no light). Turning the map by R_y(r) (`--env-rotation r`;
/// R_y(90) takes +X to -Z, as the walls above show) puts at the sky pixel
/// of direction d what the unturned map has at R_y(-r) d: the azimuth the
/// pixel's colour encodes is that of R_y(-r) d, to within 3 degrees
/// (measured: 1.1; the map's 8-bit RGBE mantissa alone allows 0.7).
/// Ignoring the flag is off by r, turning the wrong way by 2r. `--env-intensity k` multiplies every
/// pixel's linear radiance, sky and ball, by k (both are the map's radiance
/// times it; float rounding only). Hybrid (raster misses) and pure RT.
#[test]
fn env_rotation_turns_the_sky_and_env_intensity_scales_the_radiance() {
    let map = azimuth_map();
    let toml = scene_toml([
        camera([0.0; 3], [0.0, 0.0, -1.0]).yfov(60),
        no_light(),
        lambert("white", [0.8, 0.8, 0.8]),
        sphere("ball", 0.5).at([0.0, -1.2, -4.0]).material("white"),
    ]);
    let mut scene = common::scene_from_toml("ibl_azimuth", &toml);
    // As `render` does: the scene as loaded, then the flags.
    let loaded = scene.environment.clone();
    let flags = |scene: &mut Scene, args: &[&str]| {
        scene.environment = loaded.clone();
        env_flags(&map, args).apply(scene).unwrap();
    };
    flags(&mut scene, &[]);
    let cam = scene.cameras[0].clone();
    // Sky pixels: their ray passes the ball with a margin for its tessellation.
    let centre = Vec3::new(0.0, -1.2, -4.0);
    let (mut sky, mut ball) = (Vec::new(), 0);
    for y in 0..H {
        for x in 0..W {
            let (o, d) = common::pixel_ray(&cam, W, H, x, y);
            let miss = (o + d * (centre - o).dot(d) - centre).length();
            if miss > 0.6 {
                sky.push((x, y, d));
            } else if miss < 0.4 {
                ball += 1;
            }
        }
    }
    assert!(sky.len() > (W * H * 3 / 4) as usize && ball > 20, "{} sky, {ball} ball pixels", sky.len());
    let mut b = Bench::new(&scene);
    for (name, mode) in [("hybrid", Mode::Hybrid), ("rt", Mode::Rt)] {
        let settings = RenderSettings { mode, ..Default::default() };
        for deg in [0.0f32, 37.0, -90.0, 180.0] {
            flags(&mut scene, &["--env-rotation", &deg.to_string()]);
            let f = b.render(&scene, 0, &settings);
            let (mut worst, mut at) = (0.0f32, (0, 0));
            for &(x, y, d) in &sky {
                let [r, g, _] = f.radiance(x, y);
                let seen = (g - 1.0).atan2(r - 1.0);
                let e = Quat::from_rotation_y(-deg.to_radians()) * d;
                let err = angle_between(seen, e.x.atan2(-e.z)).abs().to_degrees();
                if err > worst {
                    (worst, at) = (err, (x, y));
                }
            }
            println!("{name}, --env-rotation {deg}: sky azimuth off by at most {worst:.2} degrees");
            assert!(
                worst <= 3.0,
                "{name}, --env-rotation {deg}: pixel {at:?} shows the sky {worst:.1} degrees from where the \
                 rotation puts it"
            );
        }
        flags(&mut scene, &["--env-rotation", "37"]);
        let one = b.render(&scene, 0, &settings);
        let k = 2.5;
        flags(&mut scene, &["--env-rotation", "37", "--env-intensity", &k.to_string()]);
        let scaled = b.render(&scene, 0, &settings);
        let mut worst = 0.0f32;
        for (a, s) in one.hdr.chunks_exact(4).zip(scaled.hdr.chunks_exact(4)) {
            for c in 0..3 {
                worst = worst.max((s[c] - k * a[c]).abs() / (k * a[c]).max(1e-3));
            }
        }
        println!("{name}, --env-intensity {k}: radiance off k times by at most {:.5}%", worst * 100.0);
        // 0.2%: float rounding (measured: 3e-5 %), far below the 60% of a
        // flag ignored.
        assert!(
            worst <= 2e-3,
            "{name}, --env-intensity {k}: radiance off k times the radiance at 1 by {:.3}%",
            worst * 100.0
        );
    }
    b.finish();
}

/// Sun maps through the Hann window: the ambient radiance stays >= 0 at
/// every normal (the uploaded coefficients, evaluated like env.glsl), and
/// the frames (a sphere and four walls, both cameras) are >= 0;
/// studio_small_03 goes to -0.17 unwindowed (scene/sh/window.rs).
#[test]
fn sun_maps_give_no_negative_radiance() {
    for name in ["venice_sunset_1k", "studio_small_03_1k"] {
        let map = common::shared_asset(&format!("hdri/polyhaven_1k/{name}.hdr"));
        let scene = box_scene(&format!("ibl_{name}"), &map);
        let sh = project_environment(scene.environment.map.as_ref().unwrap()).unwrap();
        for deg in [0.0f32, 73.0] {
            let env = Environment { rotation: deg.to_radians(), ..scene.environment.clone() };
            let u = irradiance_uniform(&sh, &env, false);
            let mut min = f64::MAX;
            for n in fibonacci_sphere(20_000) {
                let mut y = [0.0; 9];
                eval_basis(3, n, &mut y);
                for k in 0..3 {
                    min = min.min(u.iter().zip(y).map(|(c, yi)| c[k] as f64 * yi).sum::<f64>());
                }
            }
            println!("{name}, rotation {deg}: smallest irradiance {min}");
            assert!(min >= 0.0, "{name}, rotation {deg}: irradiance {min} < 0 at some normal");
        }
        let mut b = Bench::new(&scene);
        for camera in [0, 1] {
            let f = b.render(&scene, camera, &RenderSettings::default());
            let min = f.hdr.chunks_exact(4).flat_map(|p| &p[..3]).fold(f32::MAX, |m, v| m.min(*v));
            println!("{name}, camera {camera}: smallest radiance {min}");
            assert!(min >= 0.0, "{name}, camera {camera}: negative radiance {min}");
        }
        b.finish();
    }
}

/// The environment flags: bad values are usage errors naming the flag (exit
/// 2, nothing written), a bad map an error naming --env and the file (exit
/// 1), an angular probe must be square; good ones render.
#[test]
fn environment_flags() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ibl_cli");
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.png");
    let square = common::write_hdr("ibl_probe_square", 32, 32, |x, _| [x as f32 / 32.0, 0.5, 0.25]);
    let wide = plus_x_map();
    let usage: [(&[&str], &str); 4] = [
        (&["--env-rotation", "nan"], "--env-rotation"),
        (&["--env-intensity", "-1"], "--env-intensity"),
        (&["--env-layout", "angular"], "--env"),
        (&["--ambient", "sometimes"], "--ambient"),
    ];
    for (args, flag) in usage {
        let _ = std::fs::remove_file(&out);
        let o = common::tiny_render_cmd().args(args).arg("--out").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(flag), "{args:?}: does not name {flag}: {stderr}");
        assert!(!out.exists(), "{args:?}: wrote an image");
    }
    let missing = dir.join("missing.hdr");
    let failing: [(Vec<std::ffi::OsString>, Vec<String>); 2] = [
        (vec!["--env".into(), missing.clone().into()], vec!["--env".into(), missing.display().to_string()]),
        (
            vec!["--env".into(), wide.clone().into(), "--env-layout".into(), "angular".into()],
            vec![wide.display().to_string(), "square".into()],
        ),
    ];
    for (args, needles) in failing {
        let o = common::tiny_render_cmd().args(&args).arg("--out").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        let line = stderr.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("{stderr}"));
        for n in needles {
            assert!(line.contains(&n), "{args:?}: error does not mention '{n}': {line}");
        }
    }
    for args in [
        vec!["--env".into(), square.into_os_string(), "--env-layout".into(), "angular".into()],
        vec!["--env".into(), wide.into_os_string(), "--env-rotation".into(), "-45".into()],
        vec!["--env-intensity".into(), "2".into(), "--ambient".into(), "constant".into()],
    ] {
        let _ = std::fs::remove_file(&out);
        let o = common::tiny_render_cmd().args(&args).arg("--out").arg(&out).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(out.exists(), "{args:?}: no image");
    }
}
