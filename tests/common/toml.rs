//! Scene files as TOML text, assembled from blocks rather than written out:
//! the format src/scene/scene_file reads (`[environment]`, `[[camera]]`,
//! `[[light]]`, `[[material]]`, `[[object]]`). Each block keeps its keys in
//! the order they were set; a scene is its blocks in order (the order of
//! materials and objects is the order of the scene's lists).
//!
//! Numbers are written as the tests write them by hand: a float as `{:?}`
//! (`1.0`, `0.7`), an integer as an integer (`yfov_deg = 60`), so a test
//! picks the TOML type with its literal; [`shown`] writes `{}` (2.0 as `2`,
//! an integer) and [`Raw`] any text a test formats itself.
//!
//! ```text
//! scene_toml([
//!     black_sky(),
//!     camera([0.0, 1.0, 5.0], [0.0; 3]).yfov(50),
//!     no_light(),
//!     lambert("white", [0.8; 3]),
//!     sphere("ball", 1.0).at([0.0, 1.0, 0.0]).material("white"),
//! ])
//! ```
#![allow(dead_code)]

use std::fmt;

/// A value as TOML text.
pub trait Value {
    fn toml(&self) -> String;
}

/// Floats as `{:?}` (always a decimal point or an exponent: a TOML float),
/// integers and booleans as `{}`.
macro_rules! values {
    ($fmt:literal: $($t:ty),*) => {
        $(impl Value for $t {
            fn toml(&self) -> String {
                format!($fmt, self)
            }
        })*
    };
}
values!("{:?}": f32, f64);
values!("{}": i32, u32, bool);

/// A basic string (`"…"`): names, materials, file paths.
impl Value for str {
    fn toml(&self) -> String {
        format!("\"{}\"", self.replace('\\', "\\\\").replace('"', "\\\""))
    }
}

impl Value for String {
    fn toml(&self) -> String {
        self.as_str().toml()
    }
}

impl<T: Value + ?Sized> Value for &T {
    fn toml(&self) -> String {
        (**self).toml()
    }
}

impl<T: Value, const N: usize> Value for [T; N] {
    fn toml(&self) -> String {
        let items: Vec<String> = self.iter().map(Value::toml).collect();
        format!("[{}]", items.join(", "))
    }
}

/// TOML text written as is: a number a test formats itself, an inline table.
#[derive(Clone, Debug)]
pub struct Raw(pub String);

impl Value for Raw {
    fn toml(&self) -> String {
        self.0.clone()
    }
}

/// `{}` formatting: 0.5 is `0.5` but 2.0 is `2`, an integer.
pub fn shown(x: impl fmt::Display) -> Raw {
    Raw(x.to_string())
}

/// `[x, y, z]` with `{}` formatting (see [`shown`]).
pub fn shown3(v: [f32; 3]) -> [Raw; 3] {
    v.map(shown)
}

/// One table (`[environment]`) or array-of-tables entry (`[[object]]`).
#[derive(Clone, Debug)]
pub struct Block {
    header: String,
    lines: Vec<String>,
}

impl Block {
    /// An empty block under `header` (`"[[object]]"`).
    pub fn new(header: &str) -> Block {
        Block { header: header.to_string(), lines: Vec::new() }
    }

    /// `key = value`, in place of the key's earlier value if it has one.
    pub fn set(mut self, key: &str, value: impl Value) -> Block {
        let line = format!("{key} = {}", value.toml());
        let prefix = format!("{key} = ");
        match self.lines.iter_mut().find(|l| l.starts_with(&prefix)) {
            Some(old) => *old = line,
            None => self.lines.push(line),
        }
        self
    }

    /// `key = true`.
    pub fn flag(self, key: &str) -> Block {
        self.set(key, true)
    }

    /// A spot light's cone angles.
    pub fn cones(self, inner_deg: impl Value, outer_deg: impl Value) -> Block {
        self.set("inner_cone_deg", inner_deg).set("outer_cone_deg", outer_deg)
    }

    /// `casts_shadows = false` (lights, materials, objects).
    pub fn no_shadows(self) -> Block {
        self.set("casts_shadows", false)
    }

    /// `double_sided = true`.
    pub fn double_sided(self) -> Block {
        self.flag("double_sided")
    }

    /// An object's material, by name.
    pub fn material(self, material: &str) -> Block {
        self.set("material", material)
    }

    /// A sphere's tessellation.
    pub fn slices(self, slices: u32, stacks: u32) -> Block {
        self.set("slices", slices).set("stacks", stacks)
    }
}

