//! The compute tracer's flattened static geometry: ONE BVH (a split BVH up to a size), collapsed
//! 4-wide, over the world-space triangles of every instance that never moves, triangles in leaf order
//! (glsl/trace/compute.glsl `FlatTri`).
//!
//! Why: Sponza's ~160 static instances overlap, so a two-level ray enters many BLASes, each costing
//! an instance fetch, ray transform, watertight setup and root test; here a leaf is one contiguous
//! read. Each triangle keeps its (instance, primitive), so hits shade as on the two-level path, and
//! its instance's ray mask bits (shadow-only and invisible-to-shadow instances).
//!
//! Not every static instance: a mesh placed many times (a forest of one rock) would be copied once
//! per placement, so a primitive's static copies are flattened only while they cost at most
//! [`FLAT_MAX_COPIES`] times its own triangles or [`FLAT_ALWAYS_TRIANGLES`] in all; the rest stay
//! instances of one BLAS in the two-level BVH (`flatten_choice`).

use glam::{DVec3, Vec3};

use std::path::Path;

use super::bvh::{Bvh, BvhNode, StaticBuilder, WideBvh, WideNode};
use super::flat_cache::{self, CACHE_MIN_TRIANGLES};
use super::{instance_mask, instance_opaque};
use crate::gpu::origin::RenderOrigin;
use crate::scene::{Instance, Scene};
use std::collections::HashMap;

/// One triangle of the flat tree, 40 bytes; mirrors `FlatTri` in glsl/trace/compute.glsl.
///
/// Why no instance and primitive words (48 bytes before): the triangle's number in the tree's
/// triangle numbering (`FLAT_ID_INDEX` bits) names both through [`FlatStatic::members`], which the
/// tracer searches once per accepted hit, and the two flags a leaf test needs per triangle ride in the
/// top bits. 8 bytes per triangle: 32 MB of the 4 M triangle terrain.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FlatTriangle {
    /// Relative to the render origin, like every GPU position.
    pub p0: [f32; 3],
    pub p1: [f32; 3],
    pub p2: [f32; 3],
    /// Tree triangle number | opaque << FLAT_ID_OPAQUE_SHIFT | ray mask << FLAT_ID_MASK_SHIFT.
    pub id: u32,
}
const _: () = assert!(std::mem::size_of::<FlatTriangle>() == 40);

/// The `id` bits below the flags: at most 2^29 triangles in the tree (more than 50 GB of them).
pub const FLAT_ID_INDEX: u32 = crate::gpu::shared::FLAT_ID_INDEX;
pub const FLAT_ID_OPAQUE_SHIFT: u32 = crate::gpu::shared::FLAT_ID_OPAQUE_SHIFT;
pub const FLAT_ID_MASK_SHIFT: u32 = crate::gpu::shared::FLAT_ID_MASK_SHIFT;

/// A member instance's flag bits of `FlatTriangle::id`: its ray mask and whether it is opaque.
pub fn member_flags(scene: &Scene, instance: usize) -> u32 {
    let inst = &scene.instances[instance];
    (instance_mask(scene, inst) as u32) << FLAT_ID_MASK_SHIFT
        | (instance_opaque(scene, inst) as u32) << FLAT_ID_OPAQUE_SHIFT
}

/// What a `FlatTriangle::id` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FlatId {
    pub instance: u32,
    pub primitive: u32,
    pub mask: u32,
    pub opaque: bool,
}

pub struct FlatStatic {
    /// The root box of the binary tree the 4-wide one was collapsed from (None: no triangles).
    pub root: Option<BvhNode>,
    /// The binary tree's SAH cost.
    pub sah: f32,
    /// Which builder made it (by size: [`StaticBuilder::for_triangles`]).
    pub builder: StaticBuilder,
    /// The 4-wide collapse; leaf ranges index `triangles` directly.
    pub nodes: Vec<WideNode>,
    /// Per member instance with triangles, by tree triangle number: [first number, instance]. The
    /// tracer's lookup from a triangle's `id` to its (instance, primitive) (`flat_members`).
    pub members: Vec<[u32; 2]>,
    /// In leaf order: `triangles[k]` is reference `k` of the wide tree (a
    /// spatial split may reference a triangle twice).
    pub triangles: Vec<FlatTriangle>,
    /// Distinct triangles in the tree.
    pub source_triangles: usize,
    /// Per scene instance: whether it is in this tree (and so not in the
    /// top level).
    pub flattened: Vec<bool>,
    /// Whether the tree was read from the disk cache (`flat_cache`) instead of built.
    pub cached: bool,
    /// Host ms of the build's stages: world-space transform, binary build, 4-wide collapse, gather of
    /// the triangles in leaf order (zeros when read from the cache).
    pub stages_ms: [f64; 4],
}

