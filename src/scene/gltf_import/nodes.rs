//! Nodes: local transforms, the parent links (malformed hierarchies
//! rejected), the drawn scene's roots, and the objects, cameras and lights
//! its nodes carry.

use anyhow::{bail, ensure, Context, Result};
use glam::{DMat4, DVec3, Mat4, Quat, Vec3};

use super::values::HUGE;
use crate::scene::{Camera, Light, LightKind, Node, Object, ObjectProps, Scene, Transform};

pub(super) fn build_nodes(doc: &gltf::Document, scene: &mut Scene) -> Result<()> {
    for node in doc.nodes() {
        let name = node.name().map_or_else(|| format!("node {}", node.index()), str::to_string);
        let local = local_transform(node.transform()).with_context(|| format!("node '{name}'"))?;
        let children = node.children().map(|c| c.index()).collect();
        scene.nodes.push(Node { name, local, children, ..Default::default() });
    }
    link_parents(scene)?;
    scene.roots = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => (0..scene.nodes.len()).filter(|&i| scene.nodes[i].parent.is_none()).collect(),
    };
    let reachable = reachable_nodes(scene);
    let world = scene.world_matrices();
    for node in doc.nodes().filter(|n| reachable[n.index()]) {
        attach_node_content(&node, &world[node.index()], scene)?;
    }
    Ok(())
}

/// Local TRS from either glTF form; matrices are decomposed (shear is lost,
/// which glTF forbids anyway).
fn local_transform(t: gltf::scene::Transform) -> Result<Transform> {
    let (translation, rotation, scale) = match t {
        gltf::scene::Transform::Matrix { matrix } => {
            let (s, r, t) = Mat4::from_cols_array_2d(&matrix).to_scale_rotation_translation();
            (t, r, s)
        }
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            (Vec3::from(translation), Quat::from_array(rotation), Vec3::from(scale))
        }
    };
    let length = rotation.length();
    let rotation = (length.is_finite() && length > 1e-6).then(|| rotation / length);
    let rotation = match rotation {
        Some(r) => r,
        // A zero-scale matrix has no recoverable rotation; it draws nothing anyway.
        None if scale.cmpeq(Vec3::ZERO).any() => Quat::IDENTITY,
        None => bail!("has a non-finite or zero rotation"),
    };
    ensure!(
        translation.is_finite() && scale.is_finite(),
        "has a non-finite transform (translation {translation}, scale {scale})"
    );
    // Finite but huge values overflow once multiplied along the hierarchy.
    ensure!(
        translation.abs().max_element() < HUGE && scale.abs().max_element() < HUGE,
        "has a transform component of 1e30 or more (translation {translation}, scale {scale})"
    );
    Ok(Transform { translation: translation.as_dvec3(), rotation, scale })
}

/// Sets `parent` from the children lists, rejecting the malformed
/// hierarchies (shared children, cycles) the crate's validation lets through.
fn link_parents(scene: &mut Scene) -> Result<()> {
    for p in 0..scene.nodes.len() {
        for c in scene.nodes[p].children.clone() {
            let child = scene.nodes.get_mut(c).with_context(|| format!("node {p} has no child {c}"))?;
            ensure!(child.parent.is_none(), "node '{}' has more than one parent", child.name);
            child.parent = Some(p);
        }
    }
    // Each node has at most one parent now, so climbing from every node
    // finds any cycle; a node's state: 0 unseen, 1 on the current climb, 2
    // known to reach a root. Linear in the node count, for deep chains.
    let mut state = vec![0u8; scene.nodes.len()];
    let mut climb = Vec::new();
    for start in 0..scene.nodes.len() {
        let mut at = Some(start);
        while let Some(n) = at.filter(|&n| state[n] != 2) {
            ensure!(
                state[n] == 0,
                "node '{}' is its own ancestor (the hierarchy has a cycle)",
                scene.nodes[n].name
            );
            state[n] = 1;
            climb.push(n);
            at = scene.nodes[n].parent;
        }
        for n in climb.drain(..) {
            state[n] = 2;
        }
    }
    Ok(())
}

