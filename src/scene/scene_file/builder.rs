//! The builder: walks a parsed scene file in order (environment, materials,
//! cameras, camera path, lights, objects) and adds each to the scene, with
//! "file:line" context on every error.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, ensure, Context, Result};
use glam::Vec3;
use toml::Spanned;

use super::checks::{finite, finite3, finite3_f64, non_negative, non_negative3};
use super::elements::{
    check_no_shape_parameters, light_from_def, load_env_map, material_from_def, object_transform, procedural,
};
use super::merge::merge;
use super::orbit::{orbit_from_def, Orbit};
use super::schema::{CameraDef, CameraKeyDef, EnvironmentDef, LightDef, MaterialDef, ObjectDef, SceneFile};
use crate::scene::{
    gltf_import, obj, Camera, CameraKey, Environment, Light, Material, Mesh, Node, Object, ObjectProps,
    Scene, Transform,
};

pub(super) struct Builder<'a> {
    pub(super) scene: Scene,
    pub(super) dir: &'a Path,
    pub(super) file: &'a Path,
    pub(super) text: &'a str,
    pub(super) materials: HashMap<String, usize>,
    pub(super) default_material: Option<usize>,
    pub(super) orbits: Vec<Orbit>,
}

impl Builder<'_> {
    /// "file:line" for a byte offset into the scene file.
    fn at(&self, offset: usize) -> String {
        format!("{}:{}", self.file.display(), self.line(offset))
    }

    fn line(&self, offset: usize) -> usize {
        self.text.get(..offset).map_or(0, |t| t.matches('\n').count()) + 1
    }

    fn resolve(&self, relative: &str) -> PathBuf {
        self.dir.join(relative)
    }

    pub(super) fn build(&mut self, file: SceneFile) -> Result<()> {
        if let Some(env) = file.environment {
            self.scene.environment = self.environment(env)?;
        }
        for m in file.material {
            self.add_material(m)?;
        }
        // Scene-file cameras first: the renderer starts with camera 0.
        for (i, c) in file.camera.into_iter().enumerate() {
            let camera = self.camera(c, i)?;
            self.scene.cameras.push(camera);
        }
        self.scene.camera_path = self.camera_path(file.camera_path)?;
        for (i, l) in file.light.into_iter().enumerate() {
            let light = self.light(l, i)?;
            self.scene.lights.push(light);
        }
        for o in file.object {
            let context = format!("{}: object '{}'", self.at(o.name.span().start), o.name.get_ref());
            self.add_object(o, &context).with_context(|| context.clone())?;
        }
        self.add_orbit_animation()
    }

    fn environment(&self, env: EnvironmentDef) -> Result<Environment> {
        let mut out = Environment::default();
        let context = || format!("{}: [environment]", self.file.display());
        if let (Some(_), Some(hdr)) = (&env.color, &env.hdr) {
            bail!("{}: set either `color` or `hdr`, not both", self.at(hdr.span().start));
        }
        if env.layout.is_some() && env.hdr.is_none() {
            bail!("{}: `layout` needs an `hdr` map", context());
        }
        if let Some(c) = env.color {
            out.color = non_negative3(c, "color").with_context(context)?;
        }
        if let Some(hdr) = env.hdr {
            let path = self.resolve(hdr.get_ref());
            let layout = env.layout.unwrap_or_default();
            out.map = Some(load_env_map(&path, layout).with_context(|| self.at(hdr.span().start))?);
            out.map_path = Some(path);
        }
        if let Some(a) = env.ambient {
            let names = crate::scene::AMBIENT_NAMES;
            if !names.contains(&a.get_ref().as_str()) {
                bail!(
                    "{}: ambient '{}': expected one of {}",
                    self.at(a.span().start),
                    a.get_ref(),
                    names.join(", ")
                );
            }
            out.ambient = Some(a.into_inner());
        }
        if let Some(e) = env.exposure {
            use super::schema::ExposureDef;
            out.exposure = Some(match e.get_ref() {
                ExposureDef::Fixed(x) if x.is_finite() && *x > 0.0 => crate::scene::SceneExposure::Fixed(*x),
                ExposureDef::Named(n) if n == "auto" => crate::scene::SceneExposure::Auto,
                ExposureDef::Fixed(x) => {
                    bail!("{}: exposure {x}: expected a finite number > 0", self.at(e.span().start))
                }
                ExposureDef::Named(n) => {
                    bail!("{}: exposure '{n}': expected a number > 0 or \"auto\"", self.at(e.span().start))
                }
            });
        }
        out.intensity = non_negative(env.intensity.unwrap_or(1.0), "intensity").with_context(context)?;
        out.rotation =
            finite(env.rotation_deg.unwrap_or(0.0), "rotation_deg").with_context(context)?.to_radians();
        Ok(out)
    }

    fn camera(&self, c: CameraDef, index: usize) -> Result<Camera> {
        let name = c.name.unwrap_or_else(|| format!("camera {index}"));
        let context = || format!("{}: camera '{name}'", self.at(c.position.span().start));
        let position = finite3_f64(*c.position.get_ref(), "position").with_context(context)?;
        let target = finite3_f64(c.target, "target").with_context(context)?;
        ensure!(position != target, "{}: position and target coincide", context());
        let yfov = c.yfov_deg.unwrap_or(60.0);
        ensure!(yfov > 0.0 && yfov < 180.0, "{}: yfov_deg {yfov} is outside (0, 180)", context());
        let znear = c.znear.unwrap_or(0.05);
        ensure!(znear > 0.0 && znear.is_finite(), "{}: znear must be positive", context());
        let Some(up) = c.up else {
            let forward = (target - position).normalize().as_vec3();
            // Not parallel to the view direction (as `Camera::look_at`).
            let up = if forward.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y };
            return Ok(Camera::look_at_up_f64(&name, position, target, up, yfov.to_radians(), znear));
        };
        let up = finite3(up, "up").with_context(context)?;
        let forward = (target - position).normalize().as_vec3();
        ensure!(
            up.length() > 0.0 && up.normalize().cross(forward).length() > 1e-3,
            "{}: up {up} is zero or parallel to the view direction",
            context()
        );
        Ok(Camera::look_at_up_f64(&name, position, target, up, yfov.to_radians(), znear))
    }

    fn camera_path(&self, keys: Vec<CameraKeyDef>) -> Result<Vec<CameraKey>> {
        let mut out: Vec<CameraKey> = Vec::with_capacity(keys.len());
        for k in keys {
            let at = self.at(k.time.span().start);
            let time = finite(*k.time.get_ref(), "time").with_context(|| at.clone())?;
            if let Some(prev) = out.last() {
                ensure!(
                    time > prev.time,
                    "{at}: camera_path times must increase (time {time} follows {})",
                    prev.time
                );
            }
            let position = finite3(k.position, "position").with_context(|| at.clone())?;
            let target = finite3(k.target, "target").with_context(|| at.clone())?;
            out.push(CameraKey { time, position, target });
        }
        Ok(out)
    }

    fn light(&self, l: LightDef, index: usize) -> Result<Light> {
        let kind = *l.kind.get_ref();
        let name = l.name.clone().unwrap_or_else(|| format!("light {index}"));
        let at = self.at(l.kind.span().start);
        light_from_def(l, kind, name.clone()).with_context(|| format!("{at}: light '{name}'"))
    }

    fn add_material(&mut self, m: MaterialDef) -> Result<()> {
        let name = m.name.get_ref().clone();
        let at = self.at(m.name.span().start);
        ensure!(!self.materials.contains_key(&name), "{at}: material '{name}' is defined twice");
        let material = material_from_def(m).with_context(|| format!("{at}: material '{name}'"))?;
        self.materials.insert(name, self.scene.materials.len());
        self.scene.materials.push(material);
        Ok(())
    }

    fn lookup_material(&self, name: &Spanned<String>) -> Result<usize> {
        self.materials.get(name.get_ref()).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.materials.keys().map(String::as_str).collect();
            known.sort_unstable();
            anyhow!(
                "unknown material '{}' (line {}; defined: {})",
                name.get_ref(),
                self.line(name.span().start),
                if known.is_empty() { "none".to_string() } else { known.join(", ") }
            )
        })
    }

    /// The white dielectric used by primitives and OBJ models without a
    /// `material`, added on first use.
    fn default_material(&mut self) -> usize {
        *self.default_material.get_or_insert_with(|| {
            let material = Material {
                name: "scene default".into(),
                metallic: 0.0,
                roughness: 0.5,
                ..Default::default()
            };
            self.scene.materials.push(material);
            self.scene.materials.len() - 1
        })
    }

    fn add_object(&mut self, o: ObjectDef, context: &str) -> Result<()> {
        let material = o.material.as_ref().map(|m| self.lookup_material(m)).transpose()?;
        let local = object_transform(&o)?;
        // Checked before any model is loaded: a typo fails fast.
        let orbit = o.orbit.as_ref().map(orbit_from_def).transpose()?;
        let props = ObjectProps {
            relevance: non_negative(o.relevance.unwrap_or(1.0), "relevance")?,
            cost: non_negative(o.cost.unwrap_or(1.0), "cost")?,
            casts_shadows: o.casts_shadows.unwrap_or(true),
            material_override: None,
        };
        let name = o.name.get_ref().clone();
        let object = self.scene.objects.len();
        self.scene.objects.push(Object { name: name.clone(), props });
        let node = match (&o.gltf, &o.obj, o.primitive) {
            (Some(file), None, None) => {
                check_no_shape_parameters(&o, "a glTF model")?;
                let imported = gltf_import::load(&self.resolve(file))?;
                self.scene.objects[object].props.material_override = material;
                merge(&mut self.scene, imported, &name, local, object)
            }
            (None, Some(file), None) => {
                check_no_shape_parameters(&o, "an OBJ model")?;
                let mut mesh = obj::load_mesh(&self.resolve(file))?;
                let material = material.unwrap_or_else(|| self.default_material());
                mesh.primitives.iter_mut().for_each(|p| p.material = material);
                self.add_mesh_node(mesh, &name, local, object)
            }
            (None, None, Some(kind)) => {
                let mut primitive = procedural(&o, kind)?;
                primitive.material = material.unwrap_or_else(|| self.default_material());
                let mesh = Mesh { name: name.clone(), primitives: vec![primitive] };
                self.add_mesh_node(mesh, &name, local, object)
            }
            _ => bail!("needs exactly one of `gltf`, `obj` or `primitive`"),
        };
        if let Some(spec) = orbit {
            let pivot = self.add_pivot(node, spec.center, &name);
            let (axis, period) = (spec.axis, spec.period);
            self.orbits.push(Orbit { pivot, axis, period, context: context.to_string() });
        }
        Ok(())
    }

    /// Adds a root node for `mesh`; returns its index.
    fn add_mesh_node(&mut self, mesh: Mesh, name: &str, local: Transform, object: usize) -> usize {
        let node = self.scene.nodes.len();
        self.scene.nodes.push(Node {
            name: name.to_string(),
            local,
            mesh: Some(self.scene.meshes.len()),
            object: Some(object),
            ..Default::default()
        });
        self.scene.meshes.push(mesh);
        self.scene.roots.push(node);
        node
    }
}
