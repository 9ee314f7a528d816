//! Merging an imported glTF scene into the scene file's scene, every index
//! (meshes, materials, textures, nodes, cameras, skins, lights, animation
//! targets) offset past what is already there.

use glam::DMat4;

use crate::scene::{Light, Node, Scene, Transform};

/// Appends an imported glTF scene under a new root node carrying the
/// object's transform; returns the root. Every mesh node joins the one
/// `object`, so the heuristics treat the model as a single object. The
/// model's animations are renamed "object/animation": two objects loading
/// the same file, and the scene-file animation, stay apart by name.
pub(super) fn merge(scene: &mut Scene, sub: Scene, name: &str, local: Transform, object: usize) -> usize {
    let (mesh_base, material_base, texture_base) =
        (scene.meshes.len(), scene.materials.len(), scene.textures.len());
    let (camera_base, skin_base) = (scene.cameras.len(), scene.skins.len());
    let root = scene.nodes.len();
    let node_base = root + 1;
    let placement = local.matrix();

    scene.textures.extend(sub.textures);
    scene.materials.extend(sub.materials.into_iter().map(|mut m| {
        for t in [
            &mut m.base_color_texture,
            &mut m.metallic_roughness_texture,
            &mut m.normal_texture,
            &mut m.occlusion_texture,
            &mut m.emissive_texture,
            &mut m.transmission_texture,
        ]
        .into_iter()
        .flatten()
        {
            t.texture += texture_base;
        }
        m
    }));
    scene.meshes.extend(sub.meshes.into_iter().map(|mut mesh| {
        mesh.primitives.iter_mut().for_each(|p| p.material += material_base);
        mesh
    }));
    let children: Vec<usize> = sub.roots.iter().map(|r| r + node_base).collect();
    scene.nodes.push(Node { name: name.to_string(), local, children, ..Default::default() });
    for (i, mut n) in sub.nodes.into_iter().enumerate() {
        n.parent = n.parent.map(|p| p + node_base).or_else(|| sub.roots.contains(&i).then_some(root));
        n.children.iter_mut().for_each(|c| *c += node_base);
        n.mesh = n.mesh.map(|m| m + mesh_base);
        n.camera = n.camera.map(|c| c + camera_base);
        n.skin = n.skin.map(|k| k + skin_base);
        n.object = n.mesh.map(|_| object);
        scene.nodes.push(n);
    }
    scene.roots.push(root);
    scene.cameras.extend(sub.cameras.into_iter().map(|mut c| {
        c.world = placement * c.world;
        c
    }));
    scene.lights.extend(sub.lights.into_iter().map(|l| place_light(l, &placement, node_base)));
    scene.skins.extend(sub.skins.into_iter().map(|mut k| {
        k.joints.iter_mut().for_each(|j| *j += node_base);
        k
    }));
    scene.animations.extend(sub.animations.into_iter().map(|mut a| {
        a.name = format!("{name}/{}", a.name);
        a.channels.iter_mut().for_each(|c| c.node += node_base);
        a
    }));
    root
}

fn place_light(mut l: Light, placement: &DMat4, node_base: usize) -> Light {
    l.position = placement.transform_point3(l.position);
    l.direction = placement.transform_vector3(l.direction.as_dvec3()).as_vec3().normalize_or(l.direction);
    l.node = l.node.map(|n| n + node_base);
    l
}
