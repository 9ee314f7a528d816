//! Diffuse PRT end to end (src/prt, glsl/common/prt.glsl):
//! - a constant environment: `--ambient prt-unshadowed` renders the same
//!   image as `--ambient sh` within 1/255 (they are the same integral);
//! - a plane under a sphere of radius r at height d, constant radiance L:
//!   the rendered ambient at the point below the centre matches
//!   pi L (1 - (r/d)^2) (the CPU transfer's tolerance) and the CPU
//!   transfer interpolated at the pixel's hit (f32);
//! - PRT shadowed agrees with the ray-traced reference under the sphere;
//! - a second renderer loads the transfer from the cache;
//! - bad flags are named in the error.
use crate::common;

use common::scenes::plane_under_sphere;
use common::toml::environment;

use std::path::PathBuf;
use std::process::Command;

use glam::{Vec3, Vec4};
use hybrid_rt::app::EnvOverrides;
use hybrid_rt::prt::{self, CacheOutcome, PrtCache, PrtMode, PrtSettings};
use hybrid_rt::render::{AmbientMode, FrameOutput, PrtOptions, ReferenceSettings, RenderSettings, Renderer};
use hybrid_rt::scene::sh::ShCoeffs;
use hybrid_rt::scene::{Aabb, Camera, EnvLayout, Scene};

const W: u32 = 64;
const H: u32 = 36;
const R: f32 = 1.0;
const D: f32 = 2.0;
const SAMPLES: u32 = 64;

fn cache_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("prt-cache");
    std::env::set_var(prt::CACHE_DIR_ENV, &d);
    d
}

/// The plane under a sphere (tests/common/scenes.rs), its floor subdivided
/// into a 21×21 vertex grid so the origin is a vertex, lit by a constant
/// map of radiance 1.
fn scene() -> Scene {
    let mut scene = common::scene_from_toml("prt_plane_sphere", &plane_under_sphere());
    let floor =
        scene.meshes.iter_mut().flat_map(|m| &mut m.primitives).find(|p| p.vertices.len() == 4).unwrap();
    let v0 = floor.vertices[0];
    let n = 21u32;
    let mut vertices = Vec::new();
    let mut bounds = Aabb::EMPTY;
    for z in 0..n {
        for x in 0..n {
            let mut v = v0;
            v.position =
                [-2.0 + 4.0 * x as f32 / (n - 1) as f32, 0.0, -2.0 + 4.0 * z as f32 / (n - 1) as f32];
            v.normal = [0.0, 1.0, 0.0];
            bounds.grow(Vec3::from(v.position));
            vertices.push(v);
        }
    }
    let mut indices = Vec::new();
    for z in 0..n - 1 {
        for x in 0..n - 1 {
            let a = z * n + x;
            indices.extend_from_slice(&[a, a + n, a + 1, a + 1, a + n, a + n + 1]);
        }
    }
    (floor.vertices, floor.indices, floor.bounds) = (vertices, indices, bounds);
    scene.update_world();
    let map = common::write_hdr("prt_constant", 32, 16, |_, _| [1.0; 3]);
    EnvOverrides { map: Some((map, EnvLayout::Equirect)), ..Default::default() }.apply(&mut scene).unwrap();
    scene
}

fn settings(ambient: AmbientMode) -> RenderSettings {
    RenderSettings {
        ambient,
        prt: PrtOptions { samples: SAMPLES, ..Default::default() },
        ..Default::default()
    }
}

/// The pixel a world point projects to.
fn pixel_of(cam: &Camera, p: Vec3) -> (u32, u32) {
    let clip = cam.projection(W as f32 / H as f32) * cam.view().as_mat4() * Vec4::new(p.x, p.y, p.z, 1.0);
    let (nx, ny) = (clip.x / clip.w, clip.y / clip.w);
    (((nx + 1.0) * 0.5 * W as f32) as u32, ((ny + 1.0) * 0.5 * H as f32) as u32)
}

