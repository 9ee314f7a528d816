//! Readback at odd sizes: no row padding, no wrong pitch. A glowing
//! half-plane whose edge crosses every row at a known column: a pitch error
//! shears the edge from row to row, padding changes the buffer length.
use crate::common;

use common::toml::*;

use hybrid_rt::render::RenderSettings;

/// Glowing white on black: a plane covering x < 0 of z = 0.
fn half_plane() -> String {
    scene_toml([
        black_sky(),
        camera([0.013, 0.0, 5.0], [0.013, 0.0, 0.0]).yfov(40),
        no_light(),
        emitter("glow", [1.0; 3]),
        // The plane primitive lies in XZ, facing +Y: turned to face +Z.
        plane("left half", [20000.0, 20000.0])
            .at([-10000.0, 0.0, 0.0])
            .rot([90.0, 0.0, 0.0])
            .material("glow"),
    ])
}

#[test]
fn odd_sizes_read_back_without_padding_or_shear() {
    let scene = common::scene_from_toml("half_plane", &half_plane());
    for (w, h) in [(161u32, 91u32), (37, 23), (257, 3), (1, 1)] {
        let frame = common::render_scene(&scene, w, h, &RenderSettings::default());
        assert_eq!(frame.ldr.len(), (w * h * 4) as usize, "{w}x{h}: LDR buffer size");
        assert_eq!(frame.hdr.len(), (w * h * 4) as usize, "{w}x{h}: HDR buffer size");
        let mut checked = 0;
        for y in 0..h {
            for x in 0..w {
                let (o, d) = common::pixel_ray(&scene.cameras[0], w, h, x, y);
                let hit_x = o.x + d.x * (-o.z / d.z);
                if hit_x.abs() < 0.02 {
                    continue; // the edge pixel itself
                }
                let lit = frame.radiance(x, y)[0] > 0.5;
                assert_eq!(lit, hit_x < 0.0, "{w}x{h}: pixel ({x}, {y}) (ray meets z=0 at x={hit_x})");
                checked += 1;
            }
        }
        assert!(
            checked as f64 >= 0.8 * (w * h) as f64 || w * h < 4,
            "{w}x{h}: only {checked} pixels checked"
        );
    }
}
