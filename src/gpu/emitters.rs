//! The path tracer's emissive triangles as lights (glsl/path/emitters.glsl), chosen by power (emissive
//! luminance x world area at upload). Layout (u32 words; SCENE_EMITTERS): EMITTER_HEADER_WORDS
//! (emitter count, instance count); per instance its first emitter (NO_EMITTER: none; an instance's
//! triangles are consecutive); per emitter (instance, primitive); the CDF (count + 1 f32 bits).
//! The weights only steer the choice: the shader's pdf uses the table's values and the triangle's
//! current area, so animated emitters stay unbiased.

use glam::{DVec3, Vec3};

use crate::gpu::shared::{EMITTER_HEADER_WORDS, NO_EMITTER};
use crate::scene::Scene;

/// What a table holds, for the log.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmitterSummary {
    pub triangles: usize,
    pub instances: usize,
    /// Sum of luminance x area (W-like units of the scene's radiance).
    pub power: f64,
}

/// The table of the scene's emissive triangles on the GPU.
pub fn upload(ctx: &crate::vk::Context, scene: &Scene) -> anyhow::Result<crate::vk::Buffer> {
    let (words, s) = table(scene);
    if s.triangles > 0 {
        log::info!(
            "emissive triangles: {} in {} instances (power {:.3e}), sampled as lights by the path tracer",
            s.triangles,
            s.instances,
            s.power
        );
    }
    let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER;
    crate::vk::Buffer::with_data(ctx, "emissive triangles", bytemuck::cast_slice(&words), usage)
}

/// The table of `scene`'s emissive triangles, and what it holds.
pub fn table(scene: &Scene) -> (Vec<u32>, EmitterSummary) {
    let n_inst = scene.instances.len();
    let mut first = vec![NO_EMITTER; n_inst];
    let mut pairs: Vec<u32> = Vec::new();
    let mut weights: Vec<f64> = Vec::new();
    let mut instances = 0;
    for (i, inst) in scene.instances.iter().enumerate() {
        let m = &scene.materials[scene.instance_material(inst)];
        let e = Vec3::from(m.emissive);
        let lum = 0.2126 * e.x as f64 + 0.7152 * e.y as f64 + 0.0722 * e.z as f64;
        if !(e.max_element() > 0.0 && e.is_finite()) {
            continue;
        }
        let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
        if prim.indices.len() < 3 {
            continue;
        }
        first[i] = (pairs.len() / 2) as u32;
        instances += 1;
        let world =
            |k: u32| inst.world.transform_point3(DVec3::from(Vec3::from(prim.vertices[k as usize].position)));
        for (p, t) in prim.indices.chunks_exact(3).enumerate() {
            let (a, b, c) = (world(t[0]), world(t[1]), world(t[2]));
            let area = 0.5 * (b - a).cross(c - a).length();
            pairs.extend([i as u32, p as u32]);
            // A weight of 0 would never be chosen: its light then comes by
            // BSDF samples alone, still unbiased (MIS weight 1 there).
            weights.push(if area.is_finite() { lum.max(1e-12) * area } else { 0.0 });
        }
    }
    let total: f64 = weights.iter().sum();
    let mut words =
        Vec::with_capacity(EMITTER_HEADER_WORDS as usize + n_inst + pairs.len() + weights.len() + 1);
    let count = if total > 0.0 && total.is_finite() { weights.len() } else { 0 };
    words.extend([count as u32, n_inst as u32]);
    words.extend(&first);
    if count == 0 {
        return (vec![0, 0], EmitterSummary::default());
    }
    words.extend(&pairs);
    let mut acc = 0.0;
    words.push(0f32.to_bits());
    for (k, w) in weights.iter().enumerate() {
        acc += w;
        let v = if k + 1 == count { 1.0 } else { (acc / total) as f32 };
        words.push(v.to_bits());
    }
    (words, EmitterSummary { triangles: count, instances, power: total })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(toml: &str) -> Scene {
        let dir = std::env::temp_dir().join(format!("hybrid-rt-emitters-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(format!("{:x}.toml", toml.len()));
        std::fs::write(&p, toml).unwrap();
        Scene::load(&p).unwrap()
    }

    const LAMPS: &str = r#"
[[material]]
name = "lamp"
emissive = [1.0, 1.0, 1.0]
emissive_strength = 4.0

[[material]]
name = "dim"
emissive = [1.0, 1.0, 1.0]

[[material]]
name = "grey"

[[object]]
name = "floor"
primitive = "plane"
size = 4.0
material = "grey"

[[object]]
name = "bright"
primitive = "plane"
size = 1.0
translation = [0.0, 2.0, 0.0]
material = "lamp"

[[object]]
name = "big dim"
primitive = "plane"
size = 2.0
translation = [0.0, 3.0, 0.0]
material = "dim"
"#;

    #[test]
    fn emitters_are_chosen_by_power() {
        let s = scene(LAMPS);
        let (t, sum) = table(&s);
        assert_eq!((sum.triangles, sum.instances), (4, 2));
        // 4 x 1 m^2 and 1 x 4 m^2: equal power, 8 in all.
        assert!((sum.power - 8.0).abs() < 1e-9, "{sum:?}");
        let n_inst = t[1] as usize;
        assert_eq!(n_inst, s.instances.len());
        let first = &t[2..2 + n_inst];
        assert_eq!(first.iter().filter(|f| **f != NO_EMITTER).count(), 2);
        let pairs = &t[2 + n_inst..2 + n_inst + 8];
        let cdf: Vec<f32> = t[2 + n_inst + 8..].iter().map(|w| f32::from_bits(*w)).collect();
        assert_eq!(cdf, [0.0, 0.25, 0.5, 0.75, 1.0]);
        // Each emitting instance's first entry names it, primitive 0.
        for (i, f) in first.iter().enumerate().filter(|(_, f)| **f != NO_EMITTER) {
            assert_eq!((pairs[2 * *f as usize], pairs[2 * *f as usize + 1]), (i as u32, 0));
        }
    }

    #[test]
    fn a_scene_without_emission_has_an_empty_table() {
        let s = scene("[[object]]\nname = \"floor\"\nprimitive = \"plane\"\n");
        assert_eq!(table(&s), (vec![0, 0], EmitterSummary::default()));
    }
}