fn red_at(f: &FrameOutput, (x, y): (u32, u32)) -> f32 {
    f.hdr[((y * W + x) * 4) as usize]
}

/// The white floor's radiance over E / pi: its albedo (pure Lambert, IOR 1).
const AMBIENT_FACTOR: f64 = 0.8;

#[test]
fn prt_renders_match_sh_and_the_occluded_plane() {
    cache_dir();
    let scene = scene();
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let cam = &scene.cameras[0];
    let sh = r.render(&ctx, &scene, cam, &settings(AmbientMode::Sh)).unwrap();
    let un = r.render(&ctx, &scene, cam, &settings(AmbientMode::PrtUnshadowed)).unwrap();
    let shadowed = r.render(&ctx, &scene, cam, &settings(AmbientMode::PrtShadowed)).unwrap();
    // 5 bands: 25 coefficients a vertex in the buffer and the uniform.
    let mut five = settings(AmbientMode::PrtUnshadowed);
    five.prt.bands = 5;
    let un5 = r.render(&ctx, &scene, cam, &five).unwrap();
    r.destroy(&ctx);
    drop(ctx);

    // Unshadowed = SH irradiance under a constant map, every pixel.
    let worst = sh.hdr.iter().zip(&un.hdr).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst < 1.0 / 255.0, "prt-unshadowed vs sh: largest difference {worst}");
    let worst = sh.hdr.iter().zip(&un5.hdr).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(worst < 1.0 / 255.0, "5-band prt-unshadowed vs sh: largest difference {worst}");

    // The point under the sphere, against the closed form with the CPU
    // test's tolerance (4 sigma plain MC over SAMPLES² directions, plus the
    // 32×16 sphere's faces between r cos²(pi/32) and r from its centre).
    let px = pixel_of(cam, Vec3::ZERO);
    let got = red_at(&shadowed, px) as f64 / AMBIENT_FACTOR;
    let s = (R / D) as f64;
    let pi = std::f64::consts::PI;
    let want = 1.0 - s * s; // E / (pi L), L = 1
    let cos_c = (1.0 - s * s).sqrt();
    let var = 8.0 * pi * pi * cos_c.powi(3) / 3.0 - (pi * want).powi(2);
    let tol = (4.0 * var.sqrt() / SAMPLES as f64 + pi * s * s * (1.0 - (pi / 32.0).cos().powi(4))) / pi;
    assert!((got - want).abs() <= tol, "rendered E/(pi L) {got} vs 1 - (r/d)^2 = {want} (tolerance {tol})");
    // Against the CPU transfer interpolated at the pixel's hit on the floor
    // as the shader does (the floor's two triangles per grid cell): f32.
    let cpu = PrtCache::new(None)
        .get(&scene, &PrtSettings { samples: SAMPLES, ..PrtSettings::new(PrtMode::Shadowed) })
        .unwrap()
        .0;
    let floor = cpu.first_vertex.iter().flatten().copied().min().unwrap() as usize;
    let mut l = vec![[0.0; 3]; 9];
    l[0] = [(4.0 * pi).sqrt(); 3];
    let env = ShCoeffs::from_coeffs(3, l).unwrap();
    let (o, d) = common::pixel_ray(cam, W, H, px.0, px.1);
    let hit = o - d * (o.y / d.y);
    let n = 21usize;
    let (gx, gz) = ((hit.x as f64 + 2.0) / 0.2, (hit.z as f64 + 2.0) / 0.2);
    let (ix, iz) = (gx.floor() as usize, gz.floor() as usize);
    let (fx, fz) = (gx - ix as f64, gz - iz as f64);
    let a = iz * n + ix;
    let tri = if fx + fz <= 1.0 {
        [(a, 1.0 - fx - fz), (a + n, fz), (a + 1, fx)]
    } else {
        [(a + 1, 1.0 - fz), (a + n, 1.0 - fx), (a + n + 1, fx + fz - 1.0)]
    };
    let e: f64 = tri.iter().map(|&(v, w)| w * cpu.irradiance(floor + v, &env)[0]).sum::<f64>() / pi;
    assert!((got - e).abs() < 2e-3 * e, "rendered {got} vs CPU transfer {e} at {hit}");
    // And the shadow shows: the shadowed frame is darker there than sh.
    assert!(red_at(&shadowed, px) < red_at(&sh, px) * 0.9);
}