/// Milliseconds since the last lap.
struct StageClock(std::time::Instant);

impl StageClock {
    fn lap(&mut self) -> f64 {
        let now = std::time::Instant::now();
        let ms = (now - self.0).as_secs_f64() * 1e3;
        self.0 = now;
        ms
    }
}

/// Per node: whether an animation channel moves it or one of its ancestors.
pub fn animated_nodes(scene: &Scene) -> Vec<bool> {
    let mut targeted = vec![false; scene.nodes.len()];
    for c in scene.animations.iter().flat_map(|a| &a.channels) {
        if let Some(t) = targeted.get_mut(c.node) {
            *t = true;
        }
    }
    (0..scene.nodes.len())
        .map(|n| {
            let mut cur = Some(n);
            // Bounded by the node count, so a malformed cycle cannot hang.
            for _ in 0..=scene.nodes.len() {
                let Some(c) = cur else { return false };
                if targeted[c] {
                    return true;
                }
                cur = scene.nodes[c].parent;
            }
            false
        })
        .collect()
}

/// Per instance: whether it belongs in the flat tree (rigid and never
/// animated; the scene moves nothing else after loading).
pub fn static_instances(scene: &Scene) -> Vec<bool> {
    let animated = animated_nodes(scene);
    scene
        .instances
        .iter()
        .map(|i| i.skinned.is_none() && !animated.get(i.node).copied().unwrap_or(true))
        .collect()
}

/// A primitive's static copies are flattened while they hold at most this many times its triangles ...
pub const FLAT_MAX_COPIES: usize = 4;
/// ... or at most this many triangles in all (a small mesh placed a few thousand times).
pub const FLAT_ALWAYS_TRIANGLES: usize = 1 << 16;

/// Per instance: whether it goes into the flat tree: static (`static_instances`) and of a primitive
/// whose static copies pass the [`FLAT_MAX_COPIES`] / [`FLAT_ALWAYS_TRIANGLES`] rule.
pub fn flatten_choice(scene: &Scene) -> Vec<bool> {
    let statics = static_instances(scene);
    let mut copies: HashMap<(usize, usize), usize> = HashMap::new();
    for inst in scene.instances.iter().zip(&statics).filter(|(_, s)| **s).map(|(i, _)| i) {
        *copies.entry((inst.mesh, inst.primitive)).or_default() += 1;
    }
    let flatten = |inst: &Instance| {
        let n = copies.get(&(inst.mesh, inst.primitive)).copied().unwrap_or(0);
        let tris = scene.meshes[inst.mesh].primitives[inst.primitive].indices.len() / 3;
        n <= FLAT_MAX_COPIES || n.saturating_mul(tris) <= FLAT_ALWAYS_TRIANGLES
    };
    scene.instances.iter().zip(statics).map(|(inst, s)| s && flatten(inst)).collect()
}

/// Large meshes are transformed and gathered on every core, in chunks of this many items.
const PAR_CHUNK: usize = 1 << 15;

/// `(0..n).map(f).collect()`, on every core when `n` is large.
fn collect<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    crate::par::collect_each(n, PAR_CHUNK, f).unwrap_or_else(|e| panic!("flat tree: {e}"))
}

/// Which member holds tree triangle number `t`.
fn member_of(table: &[[u32; 2]], t: usize) -> usize {
    table.partition_point(|m| m[0] as usize <= t) - 1
}

