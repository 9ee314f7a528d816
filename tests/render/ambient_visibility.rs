//! The traced ambient (`--ambient traced`, render/passes/ao.rs): the environment's diffuse light shadowed
//! by the geometry, and the one indirect bounce, against closed forms.
//!
//! - A floor under a ceiling with a square skylight, constant sky: each floor point's visible share is
//!   the form factor of the opening (point to parallel rectangle, inclusion-exclusion over its
//!   corners), so the floor's radiance is albedo x sky x that share. The frame's mean over the view
//!   within 4 % of the closed form's, each 8x8 block within 15 % (4 rays a pixel, filtered), where the
//!   unshadowed `sh` ambient is 4x too bright.
//! - A closed room under a bright sky: black inside with `traced` on every backend and both modes (every
//!   ray is blocked), lit with `sh` (the sky through the walls).
//! - A floor alone: nothing occludes, so `traced` equals `sh` within 1/255 (the ratio estimator adds no
//!   noise where nothing is blocked).
//! - The one indirect bounce: a ceiling over a wide emissive, then sunlit, floor exits its albedo times
//!   the floor's radiance within 2 %, and under a black sky nothing with `--no-indirect` but the
//!   emissive floor's light (direct light).
use crate::common;

use common::toml::*;

use hybrid_rt::render::shading::Mode;
use hybrid_rt::render::{AmbientMode, RenderSettings};

const ALBEDO: f32 = 0.8;
/// Ceiling height and the skylight's half side.
const H: f32 = 1.0;
const A: f32 = 0.5;
const SIZE: u32 = 64;

/// The skylight's form factor (its visible share of the cosine-weighted sky) at floor point (x, z).
fn skylight_share(x: f64, z: f64) -> f64 {
    let a = A as f64;
    common::rectangle_form_factor(H as f64, -a - x, a - x, -a - z, a - z)
}

fn skylight_toml() -> String {
    // Slabs 80 m across leave the sky under their outer edges at 1 / 1601 of the cosine-weighted share;
    // 2 mm thin, so the opening is one aperture (a thick one is a shaft whose top narrows the view).
    let slab = |name, at: [f32; 3], scale: [f32; 3]| cube(name, 1.0).at(at).scale(scale).material("white");
    let (y, w) = (H + 0.001, 40.0 - A);
    scene_toml([
        environment([1.0, 1.0, 1.0]),
        camera([0.0, 0.9, 0.0], [0.0, 0.0, 0.0]).up([0.0, 0.0, -1.0]).yfov(60),
        no_light(),
        lambert("white", [ALBEDO, ALBEDO, ALBEDO]).ior(1.0),
        plane("floor", 80.0).material("white"),
        slab("north", [0.0, y, 20.0 + A / 2.0], [80.0, 0.002, w]),
        slab("south", [0.0, y, -20.0 - A / 2.0], [80.0, 0.002, w]),
        slab("east", [20.0 + A / 2.0, y, 0.0], [w, 0.002, 2.0 * A]),
        slab("west", [-20.0 - A / 2.0, y, 0.0], [w, 0.002, 2.0 * A]),
    ])
}