fn reachable_nodes(scene: &Scene) -> Vec<bool> {
    let mut seen = vec![false; scene.nodes.len()];
    let mut stack: Vec<usize> = scene.roots.clone();
    while let Some(i) = stack.pop() {
        if let Some(s) = seen.get_mut(i).filter(|s| !**s) {
            *s = true;
            stack.extend(&scene.nodes[i].children);
        }
    }
    seen
}

/// Mesh (as its own object), camera and light of one node of the drawn scene.
fn attach_node_content(node: &gltf::Node, world: &DMat4, scene: &mut Scene) -> Result<()> {
    let i = node.index();
    if let Some(mesh) = node.mesh() {
        let name = node.name().or(mesh.name()).map_or_else(|| format!("node {i}"), str::to_string);
        let props = object_props(node).with_context(|| format!("node {i} '{name}'"))?;
        scene.nodes[i].mesh = Some(mesh.index());
        scene.nodes[i].object = Some(scene.objects.len());
        scene.objects.push(Object { name, props });
    }
    if let Some(cam) = node.camera() {
        scene.nodes[i].camera = Some(scene.cameras.len());
        scene.cameras.push(convert_camera(&cam, &scene.nodes[i].name, world));
    }
    if let Some(light) = node.light() {
        scene.lights.push(convert_light(&light, &scene.nodes[i].name, world, i));
    }
    Ok(())
}

/// The ray-tracing budget's relevance K and cost factor E of a mesh node's
/// object, from the node's `extras` (`{"relevance": K, "cost": E}`, each
/// optional, numbers >= 0; other extras are ignored).
fn object_props(node: &gltf::Node) -> Result<ObjectProps> {
    let mut props = ObjectProps::default();
    let Some(raw) = node.extras() else { return Ok(props) };
    let extras: gltf::json::Value = gltf::json::deserialize::from_str(raw.get()).context("extras")?;
    for (key, field) in [("relevance", &mut props.relevance), ("cost", &mut props.cost)] {
        if let Some(v) = extras.get(key) {
            let x = v.as_f64().filter(|x| x.is_finite() && *x >= 0.0 && *x <= f32::MAX as f64);
            *field =
                x.with_context(|| format!("extras.{key} must be a finite number >= 0 (got {v})"))? as f32;
        }
    }
    Ok(props)
}

fn convert_camera(cam: &gltf::Camera, node_name: &str, world: &DMat4) -> Camera {
    let name = cam.name().unwrap_or(node_name).to_string();
    let (yfov, znear) = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => (p.yfov(), p.znear()),
        gltf::camera::Projection::Orthographic(o) => {
            // Approximated by a perspective that frames ymag half-height at
            // the middle of the ortho depth range.
            let depth = (0.5 * (o.znear() + o.zfar())).max(1e-3);
            log::warn!("camera '{name}' is orthographic: approximating it with a perspective camera");
            (2.0 * (o.ymag().abs() / depth).atan(), o.znear().max(depth * 1e-3))
        }
    };
    // Values are in range (checked by `values::check_camera`); what the spec
    // allows but the projection cannot show well is clamped, and said so.
    let (lo, hi) = (1f32.to_radians(), 170f32.to_radians());
    if !(lo..=hi).contains(&yfov) {
        log::warn!("camera '{name}': yfov {yfov} rad clamped to [1, 170] degrees");
    }
    let yfov = if yfov.is_finite() { yfov.clamp(lo, hi) } else { 1.0 };
    let znear = if znear.is_finite() && znear > 0.0 { znear } else { 0.01 };
    Camera { name, world: *world, yfov, znear }
}

fn convert_light(
    light: &gltf::khr_lights_punctual::Light,
    node_name: &str,
    world: &DMat4,
    node: usize,
) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let kind = match light.kind() {
        Kind::Directional => LightKind::Directional,
        Kind::Point => LightKind::Point,
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            LightKind::Spot { inner_cone: inner_cone_angle, outer_cone: outer_cone_angle }
        }
    };
    Light {
        name: light.name().unwrap_or(node_name).to_string(),
        kind,
        color: Vec3::from(light.color()),
        intensity: light.intensity(),
        position: world.transform_point3(DVec3::ZERO),
        // Lights shine down their node's -Z.
        direction: world.transform_vector3(DVec3::NEG_Z).as_vec3().normalize_or(Vec3::NEG_Z),
        range: light.range(),
        casts_shadows: true,
        node: Some(node),
    }
}
