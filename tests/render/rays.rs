//! The ray microbenchmark's agreement check as a test: the same fixed ray
//! sets (primary, shadow, diffuse; render/rays/sets.rs) traced by our
//! compute BVH tracer and by the driver's ray query (or its ray-tracing
//! pipeline, which `bench --rays` uses on drivers without ray queries) agree ray by ray: hit
//! versus miss (blocked versus not for shadow rays) exactly, hit distances
//! within sets::T_REL_BOUND (1e-3) of the distance, shadow transmittance
//! within sets::TRANSMITTANCE_BOUND (1e-3) per channel, with the compute
//! tracer's per-lane and its subgroup ("packet") traversal alike. No timing
//! is checked.
//! Scenes: the default scene (every material and light type, opaque and
//! glass), a glass square between a point light and the ground (shadow
//! rays through it carry a transmittance strictly between 0 and 1), and
//! orbiting objects that the compute tracer reaches through its top level.
use crate::common;

use common::scenes::{glass_occluder, shadow_scene, Frame};
use common::toml::*;
use hybrid_rt::app::{RayBench, RenderJob};
use hybrid_rt::render::rays::sets::RayKind;
use hybrid_rt::render::rays::Traversal;
use hybrid_rt::render::shading::Backend;
use hybrid_rt::scene::Scene;

fn agree(scene: &Scene, w: u32, h: u32, traversal: Traversal) -> Vec<hybrid_rt::app::KindReport> {
    agree_where(scene, w, h, traversal, Backend::Query, true)
}

/// `agree` with the driver's tracer `driver`; `shadow_hits`: whether some
/// shadow ray must be blocked or tinted (false for a scene where none may be).
fn agree_where(
    scene: &Scene,
    w: u32,
    h: u32,
    traversal: Traversal,
    driver: Backend,
    shadow_hits: bool,
) -> Vec<hybrid_rt::app::KindReport> {
    let ctx = common::validated_context();
    let mut bench = RayBench::with_traversal(&ctx, scene, traversal, driver).expect("set up both tracers");
    let job = RenderJob::new(&scene.source, w, h);
    let reports = bench.all(&ctx, scene, &job, 1);
    bench.destroy(&ctx);
    let reports = reports.expect("trace the ray sets");
    for r in &reports {
        eprintln!("{}\n{}", r.line(), r.detail());
        assert!(r.rays > 0, "{}: no {} rays", scene.source.display(), r.kind.name());
        assert_eq!(r.compute.results.len(), r.rays);
        assert_eq!(r.driver_backend, driver);
        assert_eq!(r.driver.results.len(), r.rays);
        if let Some(&i) = r.mismatches.first() {
            panic!(
                "{}: {} of {} {} rays disagree; first: ray {i}, compute {:?}, {driver:?} {:?}",
                scene.source.display(),
                r.mismatches.len(),
                r.rays,
                r.kind.name(),
                r.compute.results[i],
                r.driver.results[i]
            );
        }
        // Agreement is not trivially all-miss: some rays hit (or, shadow
        // rays, lose light to glass).
        let hits = r
            .compute
            .results
            .iter()
            .filter(|x| x.hit != 0 || (r.kind == RayKind::Shadow && x.next.iter().any(|&c| c < 1.0)))
            .count();
        assert!(
            hits > 0 || (r.kind == RayKind::Shadow && !shadow_hits),
            "{}: no {} ray hits",
            scene.source.display(),
            r.kind.name()
        );
        let stats = r.compute.stats.as_ref().expect("compute statistics");
        assert_eq!(stats.len(), r.rays);
        // A ray enters no node its subgroup did not visit; lane by lane the
        // two counts are one.
        for s in stats {
            assert!(s[2] <= s[0], "{} ray entered {} of {} nodes visited", r.kind.name(), s[2], s[0]);
            if traversal == Traversal::Lane {
                assert_eq!(s[2], s[0]);
            }
        }
    }
    common::assert_validation_clean(&ctx);
    reports
}

#[test]
fn compute_and_query_agree_on_the_default_scene() {
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    // Both traversals of the compute tracer (each ray on its own, and the
    // subgroup's rays together), whichever the passes use by default.
    for traversal in [Traversal::Lane, Traversal::Packet] {
        for r in agree(&scene, 64, 36, traversal) {
            // Both outcomes occur (sky, shadowed and lit points).
            let hits = r.compute.results.iter().filter(|x| x.hit != 0).count();
            assert!(hits < r.rays, "every {} ray hits", r.kind.name());
        }
    }
}

/// Some shadow ray of the glass scene lost light to the glass (as the
/// driver's tracer saw it) rather than being blocked or passing freely.
fn assert_some_shadow_ray_tinted(reports: &[hybrid_rt::app::KindReport]) {
    let shadow = reports.iter().find(|r| r.kind == RayKind::Shadow).unwrap();
    let tinted = shadow
        .driver
        .results
        .iter()
        .filter(|x| x.hit == 0 && x.next.iter().any(|&c| c > 0.0 && c < 1.0))
        .count();
    assert!(tinted > 0, "no shadow ray crossed the glass square");
}

#[test]
fn compute_and_query_agree_through_glass() {
    let toml = shadow_scene(Frame::IDENTITY, glass_occluder([0.9, 0.5, 0.2]));
    let scene = common::scene_from_toml("rays_glass", &toml);
    for traversal in [Traversal::Lane, Traversal::Packet] {
        let reports = agree(&scene, 32, 18, traversal);
        assert_some_shadow_ray_tinted(&reports);
    }
}

