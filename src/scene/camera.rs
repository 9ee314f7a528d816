//! Cameras: a camera-to-world matrix plus a perspective lens, and the
//! reversed-Z infinite projection the renderer uses.

use glam::{DMat4, DVec3, Mat4, Vec3, Vec4};

use super::{CameraKey, Light, LightKind, Scene};

#[derive(Clone, Debug)]
pub struct Camera {
    pub name: String,
    /// Camera-to-world, f64 like every placement (see `Transform`); the
    /// camera looks down its local -Z with +Y up (glTF).
    pub world: DMat4,
    /// Vertical field of view, radians.
    pub yfov: f32,
    pub znear: f32,
}

impl Camera {
    pub fn look_at(name: &str, position: Vec3, target: Vec3, yfov: f32, znear: f32) -> Camera {
        let forward = (target - position).try_normalize().unwrap_or(Vec3::NEG_Z);
        // Pick an up vector that is not parallel to the view direction.
        let up = if forward.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y };
        Camera::look_at_up(name, position, target, up, yfov, znear)
    }

    /// `look_at` with an explicit up vector (camera roll; scenes not aligned
    /// with +Y). `up` must not be parallel to the view direction.
    pub fn look_at_up(name: &str, position: Vec3, target: Vec3, up: Vec3, yfov: f32, znear: f32) -> Camera {
        Camera::look_at_up_f64(name, position.as_dvec3(), target.as_dvec3(), up, yfov, znear)
    }

    /// `look_at_up` with an f64 eye and target (scenes far from the origin).
    pub fn look_at_up_f64(
        name: &str,
        position: DVec3,
        target: DVec3,
        up: Vec3,
        yfov: f32,
        znear: f32,
    ) -> Camera {
        let forward = (target - position).try_normalize().unwrap_or(DVec3::NEG_Z);
        let view = DMat4::look_at_rh(position, position + forward, up.as_dvec3().normalize());
        Camera { name: name.into(), world: view.inverse(), yfov, znear }
    }

    /// The eye in f32: for framing, UI and navigation; rendering uses
    /// [`Camera::world`] through the render origin.
    pub fn position(&self) -> Vec3 {
        self.position_f64().as_vec3()
    }

    pub fn position_f64(&self) -> DVec3 {
        self.world.w_axis.truncate()
    }

    pub fn forward(&self) -> Vec3 {
        (-self.world.z_axis.truncate()).as_vec3().normalize_or(Vec3::NEG_Z)
    }

    /// World-to-view, with any scale in the node chain removed, in f64;
    /// the renderer narrows it after moving the eye to the render origin.
    pub fn view(&self) -> DMat4 {
        let (_, rot, pos) = self.world.to_scale_rotation_translation();
        DMat4::from_rotation_translation(rot, pos).inverse()
    }

    /// Reversed-Z projection with an infinite far plane, Vulkan clip space
    /// (y down, depth 0..1): depth = znear / view_distance, 1 at the near
    /// plane and 0 at infinity, so float precision goes to the distance.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let f = 1.0 / (0.5 * self.yfov).tan();
        Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, -f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 0.0, -1.0),
            Vec4::new(0.0, 0.0, self.znear, 0.0),
        )
    }
}

/// The camera at normalized time `t` (0..1) of a keyframed path, linear in
/// position and target; lens from `template`. Without keys, the template.
pub fn on_path(keys: &[CameraKey], t: f32, template: &Camera) -> Camera {
    let (Some(first), Some(last)) = (keys.first(), keys.last()) else { return template.clone() };
    let time = first.time + (last.time - first.time) * t.clamp(0.0, 1.0);
    let i = keys.iter().rposition(|k| k.time <= time).unwrap_or(0);
    let (a, b) = (keys[i], keys[(i + 1).min(keys.len() - 1)]);
    let s = if b.time > a.time { (time - a.time) / (b.time - a.time) } else { 0.0 };
    Camera::look_at(
        "path",
        a.position.lerp(b.position, s),
        a.target.lerp(b.target, s),
        template.yfov,
        template.znear,
    )
}

