//! Tone-mapping settings: the operator, how the exposure is found (fixed, log-average luminance or a
//! log-luminance histogram) and how it adapts. Passes: render/passes/luminance.rs (measures, adapts) and
//! render/passes/tonemap.rs (applies); curves in glsl/common/tonemap.glsl, adaptation in exposure.glsl.

use crate::gpu::shared::{
    AUTO_EXPOSURE_HISTOGRAM, AUTO_EXPOSURE_LOG_AVERAGE, AUTO_EXPOSURE_OFF, TONEMAP_ACES, TONEMAP_NONE,
    TONEMAP_REINHARD, TONEMAP_REINHARD_WHITE,
};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ToneOperator {
    /// Reinhard's global operator on luminance: L / (1 + L).
    #[default]
    Reinhard,
    /// Extended Reinhard: L (1 + L / Lw²) / (1 + L), Lw the white point
    /// (--white-point, default the frame's brightest luminance).
    ReinhardWhite,
    /// Narkowicz's fit of the ACES filmic curve, per channel.
    Aces,
    /// Exposure and a clamp to [0, 1].
    None,
}

impl ToneOperator {
    pub fn code(self) -> u32 {
        match self {
            ToneOperator::Reinhard => TONEMAP_REINHARD,
            ToneOperator::ReinhardWhite => TONEMAP_REINHARD_WHITE,
            ToneOperator::Aces => TONEMAP_ACES,
            ToneOperator::None => TONEMAP_NONE,
        }
    }

    pub const ALL: [ToneOperator; 4] =
        [ToneOperator::Reinhard, ToneOperator::ReinhardWhite, ToneOperator::Aces, ToneOperator::None];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ToneOperator::Reinhard => "reinhard",
            ToneOperator::ReinhardWhite => "reinhard-white",
            ToneOperator::Aces => "aces",
            ToneOperator::None => "none",
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AutoExposure {
    /// The fixed --exposure.
    #[default]
    Off,
    /// exposure = key / exp(mean(log(delta + L))) (Reinhard et al. 2002),
    /// adapted over time.
    LogAverage,
    /// The mean log-luminance of a histogram between two percentiles
    /// (outliers clipped), adapted at separate brighten/darken rates.
    Histogram,
}

impl AutoExposure {
    pub fn code(self) -> u32 {
        match self {
            AutoExposure::Off => AUTO_EXPOSURE_OFF,
            AutoExposure::LogAverage => AUTO_EXPOSURE_LOG_AVERAGE,
            AutoExposure::Histogram => AUTO_EXPOSURE_HISTOGRAM,
        }
    }
}

/// How the HDR frame becomes displayable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneSettings {
    pub operator: ToneOperator,
    pub auto_exposure: AutoExposure,
    /// Reinhard's key a: the exposed luminance the scene's average maps to.
    pub key: f32,
    /// White point of `reinhard-white` in exposed luminance; None: the
    /// frame's brightest finite luminance, exposed.
    pub white: Option<f32>,
    /// Histogram: the darkest and brightest fractions of pixels left out.
    pub histogram_low: f32,
    pub histogram_high: f32,
    /// Histogram: adaptation speed in EV per second when the image gets brighter (the scene got darker)
    /// and when it gets darker.
    pub speed_brighten: f32,
    pub speed_darken: f32,
}

impl Default for ToneSettings {
    fn default() -> Self {
        // The histogram defaults Bevy and Unreal users know: 10% / 90% percentiles, 3 EV/s brightening,
        // 1 EV/s darkening.
        ToneSettings {
            operator: ToneOperator::Reinhard,
            auto_exposure: AutoExposure::Off,
            key: 0.18,
            white: None,
            histogram_low: 0.10,
            histogram_high: 0.90,
            speed_brighten: 3.0,
            speed_darken: 1.0,
        }
    }
}

impl ToneSettings {
    /// Whether the frame's luminance must be measured (the `luminance` pass runs).
    pub fn measures_luminance(&self) -> bool {
        self.auto_exposure != AutoExposure::Off
            || (self.operator == ToneOperator::ReinhardWhite && self.white.is_none())
    }

    pub fn describe(&self) -> String {
        let exposure = match self.auto_exposure {
            AutoExposure::Off => "fixed exposure".to_string(),
            AutoExposure::LogAverage => format!("log-average auto exposure, key {}", self.key),
            AutoExposure::Histogram => format!(
                "histogram auto exposure, key {}, percentiles {}-{}",
                self.key, self.histogram_low, self.histogram_high
            ),
        };
        format!("{} ({exposure})", self.operator.name())
    }
}

pub use crate::gpu::types::{exposure_buffer_bytes, ExposureState, EXPOSURE_STATE_BYTES};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luminance_is_measured_only_when_something_reads_it() {
        let mut t = ToneSettings::default();
        assert!(!t.measures_luminance());
        t.operator = ToneOperator::ReinhardWhite;
        assert!(t.measures_luminance(), "reinhard-white without a white point uses the frame's maximum");
        t.white = Some(4.0);
        assert!(!t.measures_luminance());
        t.auto_exposure = AutoExposure::Histogram;
        assert!(t.measures_luminance());
    }
}