/// The RT pipeline as the driver's tracer (rays.rgen, the hit shaders of
/// the frame's pipeline backend): on the default scene and through glass,
/// where the any-hit shader accumulates the transmittance. (Seen failing with
/// rays.rgen tracing every ray as a closest-hit ray: the shadow sets
/// disagree.)
#[test]
fn compute_and_pipeline_agree() {
    let scene = Scene::load(&common::repo_path("assets/default.toml")).unwrap();
    agree_where(&scene, 64, 36, Traversal::Lane, Backend::Pipeline, true);
    let toml = shadow_scene(Frame::IDENTITY, glass_occluder([0.9, 0.5, 0.2]));
    let scene = common::scene_from_toml("rays_glass_pipeline", &toml);
    let reports = agree_where(&scene, 32, 18, Traversal::Lane, Backend::Pipeline, true);
    assert_some_shadow_ray_tinted(&reports);
}

/// An opaque occluder whose material casts no shadow: visible to camera
/// rays, invisible to shadow rays (instance mask). The compute tracer's flat
/// static tree filters by per-triangle mask bits, the query by instance
/// mask; they must agree, and no shadow ray may be blocked. (With the flat
/// tree's mask test removed, compute shadow rays stop at the occluder and
/// this fails with mismatches.)
#[test]
fn shadow_rays_pass_an_occluder_that_casts_no_shadow() {
    let occluder = material("occluder").base([0.9, 0.2, 0.2]).no_shadows().double_sided();
    let scene = common::scene_from_toml("rays_no_shadow", &shadow_scene(Frame::IDENTITY, occluder));
    for traversal in [Traversal::Lane, Traversal::Packet] {
        let reports = agree_where(&scene, 32, 18, traversal, Backend::Query, false);
        let shadow = reports.iter().find(|r| r.kind == RayKind::Shadow).unwrap();
        let blocked = shadow.compute.results.iter().filter(|x| x.hit != 0).count();
        assert_eq!(blocked, 0, "{blocked} shadow rays blocked by an occluder that casts no shadow");
        let primary = reports.iter().find(|r| r.kind == RayKind::Primary).unwrap();
        let occ = primary.compute.results.iter().filter(|x| x.hit != 0 && x.instance == 1).count();
        assert!(occ > 0, "no camera ray sees the occluder");
    }
}

/// Rays through the compute tracer's top level: animated (orbiting) rigid
/// objects are not flattened into the static tree but traced through the
/// top level into their own 4-wide BLAS, several instances per top-level
/// leaf, in the same walk as the static ground (glsl/trace/compute.glsl's
/// trace_bvh). Opaque, mirror and glass instances, and one whose material
/// casts no shadow (the top level's instance mask). The default and glass
/// scenes above are all static, so only this one reaches those levels.
#[test]
fn compute_and_query_agree_through_the_top_level() {
    let orbit = |period: f32| {
        shown(format!("{{ center = [0.0, 0.6, 0.0], axis = [0.0, 1.0, 0.0], period = {period} }}"))
    };
    let mut blocks = vec![
        environment([0.3, 0.4, 0.6]),
        camera([0.0, 3.0, 6.5], [0.0, 0.4, 0.0]).yfov(50),
        point([2.0, 5.0, 2.0], 60.0),
        directional([-0.3, -1.0, -0.5], 2.0),
        mirror("mirror", [0.9, 0.9, 0.9]),
        glass("glass", 1.5),
        material("red").base([0.8, 0.1, 0.1]).roughness(0.7),
        material("ground").base([0.7, 0.7, 0.7]).roughness(0.8),
        material("ghost").base([0.2, 0.8, 0.2]).no_shadows(),
        plane("ground", [20.0, 20.0]).material("ground"),
    ];
    let materials = ["mirror", "glass", "red", "ghost", "red", "glass", "red", "mirror"];
    for (i, m) in materials.iter().enumerate() {
        let a = i as f32 * std::f32::consts::TAU / materials.len() as f32;
        let r = 1.2 + 0.6 * (i % 2) as f32;
        let body =
            if i % 3 == 0 { cube(&format!("box {i}"), 0.6) } else { sphere(&format!("ball {i}"), 0.35) };
        let at = [r * a.cos(), 0.6, r * a.sin()];
        let period = [8.0, 4.0, 2.0][i % 3];
        blocks.push(body.at(at).material(m).set("orbit", orbit(period)));
        // A second instance inside it, same centre: the top level cannot split the two, so its leaves
        // hold several instances.
        blocks.push(cube(&format!("core {i}"), 0.2).at(at).material("red").set("orbit", orbit(period)));
    }
    let scene = common::scene_from_toml("rays_top_level", &scene_toml(blocks));
    let flattened = hybrid_rt::accel::flat::static_instances(&scene);
    assert_eq!(
        flattened.iter().filter(|f| !**f).count(),
        2 * materials.len(),
        "the orbiting objects stay in the top level"
    );
    for traversal in [Traversal::Lane, Traversal::Packet] {
        let reports = agree(&scene, 64, 36, traversal);
        let primary = reports.iter().find(|r| r.kind == RayKind::Primary).unwrap();
        let on_movers = primary.compute.results.iter().filter(|x| x.hit != 0 && x.instance >= 1).count();
        assert!(on_movers > 20, "only {on_movers} camera rays hit an orbiting object");
    }
}