/// The members' triangles in world space relative to `origin`, numbered as `table` says.
fn world_triangles(
    scene: &Scene,
    origin: RenderOrigin,
    members: &[usize],
    table: &[[u32; 2]],
    count: usize,
) -> Vec<[Vec3; 3]> {
    let primitive = |i: usize| {
        let inst = &scene.instances[i];
        &scene.meshes[inst.mesh].primitives[inst.primitive]
    };
    // Each vertex once (an indexed mesh shares each by about six triangles); f64 until the end: one
    // rounding per coordinate.
    let world: Vec<Vec<Vec3>> = members
        .iter()
        .map(|&i| {
            let (m, p) = (origin.relative(&scene.instances[i].world), primitive(i));
            collect(p.vertices.len(), |v| {
                m.transform_point3(DVec3::from(Vec3::from(p.vertices[v].position))).as_vec3()
            })
        })
        .collect();
    collect(count, |t| {
        let k = member_of(table, t);
        let local = t - table[k][0] as usize;
        let (w, idx) = (&world[k], &primitive(members[k]).indices[3 * local..3 * local + 3]);
        [w[idx[0] as usize], w[idx[1] as usize], w[idx[2] as usize]]
    })
}

/// The triangles the flat tree would hold (its members', in world space relative to `origin`), for
/// builders measured against its own (`bench --builders`).
pub fn static_triangles(scene: &Scene, origin: RenderOrigin) -> Vec<[Vec3; 3]> {
    let flattened = flatten_choice(scene);
    let flags: Vec<u32> = (0..scene.instances.len()).map(|i| member_flags(scene, i)).collect();
    let (members, table, count) = member_table(scene, &flattened, &flags);
    world_triangles(scene, origin, &members, &table, count)
}

/// The members (flattened instances a ray can hit, with triangles), the member table ([first number,
/// instance] each) and the triangle count.
fn member_table(scene: &Scene, flattened: &[bool], flags: &[u32]) -> (Vec<usize>, Vec<[u32; 2]>, usize) {
    let (mut members, mut table, mut count) = (Vec::new(), Vec::new(), 0usize);
    for i in (0..scene.instances.len()).filter(|&i| flattened[i] && flags[i] >> FLAT_ID_MASK_SHIFT != 0) {
        let inst = &scene.instances[i];
        let n = scene.meshes[inst.mesh].primitives[inst.primitive].indices.len() / 3;
        if n > 0 {
            members.push(i);
            table.push([count as u32, i as u32]);
            count += n;
        }
    }
    (members, table, count)
}

impl FlatStatic {
    /// In world space relative to `origin`; instances no ray can hit (mask 0) contribute no triangles.
    /// With a `cache` directory, a tree of at least [`CACHE_MIN_TRIANGLES`] is read from there when an
    /// intact file for the same geometry exists, and written there when it is built.
    pub fn build(scene: &Scene, origin: RenderOrigin, cache: Option<&Path>) -> anyhow::Result<FlatStatic> {
        let flattened = flatten_choice(scene);
        let flags: Vec<u32> = (0..scene.instances.len()).map(|i| member_flags(scene, i)).collect();
        let (members, table, count) = member_table(scene, &flattened, &flags);
        anyhow::ensure!(
            count <= FLAT_ID_INDEX as usize + 1,
            "{count} static triangles: more than the {} the compute BVH's flat tree can number",
            FLAT_ID_INDEX as usize + 1
        );
        let file = cache.filter(|_| count >= CACHE_MIN_TRIANGLES).map(|dir| {
            let key = flat_cache::key(scene, origin, &members, &flags);
            (flat_cache::path(dir, key), key)
        });
        if let Some((path, key)) = &file {
            if path.exists() {
                let t = std::time::Instant::now();
                match flat_cache::load(path, *key, flattened.clone(), table.clone()) {
                    Ok(flat) => {
                        log::info!(
                            "compute BVH: flat tree of {count} triangles read from {} in {:.0} ms",
                            path.display(),
                            t.elapsed().as_secs_f64() * 1e3
                        );
                        return Ok(flat);
                    }
                    Err(e) => {
                        log::warn!("compute BVH: ignoring cache file {}: {e:#}; rebuilding", path.display())
                    }
                }
            }
        }
        let mut clock = StageClock(std::time::Instant::now());
        let tris = world_triangles(scene, origin, &members, &table, count);
        let transform_ms = clock.lap();
        crate::progress::stage(format!("building the compute BVH over {count} triangles"));
        let (bvh, builder) = Bvh::build_static(&tris);
        let build_ms = clock.lap();
        crate::progress::stage("collapsing the compute BVH 4-wide");
        let wide = WideBvh::from_binary(&bvh);
        let collapse_ms = clock.lap();
        // In leaf order, on every core (a random-access gather); each id from the member table.
        let triangles = collect(wide.prim_indices.len(), |j| {
            let k = wide.prim_indices[j] as usize;
            let [p0, p1, p2] = tris[k];
            let id = k as u32 | flags[members[member_of(&table, k)]];
            FlatTriangle { p0: p0.into(), p1: p1.into(), p2: p2.into(), id }
        });
        let stages_ms = [transform_ms, build_ms, collapse_ms, clock.lap()];
        let flat = FlatStatic {
            root: bvh.nodes.first().copied(),
            sah: bvh.sah_cost(),
            builder,
            nodes: wide.nodes,
            members: table,
            triangles,
            source_triangles: tris.len(),
            flattened,
            cached: false,
            stages_ms,
        };
        if let Some((path, key)) = &file {
            // A cache that cannot be written costs a rebuild next time, not this run.
            if let Err(e) = flat_cache::store(path, *key, &flat) {
                log::warn!("compute BVH: cannot write cache file {}: {e:#}", path.display());
            }
        }
        Ok(flat)
    }