/// PRT shadowed against the ray-traced reference (`--reference-samples`,
/// render/reference.rs) on the same scene: the mean of a 5×5 block of floor
/// pixels under the sphere agrees within 3%. The reference's noise there is
/// about 0.3% (1024 cosine samples a pixel, 25 pixels, visibility 3/4);
/// the rest is the PRT's per-vertex interpolation over the 0.2 grid.
#[test]
fn prt_shadowed_matches_the_ray_traced_reference() {
    cache_dir();
    let scene = scene();
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let cam = &scene.cameras[0];
    let prt = r.render(&ctx, &scene, cam, &settings(AmbientMode::PrtShadowed)).unwrap();
    let samples = 1024;
    let reference = RenderSettings {
        reference: Some(ReferenceSettings { samples, bounces: 1 }),
        ..settings(AmbientMode::Sh)
    };
    let mut traced = None;
    for _ in 0..samples / hybrid_rt::gpu::shared::REFERENCE_SAMPLES_PER_FRAME {
        traced = Some(r.render(&ctx, &scene, cam, &reference).unwrap());
    }
    let traced = traced.unwrap();
    r.destroy(&ctx);
    drop(ctx);
    let (cx, cy) = pixel_of(cam, Vec3::ZERO);
    let block = |f: &FrameOutput| {
        let mut sum = 0.0f64;
        for y in cy - 2..=cy + 2 {
            for x in cx - 2..=cx + 2 {
                sum += red_at(f, (x, y)) as f64;
            }
        }
        sum / 25.0
    };
    let (a, b) = (block(&prt), block(&traced));
    eprintln!("under the sphere, 5x5 mean: prt-shadowed {a:.4}, reference (N = {samples}) {b:.4}");
    assert!((a / b - 1.0).abs() < 0.03, "prt-shadowed {a} vs the ray-traced reference {b}");
}

/// A second renderer of the same scene and settings loads the transfer
/// (no recompute) and renders the same image.
#[test]
fn second_run_loads_from_cache() {
    let dir = cache_dir();
    let scene = scene();
    let s = PrtSettings { samples: 8, ..PrtSettings::new(PrtMode::Interreflected) };
    let cache = PrtCache::new(Some(dir));
    let _ = std::fs::remove_file(cache.path(prt_key(&scene, &s)).unwrap());
    let render = || {
        let ctx = common::validated_context();
        let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
        let mut st = settings(AmbientMode::PrtInterreflected);
        st.prt.samples = 8;
        let f = r.render(&ctx, &scene, &scene.cameras[0], &st).unwrap();
        let outcome = r.prt_outcome();
        r.destroy(&ctx);
        (f, outcome)
    };
    let (a, first) = render();
    assert_eq!(first, Some(CacheOutcome::Computed), "the first renderer found no cache file");
    assert!(cache.path(prt_key(&scene, &s)).unwrap().exists(), "no cache file written");
    let (b, second) = render();
    // The renderer itself loaded the file (not only a cache asked afterwards).
    assert_eq!(second, Some(CacheOutcome::Loaded), "the second renderer recomputed the transfer");
    assert_eq!(a.hdr, b.hdr);
}

fn prt_key(scene: &Scene, s: &PrtSettings) -> u64 {
    prt::cache_key(scene, s)
}

