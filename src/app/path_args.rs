//! The command-line options of the path-traced ground truth (`--mode
//! path`), shared by render, bench and report.

use clap::Args;

use crate::render::shading::Mode;
use crate::render::PathSettings;

/// Most paths per pixel (a software device traces ~0.1-1 Mpaths/s).
pub const MAX_PATH_SAMPLES: u32 = 1 << 20;
/// Longest path cap.
pub const MAX_PATH_BOUNCES: u32 = 1024;

#[derive(Args, Clone, Debug, Default)]
pub struct PathArgs {
    /// With --mode path: paths per pixel, 1 to 1048576, rendered
    /// PATH_SAMPLES_PER_FRAME (4) a frame [default: 64].
    #[arg(long, value_name = "N", value_parser = parse_samples, allow_hyphen_values = true)]
    pub samples: Option<u32>,
    /// With --mode path: longest path in bounces, 1 to 1024 (Russian
    /// roulette ends most paths before) [default: 32].
    #[arg(long, value_name = "N", value_parser = parse_bounces, allow_hyphen_values = true)]
    pub max_bounces: Option<u32>,
    /// With --mode path: scale each path's radiance down to at most X (max
    /// channel; finite, > 0): trades fireflies for a bias the log reports
    /// [default: no clamp, unbiased].
    #[arg(long, value_name = "X", value_parser = parse_clamp, allow_hyphen_values = true)]
    pub clamp: Option<f32>,
}

impl PathArgs {
    pub fn settings(&self) -> PathSettings {
        let d = PathSettings::default();
        PathSettings {
            samples: self.samples.unwrap_or(d.samples),
            max_bounces: self.max_bounces.unwrap_or(d.max_bounces),
            clamp: self.clamp,
        }
    }

    /// An option that does nothing in `mode` (a usage error).
    pub fn without_effect(&self, mode: Mode) -> Option<&'static str> {
        let given = self.samples.is_some() || self.max_bounces.is_some() || self.clamp.is_some();
        (given && mode != Mode::Path).then_some(
            "--samples, --max-bounces and --clamp are the path tracer's: they have no effect without --mode path",
        )
    }
}

fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_PATH_SAMPLES).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': expected a whole number of paths per pixel, 1 to {MAX_PATH_SAMPLES}")),
    }
}

fn parse_bounces(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_PATH_BOUNCES).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': expected a whole number of bounces, 1 to {MAX_PATH_BOUNCES}")),
    }
}

fn parse_clamp(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a finite radiance > 0")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_take_their_ranges_only() {
        assert_eq!(parse_samples("1"), Ok(1));
        assert_eq!(parse_samples("1048576"), Ok(MAX_PATH_SAMPLES));
        for bad in ["0", "-4", "1048577", "x", "2.5"] {
            assert!(parse_samples(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_bounces("1024"), Ok(1024));
        assert!(parse_bounces("0").is_err() && parse_bounces("1025").is_err());
        assert_eq!(parse_clamp("10"), Ok(10.0));
        for bad in ["0", "-1", "inf", "nan"] {
            assert!(parse_clamp(bad).is_err(), "{bad}");
        }
        let args = PathArgs { samples: Some(8), max_bounces: Some(3), clamp: Some(2.0) };
        assert_eq!(args.settings(), PathSettings { samples: 8, max_bounces: 3, clamp: Some(2.0) });
        assert!(args.without_effect(Mode::Hybrid).is_some());
        assert!(args.without_effect(Mode::Path).is_none());
        assert!(PathArgs::default().without_effect(Mode::Rt).is_none());
        assert_eq!(PathArgs::default().settings(), PathSettings::default());
    }
}
