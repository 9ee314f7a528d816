//! The per-pixel ray budget: three glass slabs at max depth 64 and min
//! weight 0 branch into 2^depth rays through glass; each pixel stops at
//! RAY_BUDGET_PER_PIXEL secondary rays (or a full branch stack) and the frame
//! reports how many pixels were cut, so the host can warn instead of taking
//! minutes or silently dropping branches.
use crate::common;

use common::toml::*;
use common::BACKENDS;
use hybrid_rt::render::shading::Effects;
use hybrid_rt::render::RenderSettings;

/// Three glass slabs one behind the other.
fn slabs() -> String {
    let slab = |name, z| primitive(name, "cube").scale([2.0, 2.0, 0.1]).at([0.0, 0.0, z]).material("glass");
    scene_toml([
        environment([0.5, 0.6, 0.8]),
        camera([0.3, 0.2, 3.0], [0.0; 3]).yfov(40),
        directional([-0.3, -1.0, -0.4], 2.0),
        material("glass").roughness(0.0).transmission(1.0).ior(1.5),
        slab("slab a", 0.6),
        slab("slab b", 0.0),
        slab("slab c", -0.6),
    ])
}

#[test]
fn deep_glass_trees_are_cut_at_the_ray_budget_and_counted_on_every_backend() {
    let scene = common::scene_from_toml("ray_budget_slabs", &slabs());
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
