//! The BVH unit tests' random numbers: a 64-bit LCG (Knuth's MMIX
//! constants), reproducible from its seed.

use glam::Vec3;

pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1) (the state's top 24 bits).
    pub fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Uniform in [0, 1)^3.
    pub fn v(&mut self) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f())
    }
}
