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
//! glass) and a glass square between a point light and the ground (shadow
//! rays through it carry a transmittance strictly between 0 and 1).
use crate::common;

use common::scenes::{glass_occluder, shadow_scene, Frame};
use common::toml::material;
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
