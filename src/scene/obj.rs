//! Minimal Wavefront OBJ reader for scanned models (the Stanford meshes):
//! geometry only, one primitive, materials are the caller's business.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::{Vec2, Vec3};

use super::tangents::{bounds_of, fill_fallback_tangents, generate_tangents, smooth_normals};
use super::{Material, Mesh, Node, Object, Primitive, Scene, Vertex};

/// Loads every face of an OBJ file into one triangle-list primitive with
/// material index 0. Missing normals are generated smooth (area-weighted per
/// position, so UV seams do not crease the shading).
pub fn load_mesh(path: &Path) -> Result<Mesh> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("{}: cannot read OBJ file", path.display()))?;
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    parse(&text, &name, path)
}

/// An OBJ file as a one-node scene with a default material.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let mesh = load_mesh(path)?;
    let name = mesh.name.clone();
    Ok(Scene {
        meshes: vec![mesh],
        materials: vec![Material::default()],
        nodes: vec![Node { name: name.clone(), mesh: Some(0), object: Some(0), ..Default::default() }],
        roots: vec![0],
        objects: vec![Object { name, props: Default::default() }],
        ..Default::default()
    })
}

/// One face corner: position, optional texcoord and normal (0-based).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Corner {
    v: usize,
    vt: Option<usize>,
    vn: Option<usize>,
}

#[derive(Default)]
struct Parsed {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    triangles: Vec<[Corner; 3]>,
}

/// Parses OBJ text; `file` only names the source in error messages.
fn parse(text: &str, name: &str, file: &Path) -> Result<Mesh> {
    let mut p = Parsed::default();
    let mut skipped_elements = 0usize;
    for (number, line) in text.lines().enumerate() {
        let at = || format!("{}:{}", file.display(), number + 1);
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword {
            "v" => p.positions.push(parse_floats::<3>(words, 3).map(Vec3::from).with_context(at)?),
            "vn" => p.normals.push(parse_floats::<3>(words, 3).map(Vec3::from).with_context(at)?),
            // OBJ's v axis points up, glTF's (and ours) down the image.
            "vt" => {
                let [u, v] = parse_floats::<2>(words, 1).with_context(at)?;
                p.uvs.push(Vec2::new(u, 1.0 - v));
            }
            "f" => parse_face(words, &mut p).with_context(at)?,
            "l" | "p" => skipped_elements += 1,
            // Groups, smoothing groups and materials do not matter here.
            _ => {}
        }
    }
    if skipped_elements > 0 {
        log::warn!("{}: ignored {skipped_elements} point/line elements", file.display());
    }
    if p.triangles.is_empty() {
        bail!("{}: OBJ file has no faces", file.display());
    }
    build_mesh(p, name).with_context(|| file.display().to_string())
}

/// Reads up to N floats, requiring at least `required`; missing optional
/// components are zero and extra ones (w, vertex colours) are ignored.
fn parse_floats<'a, const N: usize>(
    words: impl Iterator<Item = &'a str>,
    required: usize,
) -> Result<[f32; N]> {
    let mut out = [0.0; N];
    let mut count = 0;
    for (slot, word) in out.iter_mut().zip(words) {
        let value: f32 = word.parse().with_context(|| format!("'{word}' is not a number"))?;
        if !value.is_finite() {
            bail!("non-finite value '{word}'");
        }
        *slot = value;
        count += 1;
    }
    if count < required {
        bail!("expected {required} numbers, found {count}");
    }
    Ok(out)
}