/// `Block` methods that set one key each.
macro_rules! keys {
    ($($(#[$doc:meta])* $method:ident => $key:literal,)*) => {
        impl Block {
            $($(#[$doc])* pub fn $method(self, value: impl Value) -> Block {
                self.set($key, value)
            })*
        }
    };
}
keys! {
    // Cameras.
    yfov => "yfov_deg",
    up => "up",
    znear => "znear",
    // Lights (and the environment).
    color => "color",
    intensity => "intensity",
    // Materials.
    base => "base_color",
    metallic => "metallic",
    roughness => "roughness",
    ior => "ior",
    specular => "specular",
    specular_color => "specular_color",
    clearcoat => "clearcoat",
    clearcoat_roughness => "clearcoat_roughness",
    transmission => "transmission",
    emissive => "emissive",
    // Objects.
    /// `translation`.
    at => "translation",
    /// `rotation_deg`.
    rot => "rotation_deg",
    /// A number, or per axis.
    scale => "scale",
}

impl fmt::Display for Block {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        writeln!(f, "\n{}", self.header)?;
        for line in &self.lines {
            writeln!(f, "{line}")?;
        }
        Ok(())
    }
}

/// A scene file's text: its blocks in order.
pub fn scene_toml(blocks: impl IntoIterator<Item = Block>) -> String {
    blocks.into_iter().map(|b| b.to_string()).collect()
}

/// `[environment]` of constant radiance `color`.
pub fn environment(color: impl Value) -> Block {
    Block::new("[environment]").color(color)
}

/// A black sky.
pub fn black_sky() -> Block {
    environment([0.0, 0.0, 0.0])
}

/// `[environment]` lit by the map at `hdr`.
pub fn environment_hdr(hdr: impl fmt::Display) -> Block {
    Block::new("[environment]").set("hdr", hdr.to_string())
}

pub fn camera(position: impl Value, target: impl Value) -> Block {
    Block::new("[[camera]]").set("position", position).set("target", target)
}

/// A light of type `kind` with no other key.
pub fn light(kind: &str) -> Block {
    Block::new("[[light]]").set("type", kind)
}

pub fn directional(direction: impl Value, intensity: impl Value) -> Block {
    light("directional").set("direction", direction).intensity(intensity)
}

/// A sun straight down of intensity 0: scenes lit by their sky or emission
/// alone.
pub fn no_light() -> Block {
    directional([0.0, -1.0, 0.0], 0.0)
}

pub fn point(position: impl Value, intensity: impl Value) -> Block {
    light("point").set("position", position).intensity(intensity)
}

pub fn spot(position: impl Value, direction: impl Value, intensity: impl Value) -> Block {
    light("spot").set("position", position).set("direction", direction).intensity(intensity)
}

pub fn material(name: &str) -> Block {
    Block::new("[[material]]").set("name", name)
}

/// Diffuse: `base` at roughness 1.
pub fn lambert(name: &str, base: impl Value) -> Block {
    material(name).base(base).roughness(1.0)
}

/// A smooth metal of reflectance `base`.
pub fn mirror(name: &str, base: impl Value) -> Block {
    material(name).base(base).metallic(1.0).roughness(0.0)
}

/// Clear smooth glass (white, transmission 1) of index `ior`.
pub fn glass(name: &str, ior: impl Value) -> Block {
    material(name).base([1.0, 1.0, 1.0]).roughness(0.0).transmission(1.0).ior(ior)
}

/// The tests' matte clay ("clay").
pub fn clay() -> Block {
    material("clay").base([0.7, 0.6, 0.5]).roughness(0.8)
}

/// Black, emitting `emissive`.
pub fn emitter(name: &str, emissive: impl Value) -> Block {
    material(name).base([0.0, 0.0, 0.0]).emissive(emissive)
}

/// An object with a name only (a model or a primitive follows).
pub fn object(name: &str) -> Block {
    Block::new("[[object]]").set("name", name)
}

/// A primitive of its default size.
pub fn primitive(name: &str, kind: &str) -> Block {
    object(name).set("primitive", kind)
}

/// A plane in XZ facing +Y, `size` its side or its [x, z] extent.
pub fn plane(name: &str, size: impl Value) -> Block {
    primitive(name, "plane").set("size", size)
}

pub fn cube(name: &str, size: impl Value) -> Block {
    primitive(name, "cube").set("size", size)
}

pub fn sphere(name: &str, radius: impl Value) -> Block {
    primitive(name, "sphere").set("radius", radius)
}

/// An object loaded from the glTF file at `path`.
pub fn gltf(name: &str, path: impl fmt::Display) -> Block {
    object(name).set("gltf", path.to_string())
}
