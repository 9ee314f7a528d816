//! Direct transfer (unshadowed and shadowed), the shared direction set, the
//! static occluders and the threaded per-vertex loop.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};

use super::WorldVertex;
use crate::accel::bvh::Bvh;
use crate::accel::cpu_trace::{traverse_any, traverse_closest};
use crate::scene::sh::{eval_basis, MAX_BANDS};
use crate::scene::{Aabb, Scene};

/// ULPs of the extent a ray origin moves along the normal; the same rule
/// and value as glsl/common/offset.glsl (`shared::OFFSET_ULPS`).
use crate::gpu::shared::OFFSET_ULPS;

/// N×N stratified jittered directions over the sphere (uniform density, so
/// each carries the weight 4π / N²) and their SH basis values.
pub(crate) struct SampleSet {
    pub dirs: Vec<DVec3>,
    /// bands² values per direction.
    pub basis: Vec<f64>,
    pub coeffs: usize,
    pub weight: f64,
}

impl SampleSet {
    pub fn new(n: u32, bands: usize, seed: u64) -> Self {
        let mut rng = seed | 1;
        let mut next = || {
            // xorshift64*: deterministic jitter, no dependency.
            rng ^= rng >> 12;
            rng ^= rng << 25;
            rng ^= rng >> 27;
            (rng.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        };
        let coeffs = bands * bands;
        let mut dirs = Vec::with_capacity((n * n) as usize);
        let mut basis = Vec::with_capacity((n * n) as usize * coeffs);
        let mut y = [0.0; MAX_BANDS * MAX_BANDS];
        for i in 0..n {
            for j in 0..n {
                // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
                let z = 1.0 - 2.0 * (i as f64 + next()) / n as f64;
                let phi = std::f64::consts::TAU * (j as f64 + next()) / n as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                eval_basis(bands, d, &mut y);
                dirs.push(d);
                basis.extend_from_slice(&y[..coeffs]);
            }
        }
        let weight = 4.0 * std::f64::consts::PI / (n * n) as f64;
        Self { dirs, basis, coeffs, weight }
    }

    pub fn y(&self, s: usize) -> &[f64] {
        &self.basis[s * self.coeffs..][..self.coeffs]
    }
}

/// The static triangles in world space (f32) with a BVH, and per triangle
/// its global vertex indices (into the transfer's vertex order) and the
/// albedo of its material (base colour; textures are not sampled).
pub(crate) struct Occluders {
    pub bvh: Bvh,
    pub tris: Vec<[Vec3; 3]>,
    pub verts: Vec<[u32; 3]>,
    pub albedo: Vec<[f32; 3]>,
}

impl Occluders {
    pub fn build(scene: &Scene, statics: &[usize], first_vertex: &[Option<u32>]) -> Self {
        let (mut tris, mut verts, mut albedo) = (Vec::new(), Vec::new(), Vec::new());
        for &i in statics {
            let inst = &scene.instances[i];
            let prim = &scene.meshes[inst.mesh].primitives[inst.primitive];
            let base = first_vertex[i].unwrap_or(0);
            let c = scene.materials.get(scene.instance_material(inst)).map_or([0.0; 4], |m| m.base_color);
            let p = |k: u32| {
                inst.world.transform_point3(Vec3::from(prim.vertices[k as usize].position).as_dvec3())
            };
            for t in prim.indices.chunks_exact(3) {
                if t.iter().any(|&k| k as usize >= prim.vertices.len()) {
                    continue;
                }
                tris.push([p(t[0]).as_vec3(), p(t[1]).as_vec3(), p(t[2]).as_vec3()]);
                verts.push([base + t[0], base + t[1], base + t[2]]);
                albedo.push([c[0], c[1], c[2]]);
            }
        }
        let aabbs: Vec<Aabb> = tris
            .iter()
            .map(|t| Aabb { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) })
            .collect();
        Self { bvh: Bvh::build(&aabbs), tris, verts, albedo }
    }

    /// Whether the ray from `v` along `d` hits anything (first hit ends it).
    pub fn occluded(&self, v: &WorldVertex, d: DVec3) -> bool {
        let o = offset_origin(v.p.as_vec3(), v.n.as_vec3(), v.extent as f32);
        traverse_any(&self.bvh, &self.tris, o, d.as_vec3(), f32::INFINITY)
    }