#[test]
fn a_skylight_lights_the_floor_by_its_form_factor() {
    let scene = common::scene_from_toml("ao_skylight", &skylight_toml());
    let cam = &scene.cameras[0];
    let mut b = common::Bench::new(&scene, SIZE, SIZE);
    let traced = b.frame(&scene, cam, &RenderSettings::default());
    assert!(b.renderer.pass_names().contains(&"ao filter"), "{:?}", b.renderer.pass_names());
    let sh = b.frame(&scene, cam, &RenderSettings { ambient: AmbientMode::Sh, ..Default::default() });
    assert!(!b.renderer.pass_names().contains(&"ao"), "{:?}", b.renderer.pass_names());
    b.finish();
    let red =
        |f: &hybrid_rt::render::FrameOutput, x: u32, y: u32| f.hdr[((y * SIZE + x) * 4) as usize] as f64;
    let (mut got, mut want, mut open, mut square) = (0.0, 0.0, 0.0, 0.0);
    let mut worst_block: f64 = 0.0;
    for by in 0..SIZE / 8 {
        for bx in 0..SIZE / 8 {
            let (mut g, mut w) = (0.0, 0.0);
            for y in by * 8..by * 8 + 8 {
                for x in bx * 8..bx * 8 + 8 {
                    let (px, pz) = common::floor_point(cam, SIZE, SIZE, x, y);
                    let expected = ALBEDO as f64 * skylight_share(px, pz);
                    g += red(&traced, x, y);
                    w += expected;
                    square += (red(&traced, x, y) / expected - 1.0).powi(2);
                    open += red(&sh, x, y);
                }
            }
            worst_block = worst_block.max((g / w - 1.0).abs());
            got += g;
            want += w;
        }
    }
    let n = (SIZE * SIZE) as f64;
    let (got, want, open, rms) = (got / n, want / n, open / n, (square / n).sqrt());
    println!(
        "floor under a skylight: traced mean {got:.4}, closed form {want:.4} ({:+.2} %), per pixel {:.1} % rms, \
         worst 8x8 block {:.1} %; sh (unshadowed) {open:.4}",
        100.0 * (got / want - 1.0),
        100.0 * rms,
        100.0 * worst_block
    );
    assert!((got / want - 1.0).abs() < 0.04, "traced ambient {got} against the form factor's {want}");
    assert!(
        worst_block < 0.15,
        "an 8x8 block of the floor is {:.1} % off its form factor",
        100.0 * worst_block
    );
    // The check measures something: unshadowed, the floor sees the whole sky.
    assert!((open - ALBEDO as f64).abs() < 0.02 && open > 3.0 * want, "sh ambient {open}");
}

#[test]
fn a_closed_room_is_dark_inside_on_every_backend() {
    let wall = |name, at, rot| plane(name, [4.2, 4.2]).at(at).rot(rot).material("white");
    let toml = scene_toml([
        environment([20.0, 20.0, 20.0]),
        camera([0.0, 0.0, 1.5], [0.0, 0.0, -2.0]).yfov(90),
        no_light(),
        lambert("white", [ALBEDO, ALBEDO, ALBEDO]).ior(1.0),
        wall("faces +X", [-2.0, 0.0, 0.0], [0.0, 0.0, -90.0]),
        wall("faces -X", [2.0, 0.0, 0.0], [0.0, 0.0, 90.0]),
        wall("faces +Z", [0.0, 0.0, -2.0], [90.0, 0.0, 0.0]),
        wall("faces -Z", [0.0, 0.0, 2.0], [-90.0, 0.0, 0.0]),
        wall("floor", [0.0, -2.0, 0.0], [0.0, 0.0, 0.0]),
        wall("ceiling", [0.0, 2.0, 0.0], [180.0, 0.0, 0.0]),
        sphere("ball", 0.4).material("white"),
    ]);
    let scene = common::scene_from_toml("ao_closed_room", &toml);
    let mut b = common::Bench::new(&scene, 48, 27);
    for backend in common::BACKENDS {
        for mode in [Mode::Hybrid, Mode::Rt] {
            let settings = RenderSettings { backend, mode, ..Default::default() };
            let dark = b.frame(&scene, &scene.cameras[0], &settings);
            let lit =
                b.frame(&scene, &scene.cameras[0], &RenderSettings { ambient: AmbientMode::Sh, ..settings });
            let brightest = dark.ldr.chunks_exact(4).map(|p| p[0].max(p[1]).max(p[2])).max().unwrap();
            let lit_mean = lit.ldr.chunks_exact(4).map(|p| p[0] as f64).sum::<f64>() / (48.0 * 27.0);
            println!("{backend:?} {mode:?}: closed room, traced brightest {brightest}/255, sh mean {lit_mean:.0}/255");
            assert!(brightest <= 1, "{backend:?} {mode:?}: the sky lights a closed room ({brightest}/255)");
            assert!(lit_mean > 100.0, "{backend:?} {mode:?}: unshadowed ambient {lit_mean}/255");
        }
    }
    b.finish();
}

