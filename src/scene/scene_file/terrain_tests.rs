//! Scene-file tests of `primitive = "terrain"` (the scale tests' generated geometry).

use super::tests::write;
use crate::scene::Scene;

/// `primitive = "terrain"`: two triangles per cell, the size and height asked for, deterministic.
#[test]
fn terrain_object_generates_its_cells() {
    let text = "[[object]]\nname = \"hills\"\nprimitive = \"terrain\"\nsize = [40, 20]\ncells = [30, 10]\nheight = 2\n";
    let scene = Scene::load(&write("terrain", "scene.toml", text)).unwrap();
    assert_eq!(scene.objects.len(), 1);
    let p = &scene.meshes[scene.instances[0].mesh].primitives[scene.instances[0].primitive];
    assert_eq!(p.indices.len() / 3, 2 * 30 * 10);
    assert_eq!((p.bounds.min.x, p.bounds.max.x, p.bounds.min.z, p.bounds.max.z), (-20.0, 20.0, -10.0, 10.0));
    assert!(p.bounds.min.y >= -2.0 && p.bounds.max.y <= 2.0 && p.bounds.max.y > p.bounds.min.y);
    // Defaults: 100 x 100 m, 64 x 64 cells, heights within a tenth of the side.
    let scene = Scene::load(&write(
        "terrain-default",
        "scene.toml",
        "[[object]]\nname = \"t\"\nprimitive = \"terrain\"\n",
    ))
    .unwrap();
    let p = &scene.meshes[0].primitives[0];
    assert_eq!(p.indices.len() / 3, 2 * 64 * 64);
    assert_eq!((p.bounds.min.x, p.bounds.max.x), (-50.0, 50.0));
    assert!(p.bounds.max.y <= 10.0 && p.bounds.max.y > 2.0);
}