    /// Closest hit from `v` along `d`: (triangle, u, v, front-facing).
    pub fn trace(&self, v: &WorldVertex, d: DVec3) -> Option<(u32, f32, f32, bool)> {
        let o = offset_origin(v.p.as_vec3(), v.n.as_vec3(), v.extent as f32);
        let dir = d.as_vec3();
        traverse_closest(&self.bvh, &self.tris, o, dir, f32::INFINITY).map(|(t, _, b1, b2)| {
            let tri = &self.tris[t as usize];
            let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            (t, b1, b2, ng.dot(dir) < 0.0)
        })
    }
}

/// offset.glsl's `offset_ray` on the host: 16 ULPs of the largest of the
/// point's coordinates and the primitive's extent, along the normal.
pub fn offset_origin(p: Vec3, n: Vec3, extent: f32) -> Vec3 {
    let m = p.abs().max_element().max(extent).max(1e-30);
    let ulp = f32::from_bits(m.to_bits() + 1) - m;
    p + n * (OFFSET_ULPS * ulp)
}

/// Direct transfer (monochrome, bands² floats a vertex): the clamped
/// cosine, times the visibility when `occluders` is given.
pub(crate) fn direct(
    verts: &[WorldVertex],
    s: &SampleSet,
    occluders: Option<&Occluders>,
    rays: &mut u64,
) -> Vec<f32> {
    let k = s.coeffs;
    let (data, traced) = per_vertex(verts.len(), k, "direct transfer", |v, out| {
        let wv = &verts[v];
        let mut acc = [0.0f64; MAX_BANDS * MAX_BANDS];
        let mut traced = 0u64;
        for (i, d) in s.dirs.iter().enumerate() {
            let c = wv.n.dot(*d);
            if c <= 0.0 {
                continue;
            }
            if let Some(occ) = occluders {
                traced += 1;
                if occ.occluded(wv, *d) {
                    continue;
                }
            }
            for (a, y) in acc.iter_mut().zip(s.y(i)) {
                *a += c * y;
            }
        }
        for (o, a) in out.iter_mut().zip(acc) {
            *o = (a * s.weight) as f32;
        }
        traced
    });
    *rays += traced;
    data
}

/// Runs `f(vertex, out)` for every vertex on all cores (`out`: `stride`
/// floats), summing what it returns (rays traced). Shows a progress line
/// on a terminal; logs the time either way.
pub(crate) fn per_vertex(
    count: usize,
    stride: usize,
    what: &str,
    f: impl Fn(usize, &mut [f32]) -> u64 + Sync,
) -> (Vec<f32>, u64) {
    let mut data = vec![0.0f32; count * stride];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(count.max(1));
    // Chunks much smaller than count / threads balance uneven vertices.
    let chunk = (count / (threads * 16)).clamp(1, 4096);
    let done = AtomicUsize::new(0);
    let t0 = Instant::now();
    let show = std::io::stderr().is_terminal() && count > 0;
    let chunks: Vec<(usize, &mut [f32])> =
        data.chunks_mut((chunk * stride).max(1)).enumerate().map(|(i, c)| (i * chunk, c)).collect();
    let chunks = std::sync::Mutex::new(chunks.into_iter());
    let rays = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut rays = 0u64;
                    while let Some((start, out)) = chunks.lock().map(|mut c| c.next()).ok().flatten() {
                        for (j, o) in out.chunks_mut(stride.max(1)).enumerate() {
                            rays += f(start + j, o);
                        }
                        done.fetch_add(out.len() / stride.max(1), Ordering::Relaxed);
                    }
                    rays
                })
            })
            .collect();
        if show {
            while !workers.iter().all(|w| w.is_finished()) {
                std::thread::sleep(Duration::from_millis(200));
                let d = done.load(Ordering::Relaxed);
                let frac = d as f64 / count as f64;
                let bar = "#".repeat((frac * 30.0) as usize);
                eprint!(
                    "\rprt {what}: [{bar:<30}] {d}/{count} vertices, {:.1} s",
                    t0.elapsed().as_secs_f64()
                );
            }
            eprintln!();
        }
        workers.into_iter().map(|w| w.join().unwrap_or(0)).sum::<u64>()
    });
    log::debug!("prt: {what} of {count} vertices in {:.2} s", t0.elapsed().as_secs_f64());
    (data, rays)
}