fn bin_err(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_hybrid-rt")).args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    assert_eq!(out.status.code(), Some(2), "{args:?}: usage errors exit 2");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn bad_prt_flags_are_named() {
    for cmd in ["render", "bench", "view"] {
        let e = bin_err(&[cmd, "--ambient", "prt-foo"]);
        assert!(e.contains("--ambient") && e.contains("prt-foo") && e.contains("prt-shadowed"), "{e}");
        let e = bin_err(&[cmd, "--prt-samples", "0"]);
        assert!(e.contains("--prt-samples") && e.contains('0'), "{e}");
        let e = bin_err(&[cmd, "--prt-bounces", "99"]);
        assert!(e.contains("--prt-bounces"), "{e}");
        let e = bin_err(&[cmd, "--prt-bands", "9"]);
        assert!(e.contains("--prt-bands"), "{e}");
    }
}

/// The precompute's visibility rays start where the shaders' would:
/// `prt::offset_origin` against offset.glsl's `offset_ray` (run on
/// the device through the shading probe), within one ULP of the result
/// (the shader compiler may fuse the multiply-add).
#[test]
fn host_offset_matches_the_shaders() {
    use common::probe::{run, Case};
    let normals = [[0.0f32, 1.0, 0.0], [0.577_350_3, -0.577_350_3, 0.577_350_3], [-0.267, 0.802, -0.534]];
    let points =
        [[0.0f32, 0.0, 0.0], [1e-3, -2e-3, 1e-4], [1.0, -2.0, 3.0], [1e5, -3e4, 1e5], [-1e6, 1e6, 2e6]];
    let extents = [0.0f32, 1e-6, 2e4];
    let mut cases = Vec::new();
    let mut host = Vec::new();
    for p in points {
        for n in normals {
            for e in extents {
                cases.push(Case::offset(p, n, e));
                host.push(prt::offset_origin(Vec3::from(p), Vec3::from(n), e));
            }
        }
    }
    for ((gpu, h), c) in run(&cases).iter().zip(&host).zip(&cases) {
        for i in 0..3 {
            let ulp = f32::from_bits(h[i].abs().to_bits() + 1) - h[i].abs();
            assert!((gpu[i] - h[i]).abs() <= ulp, "p {:?} n {:?}: shader {gpu:?}, host {h}", c.p, c.q);
        }
        assert_ne!(Vec3::new(gpu[0], gpu[1], gpu[2]), Vec3::new(c.p[0], c.p[1], c.p[2]));
    }
}

/// `[environment] ambient` in a scene file selects the mode when the
/// command line gives none (and not when it gives one); a bad name is an
/// error naming the file, line and the accepted names.
#[test]
fn scene_file_selects_the_ambient_mode() {
    cache_dir();
    let mut scene = scene();
    scene.environment.ambient = Some("prt-shadowed".into());
    let ctx = common::validated_context();
    let mut r = Renderer::new(&ctx, &scene, ash::vk::Extent2D { width: W, height: H }).unwrap();
    let cam = &scene.cameras[0];
    let explicit = r.render(&ctx, &scene, cam, &settings(AmbientMode::PrtShadowed)).unwrap();
    let from_scene = r
        .render(&ctx, &scene, cam, &RenderSettings { ambient_from_scene: true, ..settings(AmbientMode::Sh) })
        .unwrap();
    let cli_sh = r.render(&ctx, &scene, cam, &settings(AmbientMode::Sh)).unwrap();
    r.destroy(&ctx);
    drop(ctx);
    assert_eq!(explicit.hdr, from_scene.hdr);
    assert_ne!(explicit.hdr, cli_sh.hdr);

    let toml = environment([1.0, 1.0, 1.0]).set("ambient", "prt-foo").to_string() + &plane_under_sphere();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scenes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("prt_bad_ambient.toml");
    std::fs::write(&path, &toml).unwrap();
    let e = format!("{:#}", Scene::load(&path).unwrap_err());
    assert!(e.contains("prt_bad_ambient.toml") && e.contains("prt-foo") && e.contains("prt-shadowed"), "{e}");
    let ok = toml.replace("prt-foo", "prt-interreflected");
    std::fs::write(&path, ok).unwrap();
    assert_eq!(Scene::load(&path).unwrap().environment.ambient.as_deref(), Some("prt-interreflected"));
}