/// A scene with no light and nothing emissive gets a sun-like directional light (a room lit by its
/// lamps stays lit by them alone); one with no camera gets a camera that frames its bounds.
pub fn add_defaults(scene: &mut Scene) {
    let b = scene.bounds;
    let (center, radius) =
        if b.is_empty() { (Vec3::ZERO, 1.0) } else { (b.center(), (b.extent().length() * 0.5).max(1e-6)) };
    let emits = scene.instances.iter().any(|i| {
        let e = scene.materials[scene.instance_material(i)].emissive;
        e.iter().any(|c| c.is_finite() && *c > 0.0)
    });
    if scene.lights.is_empty() && emits {
        log::info!("scene has no punctual lights: lit by its emissive surfaces (no default sun)");
    } else if scene.lights.is_empty() {
        log::info!("scene has no lights: adding a default directional light");
        scene.lights.push(Light {
            name: "default sun".into(),
            kind: LightKind::Directional,
            color: Vec3::ONE,
            intensity: 3.0,
            position: DVec3::ZERO,
            direction: Vec3::new(-0.35, -1.0, -0.45).normalize(),
            range: None,
            casts_shadows: true,
            node: None,
        });
    }
    if scene.cameras.is_empty() {
        log::info!("scene has no camera: framing its bounds");
        let yfov = 45f32.to_radians();
        let distance = radius / (0.5 * yfov).sin() * 1.1;
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        scene.cameras.push(Camera::look_at(
            "default",
            center + dir * distance,
            center,
            yfov,
            (distance - radius).max(distance * 1e-3).max(1e-4) * 0.5,
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversed_z_maps_near_to_one_and_far_to_zero() {
        let cam = Camera::look_at("t", Vec3::ZERO, Vec3::NEG_Z, 1.0, 0.1);
        let p = cam.projection(1.0) * cam.view().as_mat4();
        let near = p * Vec4::new(0.0, 0.0, -0.1, 1.0);
        assert!((near.z / near.w - 1.0).abs() < 1e-6);
        let far = p * Vec4::new(0.0, 0.0, -1e6, 1.0);
        assert!(far.z / far.w < 1e-6 && far.z / far.w > 0.0);
        // +Y in view space goes to negative clip y (Vulkan's y points down).
        let up = p * Vec4::new(0.0, 1.0, -1.0, 1.0);
        assert!(up.y < 0.0);
    }

    /// The default sun lights a scene that has no other light; one whose surfaces emit keeps its own
    /// light (an emissive material no object uses lights nothing).
    #[test]
    fn the_default_sun_only_where_nothing_emits() {
        let dir = std::env::temp_dir().join("hybrid-rt-tests").join("default-sun");
        std::fs::create_dir_all(&dir).unwrap();
        let lamp = "[[material]]\nname = \"lamp\"\nemissive = [0.0, 0.5, 0.0]\n";
        let grey = "[[material]]\nname = \"grey\"\n";
        let floor =
            |m: &str| format!("[[object]]\nname = \"floor\"\nprimitive = \"plane\"\nmaterial = \"{m}\"\n");
        for (text, sun) in [
            (format!("{grey}{floor}", floor = floor("grey")), true),
            (format!("{lamp}{floor}", floor = floor("lamp")), false),
            (format!("{lamp}{grey}{floor}", floor = floor("grey")), true),
        ] {
            let p = dir.join("scene.toml");
            std::fs::write(&p, &text).unwrap();
            let s = Scene::load(&p).unwrap();
            let names: Vec<&str> = s.lights.iter().map(|l| l.name.as_str()).collect();
            assert_eq!(names, if sun { vec!["default sun"] } else { vec![] }, "{text}");
        }
    }
}