#[test]
fn nothing_to_occlude_leaves_the_ambient_as_it_is() {
    let toml = scene_toml([
        environment([0.6, 0.5, 0.4]),
        camera([0.0, 2.0, 4.0], [0.0, 0.0, 0.0]),
        no_light(),
        lambert("white", [ALBEDO, ALBEDO, ALBEDO]).ior(1.0),
        plane("floor", 20.0).material("white"),
    ]);
    let scene = common::scene_from_toml("ao_open_floor", &toml);
    let mut b = common::Bench::new(&scene, 64, 36);
    let cam = &scene.cameras[0];
    let traced = b.frame(&scene, cam, &RenderSettings::default());
    assert!(b.renderer.pass_names().contains(&"ao"), "{:?}", b.renderer.pass_names());
    let sh = b.frame(&scene, cam, &RenderSettings { ambient: AmbientMode::Sh, ..Default::default() });
    b.finish();
    let worst = traced.ldr.iter().zip(&sh.ldr).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
    println!("open floor: traced against sh, largest difference {worst}/255");
    assert!(worst <= 1, "traced visibility changed an unoccluded floor by {worst}/255");
}

/// A ceiling facing down over a wide floor sees the floor over its whole hemisphere, so the floor's
/// radiance L reaches it as irradiance pi L and it exits its albedo times L: the one indirect bounce
/// in closed form, from an emissive floor (the hit's emission), a floor lit by a sun straight above (the
/// hit's direct light, its shadow ray passing the ceiling, which casts no shadows) and a floor under a
/// constant sky (the hit's environment ray). Without the bounce (`--no-indirect`) the ceiling is black,
/// but for the emissive floor: emitters are direct light (tests/render/emitters.rs).
#[test]
fn a_ceiling_is_lit_by_the_floor_it_sees() {
    let (ceiling, floor, sun) = (0.8f32, 0.5f32, 3.0f32);
    let toml = |floor_material: Block, light: Block, sky: Block| {
        scene_toml([
            sky,
            camera([0.0, 0.3, 0.0], [0.0, 1.0, 0.0]).up([0.0, 0.0, -1.0]).yfov(60),
            light,
            lambert("ceiling", [ceiling; 3]).ior(1.0),
            floor_material,
            plane("floor", 400.0).material("floor"),
            plane("ceiling", 400.0)
                .at([0.0, 1.0, 0.0])
                .rot([180.0, 0.0, 0.0])
                .material("ceiling")
                .no_shadows(),
        ])
    };
    let cases = [
        ("emissive floor", toml(emitter("floor", [1.0, 1.0, 1.0]), no_light(), black_sky()), ceiling * 1.0),
        (
            "sunlit floor",
            toml(lambert("floor", [floor; 3]).ior(1.0), directional([0.0, -1.0, 0.0], sun), black_sky()),
            ceiling * floor * sun / std::f32::consts::PI,
        ),
        // The floor's own ambient: it sees the sky through the ceiling (no shadows) and the ceiling's
        // rays all hit the floor, so the ceiling has the sky only by the bounce.
        (
            "sky-lit floor",
            toml(lambert("floor", [floor; 3]).ior(1.0), no_light(), environment([2.0, 2.0, 2.0])),
            ceiling * floor * 2.0,
        ),
    ];
    for (name, toml, want) in cases {
        let scene = common::scene_from_toml(&format!("ao_ceiling_{}", name.replace(' ', "_")), &toml);
        let mut b = common::Bench::new(&scene, 32, 32);
        let cam = &scene.cameras[0];
        let lit = b.frame(&scene, cam, &RenderSettings::default());
        let dark = b.frame(&scene, cam, &RenderSettings { ambient_bounce: false, ..Default::default() });
        b.finish();
        let mean = |f: &hybrid_rt::render::FrameOutput| {
            f.hdr.chunks_exact(4).map(|p| p[0] as f64).sum::<f64>() / f.hdr.len() as f64 * 4.0
        };
        let (got, without) = (mean(&lit), mean(&dark));
        println!("{name}: ceiling {got:.4}, closed form {want:.4}; without the bounce {without:.4}");
        assert!((got / want as f64 - 1.0).abs() < 0.02, "{name}: ceiling {got} against {want}");
        if name == "emissive floor" {
            assert!(
                (without / want as f64 - 1.0).abs() < 0.02,
                "{name}: ceiling {without} without the bounce"
            );
        } else {
            assert!(without < 0.01 * want as f64, "{name}: {without} without the bounce");
        }
    }
}