    /// Bytes on the GPU: wide nodes, the triangles and the member table.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
            + self.triangles.len() * std::mem::size_of::<FlatTriangle>()
            + self.members.len() * 8
    }

    /// What a triangle's `id` names: the member whose numbers hold it (the tracer's `flat_resolve`).
    pub fn resolve(&self, id: u32) -> FlatId {
        let index = id & FLAT_ID_INDEX;
        let k = self.members.partition_point(|m| m[0] <= index) - 1;
        let [first, instance] = self.members[k];
        FlatId {
            instance,
            primitive: index - first,
            mask: id >> FLAT_ID_MASK_SHIFT,
            opaque: (id >> FLAT_ID_OPAQUE_SHIFT) & 1 != 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{MASK_SHADOW, MASK_VISIBLE};
    use crate::scene::animation::{Animation, AnimationChannel, Channel, Interpolation};
    use crate::scene::{Material, Mesh, Node, Primitive, Transform, Vertex};
    use glam::Quat;
    use std::collections::HashMap;

    fn quad(material: usize) -> Primitive {
        let v = |x: f32, y: f32| Vertex { position: [x, y, 0.0], ..Default::default() };
        Primitive {
            vertices: vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)],
            indices: vec![0, 1, 2, 0, 2, 3],
            material,
            ..Default::default()
        }
    }

    /// Three nodes sharing one two-quad mesh (materials: casts shadows,
    /// does not), the third under an animated parent.
    fn scene() -> Scene {
        let mut s = Scene {
            materials: vec![
                Material::default(),
                Material { casts_shadows: false, transmission: 0.5, ..Default::default() },
            ],
            meshes: vec![Mesh { primitives: vec![quad(0), quad(1)], ..Default::default() }],
            ..Default::default()
        };
        let place = |translation: DVec3, rotation: Quat, s: f32| Transform {
            translation,
            rotation,
            scale: Vec3::splat(s),
        };
        let mesh_node = |name: &str, local: Transform, parent: Option<usize>| Node {
            name: name.into(),
            local,
            mesh: Some(0),
            parent,
            ..Default::default()
        };
        s.nodes = vec![
            mesh_node("a", place(DVec3::new(3.0, -2.0, 1.0), Quat::from_rotation_y(0.7), 2.0), None),
            mesh_node("b", place(DVec3::new(-5.0, 0.5, 4.0), Quat::from_rotation_x(-1.1), 0.5), None),
            Node { name: "mover".into(), children: vec![3], ..Default::default() },
            mesh_node("c", place(DVec3::ZERO, Quat::IDENTITY, 1.0), Some(2)),
        ];
        s.roots = vec![0, 1, 2];
        s.animations.push(Animation::new(
            "move".into(),
            vec![AnimationChannel {
                node: 2,
                times: vec![0.0, 1.0],
                interpolation: Interpolation::Linear,
                values: Channel::Translation(vec![Vec3::ZERO, Vec3::X]),
            }],
        ));
        s.update_world();
        s
    }

    #[test]
    fn flat_tree_holds_every_static_triangle_in_world_space_with_its_mask() {
        let s = scene();
        let origin = RenderOrigin(DVec3::new(1.0, 0.0, -1.0));
        let flat = FlatStatic::build(&s, origin, None).unwrap();
        // Instances: a/prim 0, a/prim 1, b/0, b/1, c/0, c/1; c is animated.
        assert_eq!(flat.flattened, vec![true, true, true, true, false, false]);
        let mut seen: HashMap<(u32, u32), (FlatTriangle, FlatId)> = HashMap::new();
        for t in &flat.triangles {
            let id = flat.resolve(t.id);
            // A spatial split may reference a triangle from two leaves, but
            // always as the same record.
            if let Some(before) = seen.insert((id.instance, id.primitive), (*t, id)) {
                assert_eq!(before.0, *t, "two different records of one triangle");
            }
        }
        // Member table: (first number, instance) with each member's triangle count between them.
        assert_eq!(flat.members, vec![[0, 0], [2, 1], [4, 2], [6, 3]]);
        let mut expected = 0;
        for (i, inst) in s.instances.iter().enumerate().filter(|(i, _)| flat.flattened[*i]) {
            let p = &s.meshes[inst.mesh].primitives[inst.primitive];
            let m = origin.relative(&inst.world);
            let mask = if inst.primitive == 0 { MASK_VISIBLE | MASK_SHADOW } else { MASK_VISIBLE };
            for (prim, idx) in p.indices.chunks_exact(3).enumerate() {
                expected += 1;
                let (t, id) = seen[&(i as u32, prim as u32)];
                assert_eq!(id.mask, mask as u32, "instance {i} triangle {prim}: mask");
                assert_eq!(id.opaque, inst.primitive == 0, "instance {i} triangle {prim}: opacity");
                for (k, got) in [t.p0, t.p1, t.p2].iter().enumerate() {
                    let want =
                        m.transform_point3(DVec3::from(Vec3::from(p.vertices[idx[k] as usize].position)));
                    assert!(
                        (DVec3::from(Vec3::from(*got)) - want).length() < 1e-5,
                        "instance {i} triangle {prim} vertex {k}: {got:?} vs {want:?}"
                    );
                }
            }
        }
        assert_eq!(seen.len(), expected, "only the static instances' triangles");
        assert_eq!(flat.source_triangles, expected);
        // Every leaf range of the wide tree stays inside the triangles, and
        // all of them are covered (the SBVH may reference one twice).
        let mut covered = vec![false; flat.triangles.len()];
        for n in &flat.nodes {
            for c in 0..n.children() {
                if let Some((first, count)) = n.leaf(c) {
                    covered[first..first + count].iter_mut().for_each(|v| *v = true);
                }
            }
        }
        assert!(covered.iter().all(|&c| c), "a triangle no leaf reaches");
    }

    /// A primitive placed many times stays instanced (one BLAS) past the copy rule; few copies, or a
    /// small total, are flattened. The flat tree then holds only the flattened ones.
    #[test]
    fn heavily_instanced_primitives_stay_out_of_the_flat_tree() {
        // 100 x 100 cells: 20,000 triangles per copy; the quad: 2.
        let build = |big: usize, small: usize| {
            let mut s = Scene {
                materials: vec![Material::default()],
                meshes: vec![
                    Mesh {
                        primitives: vec![crate::scene::primitives::terrain(10.0, 10.0, 100, 100, 1.0)],
                        ..Default::default()
                    },
                    Mesh { primitives: vec![quad(0)], ..Default::default() },
                ],
                ..Default::default()
            };
            for (mesh, n) in [(0, big), (1, small)] {
                for k in 0..n {
                    let mut local = Transform::default();
                    local.translation.x = 20.0 * k as f64;
                    s.roots.push(s.nodes.len());
                    s.nodes.push(Node {
                        name: format!("{mesh}/{k}"),
                        local,
                        mesh: Some(mesh),
                        ..Default::default()
                    });
                }
            }
            s.update_world();
            s
        };
        let by_mesh = |s: &Scene, f: &[bool], mesh: usize| {
            s.instances.iter().zip(f).filter(|(i, _)| i.mesh == mesh).map(|(_, f)| *f).collect::<Vec<_>>()
        };
        // 4 copies of 20,000: at the copy limit, flattened; 5 (100,000 > 2^16): instanced.
        let s = build(FLAT_MAX_COPIES, 40);
        assert!(flatten_choice(&s).iter().all(|f| *f));
        let s = build(FLAT_MAX_COPIES + 1, 40);
        let f = flatten_choice(&s);
        assert_eq!(by_mesh(&s, &f, 0), vec![false; FLAT_MAX_COPIES + 1]);
        // 40 quads = 80 triangles: far past the copy limit, under the total.
        assert_eq!(by_mesh(&s, &f, 1), vec![true; 40]);
        let flat = FlatStatic::build(&s, RenderOrigin::default(), None).unwrap();
        assert_eq!(flat.flattened, f);
        assert_eq!(flat.source_triangles, 80);
        // The total line counts triangles: 32,768 quads are exactly 65,536, one more is past it.
        let n = FLAT_ALWAYS_TRIANGLES / 2;
        assert!(flatten_choice(&build(0, n)).iter().all(|f| *f));
        assert!(flatten_choice(&build(0, n + 1)).iter().all(|f| !*f));
    }

    /// The disk cache: a second build of the same geometry reads the first one's tree; a damaged or
    /// truncated file is rebuilt (and rewritten), never trusted; other geometry gets its own file;
    /// small trees get none.
    #[test]
    fn flat_tree_cache_reads_back_and_rebuilds_damaged_files() {
        let dir = std::env::temp_dir().join("hybrid-rt-tests").join("flat-cache");
        let _ = std::fs::remove_dir_all(&dir);
        let mut s = Scene {
            materials: vec![Material::default()],
            // 182 x 182 cells: 66,248 triangles, just over the cache's lower bound.
            meshes: vec![Mesh {
                primitives: vec![crate::scene::primitives::terrain(50.0, 50.0, 182, 182, 5.0)],
                ..Default::default()
            }],
            nodes: vec![Node { name: "t".into(), mesh: Some(0), ..Default::default() }],
            roots: vec![0],
            ..Default::default()
        };
        s.update_world();
        let origin = RenderOrigin(DVec3::new(0.5, 0.0, -2.0));
        let same = |a: &FlatStatic, b: &FlatStatic| {
            assert_eq!(a.root, b.root);
            assert_eq!(a.sah.to_bits(), b.sah.to_bits());
            assert_eq!(a.builder, b.builder);
            assert_eq!(a.nodes, b.nodes);
            assert_eq!(a.triangles, b.triangles);
            assert_eq!(a.source_triangles, b.source_triangles);
            assert_eq!(a.flattened, b.flattened);
        };
        let built = FlatStatic::build(&s, origin, Some(&dir)).unwrap();
        assert!(!built.cached);
        assert!(built.source_triangles >= CACHE_MIN_TRIANGLES);
        let files = || -> Vec<std::path::PathBuf> {
            std::fs::read_dir(&dir).map(|d| d.map(|e| e.unwrap().path()).collect()).unwrap_or_default()
        };
        let [file] = files().try_into().expect("one cache file, no temporary left");
        let read = FlatStatic::build(&s, origin, Some(&dir)).unwrap();
        assert!(read.cached, "the second build reads the file");
        same(&built, &read);
        let whole = std::fs::read(&file).unwrap();
        for (what, bad) in [
            ("a flipped byte in the triangles", {
                let mut b = whole.clone();
                let at = b.len() - 100;
                b[at] ^= 4;
                b
            }),
            ("a truncated file", whole[..whole.len() / 3].to_vec()),
            ("an empty file", Vec::new()),
        ] {
            std::fs::write(&file, &bad).unwrap();
            let rebuilt = FlatStatic::build(&s, origin, Some(&dir)).unwrap();
            assert!(!rebuilt.cached, "{what} was trusted");
            same(&built, &rebuilt);
            assert_eq!(std::fs::read(&file).unwrap(), whole, "{what}: the file is written again");
        }
        // Other geometry (the instance moved), other origin: other keys, new files.
        let other = FlatStatic::build(&s, RenderOrigin(DVec3::ZERO), Some(&dir)).unwrap();
        assert!(!other.cached);
        s.nodes[0].local.translation.x += 1.0;
        s.update_world();
        assert!(!FlatStatic::build(&s, origin, Some(&dir)).unwrap().cached);
        assert_eq!(files().len(), 3);
        // The triangles' opacity bits are in the file: a material turned transmissive is a new key.
        s.materials[0].transmission = 0.5;
        let clear = FlatStatic::build(&s, origin, Some(&dir)).unwrap();
        assert!(!clear.cached);
        assert!(!clear.resolve(clear.triangles[0].id).opaque);
        assert_eq!(files().len(), 4);
        // A tree under the lower bound is not worth a file.
        let small = scene();
        FlatStatic::build(&small, origin, Some(&dir)).unwrap();
        assert_eq!(files().len(), 4);
    }
}
