//! The per-pixel ray budget: three glass slabs at max depth 64 and min
//! weight 0 branch into 2^depth rays through glass; each pixel stops at
//! RAY_BUDGET_PER_PIXEL secondary rays (or a full branch stack) and the frame
//! reports how many pixels were cut, so the host can warn instead of taking
//! minutes or silently dropping branches.
use crate::common;

use common::BACKENDS;
use hybrid_rt::render::shading::Effects;
use hybrid_rt::render::RenderSettings;

const SLABS: &str = r#"
[environment]
color = [0.5, 0.6, 0.8]

[[camera]]
position = [0.3, 0.2, 3.0]
target = [0.0, 0.0, 0.0]
yfov_deg = 40

[[light]]
type = "directional"
direction = [-0.3, -1.0, -0.4]
intensity = 2.0

[[material]]
name = "glass"
roughness = 0.0
transmission = 1.0
ior = 1.5

[[object]]
name = "slab a"
primitive = "cube"
scale = [2.0, 2.0, 0.1]
translation = [0.0, 0.0, 0.6]
material = "glass"

[[object]]
name = "slab b"
primitive = "cube"
scale = [2.0, 2.0, 0.1]
translation = [0.0, 0.0, 0.0]
material = "glass"

[[object]]
name = "slab c"
primitive = "cube"
scale = [2.0, 2.0, 0.1]
translation = [0.0, 0.0, -0.6]
material = "glass"
"#;

#[test]
fn deep_glass_trees_are_cut_at_the_ray_budget_and_counted_on_every_backend() {
    let scene = common::scene_from_toml("ray_budget_slabs", SLABS);
    for backend in BACKENDS {
        let deep = RenderSettings {
            backend,
            effects: Effects { max_depth: 64, min_weight: 0.0, ..Effects::default() },
            ..Default::default()
        };
        let cut = common::render_scene(&scene, 64, 36, &deep);
        eprintln!("{backend:?}: {} of {} pixels cut", cut.truncated_pixels, 64 * 36);
        assert!(cut.truncated_pixels > 100, "{backend:?}: only {} pixels cut", cut.truncated_pixels);
        assert!(cut.truncation_warning().is_some_and(|w| w.contains("--max-depth")));
        let defaults =
            common::render_scene(&scene, 64, 36, &RenderSettings { backend, ..Default::default() });
        assert_eq!(defaults.truncated_pixels, 0, "{backend:?}: the default settings cut trees");
        assert!(defaults.truncation_warning().is_none());
    }
}
