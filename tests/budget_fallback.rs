//! What the effects the ray-tracing budget leaves out show (`--fallback`,
//! render/budget's Fallback): with the raster fallback a mirror left out
//! reflects the environment exactly as the traced reflection does where it
//! sees only sky; with `none` it reflects nothing.
mod common;

use hybrid_rt::metrics::diff_stats;
use hybrid_rt::render::budget::{BudgetSettings, Fallback};
use hybrid_rt::render::RenderSettings;

const W: u32 = 96;
const H: u32 = 54;

fn zero_budget(base: BudgetSettings, fallback: Fallback) -> Option<BudgetSettings> {
    Some(BudgetSettings { fallback, ..base })
}

/// A lone mirror sphere under a graded sky: its reflection rays all miss,
/// so the traced reflection is exactly the environment in the mirror
/// direction.
fn mirror_sphere_scene() -> String {
    // Gradients in both directions: a wrong direction or weight shows.
    let map = common::write_hdr("fallback_sky", 32, 16, |x, y| {
        [0.2 + x as f32 / 16.0, 0.1 + y as f32 / 8.0, 0.6 - y as f32 / 40.0]
    });
    format!(
        r#"
[environment]
hdr = "{}"

[[camera]]
position = [0.0, 0.3, 3.0]
target = [0.0, 0.0, 0.0]
yfov_deg = 45

[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
intensity = 0.0

[[material]]
name = "mirror"
base_color = [0.9, 0.8, 0.7]
metallic = 1.0
roughness = 0.0

[[object]]
name = "ball"
primitive = "sphere"
radius = 0.8
material = "mirror"
"#,
        map.display()
    )
}

#[test]
fn a_mirror_left_out_reflects_the_sky_as_the_traced_one_does_on_every_backend() {
    let scene = common::scene_from_toml("fallback_mirror_sphere", &mirror_sphere_scene());
    for backend in common::BACKENDS {
        let full = RenderSettings { backend, ..Default::default() };
        let traced = common::render_scene(&scene, W, H, &full);
        let modes = [BudgetSettings::paper(0.0), BudgetSettings::effects(0.0)];
        for base in modes {
            let with = |fallback| RenderSettings { budget: zero_budget(base, fallback), ..full };
            let raster = common::render_scene(&scene, W, H, &with(Fallback::Raster));
            let none = common::render_scene(&scene, W, H, &with(Fallback::None));
            // The same weight times the same environment lookup: equal up
            // to one 8-bit step (float rounding of the two code paths).
            let (max_raster, _) = diff_stats(&traced.rgb8(), &raster.rgb8(), 3, 1);
            // Without a fallback the sphere loses its reflection: most of
            // its pixels (about 12% of the frame) change by more than 8.
            let (_, share_none) = diff_stats(&traced.rgb8(), &none.rgb8(), 3, 8);
            eprintln!(
                "{backend:?} {:?}: budget 0 raster fallback vs traced max {max_raster}; none changes {:.1}%",
                base.mode,
                share_none * 100.0
            );
            assert!(max_raster <= 1, "{backend:?} {:?}: raster fallback differs by {max_raster}", base.mode);
            assert!(share_none > 0.05, "{backend:?}: --fallback none kept the reflection ({share_none})");
        }
    }
}