/// A polygon of any size, triangulated as a fan around its first corner.
fn parse_face<'a>(words: impl Iterator<Item = &'a str>, p: &mut Parsed) -> Result<()> {
    let corners = words.map(|w| parse_corner(w, p)).collect::<Result<Vec<_>>>()?;
    if corners.len() < 3 {
        bail!("face has {} vertices, need at least 3", corners.len());
    }
    for i in 1..corners.len() - 1 {
        p.triangles.push([corners[0], corners[i], corners[i + 1]]);
    }
    Ok(())
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn`.
fn parse_corner(word: &str, p: &Parsed) -> Result<Corner> {
    let mut parts = word.split('/');
    let v = resolve(parts.next(), p.positions.len(), "vertex")?
        .with_context(|| format!("face corner '{word}' has no vertex index"))?;
    let vt = resolve(parts.next(), p.uvs.len(), "texture coordinate")?;
    let vn = resolve(parts.next(), p.normals.len(), "normal")?;
    if parts.next().is_some() {
        bail!("malformed face corner '{word}'");
    }
    Ok(Corner { v, vt, vn })
}

/// 1-based or negative (relative to the elements defined so far) index.
fn resolve(field: Option<&str>, defined: usize, what: &str) -> Result<Option<usize>> {
    let Some(field) = field.filter(|f| !f.is_empty()) else { return Ok(None) };
    let i: i64 = field.parse().with_context(|| format!("'{field}' is not a {what} index"))?;
    let resolved = if i > 0 { i - 1 } else { defined as i64 + i };
    if i == 0 || resolved < 0 || resolved >= defined as i64 {
        bail!("{what} index {i} is out of range ({defined} defined so far)");
    }
    Ok(Some(resolved as usize))
}

/// De-duplicates corners into vertices and fills missing attributes.
fn build_mesh(p: Parsed, name: &str) -> Result<Mesh> {
    let needs_normals = p.triangles.iter().flatten().any(|c| c.vn.is_none());
    let generated = if needs_normals {
        let tris: Vec<[usize; 3]> = p.triangles.iter().map(|t| t.map(|c| c.v)).collect();
        smooth_normals(&p.positions, &tris)
    } else {
        Vec::new()
    };
    let mut lookup: HashMap<Corner, u32> = HashMap::new();
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut indices = Vec::with_capacity(p.triangles.len() * 3);
    for corner in p.triangles.iter().flatten() {
        let index = match lookup.get(corner) {
            Some(&i) => i,
            None => {
                let i = u32::try_from(vertices.len()).context("more than 2^32 vertices")?;
                let normal = match corner.vn {
                    Some(n) => p.normals[n].try_normalize().unwrap_or(Vec3::Y),
                    None => generated[corner.v],
                };
                vertices.push(Vertex {
                    position: p.positions[corner.v].to_array(),
                    normal: normal.to_array(),
                    uv: corner.vt.map(|t| p.uvs[t]).unwrap_or(Vec2::ZERO).to_array(),
                    tangent: [0.0; 4],
                });
                lookup.insert(*corner, i);
                i
            }
        };
        indices.push(index);
    }
    if p.uvs.is_empty() {
        fill_fallback_tangents(&mut vertices);
    } else {
        generate_tangents(&mut vertices, &indices);
    }
    let bounds = bounds_of(&vertices);
    Ok(Mesh {
        name: name.to_string(),
        primitives: vec![Primitive { vertices, indices, material: 0, bounds, skin: None }],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Mesh> {
        parse(text, "test", Path::new("inline.obj"))
    }

    #[test]
    fn quads_and_negative_indices() {
        let text = "# a unit square as one quad, then a triangle via negative indices\n\
                    v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    vn 0 0 1\n\
                    f 1/1/1 2/2/1 3/3/1 4/4/1\n\
                    v 0 0 1\n\
                    f -1//-1 -5//1 -4//1\n";
        let mesh = parse_str(text).unwrap();
        let p = &mesh.primitives[0];
        assert_eq!(p.indices.len(), 9);
        // The quad's 4 corners plus 3 new (position, normal) combinations.
        assert_eq!(p.vertices.len(), 7);
        assert_eq!(p.vertices[0].uv, [0.0, 1.0], "v is flipped to glTF's top-left origin");
        assert_eq!(p.vertices[p.indices[6] as usize].position, [0.0, 0.0, 1.0]);
        assert_eq!(p.vertices[p.indices[7] as usize].position, [0.0, 0.0, 0.0]);
        assert!(p.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
        assert_eq!(p.bounds.max, Vec3::ONE);
    }

    #[test]
    fn missing_normals_are_generated_smooth() {
        let mesh = parse_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\n").unwrap();
        let p = &mesh.primitives[0];
        assert_eq!(p.vertices.len(), 4);
        // Vertex 1 is shared by the -Z and -Y facing triangles.
        let n = Vec3::from(p.vertices[0].normal);
        assert!((n - Vec3::new(0.0, -1.0, -1.0).normalize()).length() < 1e-5, "{n}");
        for v in &p.vertices {
            let t = Vec3::from_slice(&v.tangent[..3]);
            assert!(t.dot(Vec3::from(v.normal)).abs() < 1e-5 && (t.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn errors_name_file_and_line() {
        let err = format!("{:#}", parse_str("v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap_err());
        assert!(err.contains("inline.obj:3") && err.contains("vertex index 3"), "{err}");
        let err = format!("{:#}", parse_str("v 0 0 0\nv 1 x 0\n").unwrap_err());
        assert!(err.contains("inline.obj:2") && err.contains("'x'"), "{err}");
        let err = format!("{:#}", parse_str("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err());
        assert!(err.contains("inline.obj:3") && err.contains("at least 3"), "{err}");
        let err = format!("{:#}", parse_str("v 0 0 0\n").unwrap_err());
        assert!(err.contains("no faces"), "{err}");
        let err = format!("{:#}", load_mesh(Path::new("/nonexistent/x.obj")).unwrap_err());
        assert!(err.contains("/nonexistent/x.obj"), "{err}");
    }

    #[test]
    fn stanford_bunny_loads() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/assets/stanford/bunny/stanford-bunny.obj"
        ));
        let mesh = load_mesh(path).unwrap_or_else(|e| panic!("missing shared asset: {e:#}"));
        let p = &mesh.primitives[0];
        assert_eq!(p.indices.len() / 3, 69_451);
        // The scan has a few unreferenced vertices, which are dropped.
        assert!(p.vertices.len() <= 35_947 && p.vertices.len() > 34_000, "{}", p.vertices.len());
        assert!(!p.bounds.is_empty());
    }
}
