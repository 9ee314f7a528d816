//! The per-vertex transfer packed into one storage buffer (layout:
//! gpu/shared_values.rs SCENE_PRT), which `GpuScene::set_prt` uploads.

use super::PrtTransfer;
use crate::gpu::shared::{PRT_HEADER_WORDS, PRT_NO_VERTEX};

/// Header, per-instance first vertex, transfer floats (as bits).
pub fn pack(t: &PrtTransfer) -> Vec<u32> {
    let n = t.first_vertex.len();
    let mut w = Vec::with_capacity(PRT_HEADER_WORDS as usize + n + t.data.len());
    w.extend_from_slice(&[t.coeffs() as u32, t.channels() as u32, n as u32, 0]);
    w.extend(t.first_vertex.iter().map(|f| f.unwrap_or(PRT_NO_VERTEX)));
    w.extend(t.data.iter().map(|f| f.to_bits()));
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prt::{PrtMode, PrtSettings};

    #[test]
    fn pack_layout() {
        let t = PrtTransfer {
            settings: PrtSettings { bands: 2, ..PrtSettings::new(PrtMode::Interreflected) },
            first_vertex: vec![Some(0), None, Some(1)],
            data: (0..24).map(|i| i as f32).collect(),
            rays: 0,
        };
        let w = pack(&t);
        assert_eq!(&w[..7], &[4, 3, 3, 0, 0, PRT_NO_VERTEX, 1]);
        assert_eq!(w.len(), 7 + 24);
        assert_eq!(f32::from_bits(w[7 + 12 + 5]), 17.0);
    }
}
