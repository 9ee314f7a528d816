//! Windowing (per-band attenuation) against ringing.
//!
//! Truncating a map with a sun (one ~6.5e4 texel) to a few bands gives Gibbs overshoot: a negative
//! lobe around the sun. A window scales band l by w_l, falling to 0 at l = `bands` (the first band
//! not stored), tapering the spectrum instead of cutting it. With W = `bands`:
//! - Hann:    w_l = (1 + cos(pi l / W)) / 2,
//! - Lanczos: w_l = sinc(l / W) = sin(pi l / W) / (pi l / W),
//!
//! so for L2 (W = 3) Hann gives 1, 0.75, 0.25 and Lanczos 1, 0.827, 0.413.
//!
//! Hann is the default. At L2 a single bright texel of power P reconstructs with a minimum of
//! -1.8 P / 4pi unwindowed, -0.53 P / 4pi with Lanczos, -0.30 P / 4pi with Hann (the zonal kernel
//! sum_l w_l (2l+1) P_l(t) / 4pi minimised over t). None makes a delta non-negative at L2, but Hann
//! keeps a sun on a sky non-negative when the sky exceeds 0.024 P (`tests_maps`: a 6.5e4 sun on a 0.1
//! sky; `tests_hdri`: venice_sunset).
//!
//! The price is blur: Hann irradiance is 9-25% off brute force on the shipped maps (plain L2:
//! 1.8-2.6%), since the clamped cosine already damps bands 1-2, and unwindowed L2 irradiance stays
//! positive on four of five maps (studio_small_03: -0.17). Irradiance-only callers may prefer
//! `Window::None`.

use super::basis::band_of;
use super::ShCoeffs;

/// Per-band window. `Hann` (the default) is applied by the projections unless
/// asked otherwise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Window {
    /// Plain truncation (what the irradiance-accuracy figures of Ramamoorthi
    /// & Hanrahan refer to).
    None,
    #[default]
    Hann,
    Lanczos,
}

impl Window {
    /// Factor for band `l` of a `bands`-band expansion (window width `bands`).
    pub fn factor(self, l: usize, bands: usize) -> f64 {
        let x = l as f64 / bands as f64;
        if x >= 1.0 {
            return 0.0;
        }
        match self {
            Window::None => 1.0,
            Window::Hann => 0.5 * (1.0 + (std::f64::consts::PI * x).cos()),
            Window::Lanczos if l == 0 => 1.0,
            Window::Lanczos => {
                let px = std::f64::consts::PI * x;
                px.sin() / px
            }
        }
    }
}

impl ShCoeffs {
    /// These coefficients with `w` applied (band l scaled by w.factor(l, bands)).
    /// Windowing an already windowed set applies the factors again.
    pub fn windowed(&self, w: Window) -> ShCoeffs {
        let mut out = self.clone();
        for (i, c) in out.rgb.iter_mut().enumerate() {
            let f = w.factor(band_of(i), self.bands);
            c.iter_mut().for_each(|v| *v *= f);
        }
        out
    }

    /// Undoes `windowed(w)`: bands the window zeroed stay zero.
    pub fn unwindowed(&self, w: Window) -> ShCoeffs {
        let mut out = self.clone();
        for (i, c) in out.rgb.iter_mut().enumerate() {
            let f = w.factor(band_of(i), self.bands);
            let inv = if f > 0.0 { 1.0 / f } else { 0.0 };
            c.iter_mut().for_each(|v| *v *= inv);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors() {
        let near = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(near(Window::Hann.factor(0, 3), 1.0));
        assert!(near(Window::Hann.factor(1, 3), 0.75));
        assert!(near(Window::Hann.factor(2, 3), 0.25));
        assert!(near(Window::Hann.factor(3, 3), 0.0));
        assert!(near(Window::Lanczos.factor(0, 3), 1.0));
        assert!(near(Window::Lanczos.factor(1, 3), 3.0 * 3f64.sqrt() / (2.0 * std::f64::consts::PI)));
        assert!(near(Window::None.factor(2, 3), 1.0));
        for bands in 1..=8 {
            for w in [Window::None, Window::Hann, Window::Lanczos] {
                assert!(near(w.factor(0, bands), 1.0));
                // Monotone non-increasing in l.
                for l in 1..bands {
                    assert!(w.factor(l, bands) <= w.factor(l - 1, bands) + 1e-15);
                }
            }
        }
    }

    /// The zonal kernel minima quoted in the module doc.
    #[test]
    fn l2_delta_kernel_minimum() {
        let kernel_min = |w: Window| {
            (0..=2000)
                .map(|i| {
                    let t = -1.0 + 2.0 * i as f64 / 2000.0;
                    let p = [1.0, t, 0.5 * (3.0 * t * t - 1.0)];
                    (0..3).map(|l| w.factor(l, 3) * (2 * l + 1) as f64 * p[l]).sum::<f64>()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let (none, hann, lanczos) =
            (kernel_min(Window::None), kernel_min(Window::Hann), kernel_min(Window::Lanczos));
        println!("L2 delta kernel minimum x 4pi / P: none {none:.3}, Hann {hann:.3}, Lanczos {lanczos:.3}");
        assert!((none + 1.8).abs() < 1e-3 && (hann + 0.3).abs() < 1e-3 && (lanczos + 0.53).abs() < 5e-3);
    }

    #[test]
    fn windowed_scales_each_band() {
        let c = ShCoeffs::from_coeffs(3, vec![[1.0, 2.0, 3.0]; 9]).unwrap();
        let w = c.windowed(Window::Hann);
        for (i, f) in [1.0, 0.75, 0.75, 0.75, 0.25, 0.25, 0.25, 0.25, 0.25].into_iter().enumerate() {
            for k in 0..3 {
                assert!((w.coeffs()[i][k] - f * (k + 1) as f64).abs() < 1e-12, "{i} {k}");
            }
        }
        assert_eq!(c.windowed(Window::None), c);
    }
}
