//! The quality knobs a report sweeps: one table entry per knob, so a later
//! feature (budget heuristic, SH bands, ...) adds itself as
//! one more row. Each knob changes one thing of the base settings.

use anyhow::{bail, Context as _, Result};

use crate::app::AccelUpdate;
use crate::render::shading::{AaMode, Backend, Mode};
use crate::render::{AmbientMode, RenderSettings};

/// What one measured setting renders: the frame settings and the
/// resolution scale (the frame is rendered at the scaled size and
/// resampled to the reference's size before it is compared).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    pub settings: RenderSettings,
    pub scale: f32,
    /// Some: the scene is played through the animation's last frames up to
    /// the report's time, keeping the acceleration structures current this
    /// way (measure::measure_animated); None: one still pose.
    pub accel: Option<AccelUpdate>,
    /// The `budget` knob's share of the cost of tracing every visible
    /// object; `run` turns it into `settings.budget` once it has measured
    /// that cost.
    pub budget_share: Option<f64>,
}

impl Variant {
    /// A still frame at full size.
    pub fn new(settings: RenderSettings) -> Variant {
        Variant { settings, scale: 1.0, accel: None, budget_share: None }
    }
}

/// One knob: its name on the command line and in the tables, what it is,
/// the values a full report sweeps, and how a value changes a variant.
pub struct Knob {
    pub name: &'static str,
    pub about: &'static str,
    pub values: &'static [&'static str],
    /// Applies `value` to the variant; an error says what was expected.
    pub apply: fn(&mut Variant, &str) -> Result<()>,
    /// True when a default value the device cannot run is skipped (noted in
    /// the report) rather than an error.
    pub skip_unavailable: bool,
}

/// The table of knobs, in report order.
pub const KNOBS: &[Knob] = &[
    Knob {
        name: "max-depth",
        about: "maximum reflection/refraction recursion depth",
        values: &["0", "1", "2", "3", "4", "6", "8", "16"],
        apply: |v, s| {
            let d: u32 = s.parse().with_context(|| format!("max-depth '{s}': expected 0..=64"))?;
            if d > 64 {
                bail!("max-depth {d}: expected 0..=64");
            }
            v.settings.effects.max_depth = d;
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "min-weight",
        about: "importance cutoff: branches with a smaller weight are not traced",
        values: &["0.1", "0.03", "0.01", "0.003", "0.001", "0"],
        apply: |v, s| {
            let w: f32 = s.parse().with_context(|| format!("min-weight '{s}': expected a number in [0, 1]"))?;
            if !(0.0..=1.0).contains(&w) {
                bail!("min-weight {w}: expected a number in [0, 1]");
            }
            v.settings.effects.min_weight = w;
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "effects",
        about: "secondary effects: none (raster only), shadows, +reflections, +refractions",
        values: &["none", "shadows", "+reflections", "+refractions"],
        apply: |v, s| {
            let e = &mut v.settings.effects;
            (e.shadows, e.reflections, e.refractions) = match s {
                "none" => (false, false, false),
                "shadows" => (true, false, false),
                "+reflections" => (true, true, false),
                "+refractions" => (true, true, true),
                _ => bail!("effects '{s}': expected none, shadows, +reflections or +refractions"),
            };
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "ambient",
        about: "the diffuse ambient: traced (SH shadowed by traced visibility, plus the one indirect bounce), \
                visibility (traced without the bounce: --no-indirect), sh (unshadowed) or constant (the \
                map's mean); the --prt report sweeps the PRT transfers",
        values: &["traced", "visibility", "sh", "constant"],
        apply: |v, s| {
            (v.settings.ambient, v.settings.ambient_bounce) = match s {
                "traced" => (AmbientMode::Traced, true),
                "visibility" => (AmbientMode::Traced, false),
                "sh" => (AmbientMode::Sh, true),
                "constant" => (AmbientMode::Constant, true),
                _ => bail!("ambient '{s}': expected traced, visibility, sh or constant"),
            };
            v.settings.ambient_from_scene = false;
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "mode",
        about: "hybrid (G-buffer primary hits) or rt (camera rays traced)",
        values: &["hybrid", "rt"],
        apply: |v, s| {
            v.settings.mode = match s {
                "hybrid" => Mode::Hybrid,
                "rt" => Mode::Rt,
                _ => bail!("mode '{s}': expected hybrid or rt"),
            };
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "backend",
        about: "ray traversal backend (those the device offers)",
        values: &["query", "pipeline", "compute"],
        apply: |v, s| {
            v.settings.backend = match s {
                "query" => Backend::Query,
                "pipeline" => Backend::Pipeline,
                "compute" => Backend::Compute,
                _ => bail!("backend '{s}': expected query, pipeline or compute"),
            };
            Ok(())
        },
        skip_unavailable: true,
    },
    Knob {
        name: "aa",
        about: "anti-aliasing after tone mapping: none, edge (G-buffer depth/normal edges) or fxaa \
                (luminance edges); its rows compare the final 8-bit image with the base settings \
                supersampled (--ref-supersample), not with the reference",
        values: &["none", "edge", "fxaa"],
        apply: |v, s| {
            v.settings.aa = match s {
                "none" => AaMode::None,
                "edge" => AaMode::Edge,
                "fxaa" => AaMode::Fxaa,
                _ => bail!("aa '{s}': expected none, edge or fxaa"),
            };
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "accel-update",
        about: "acceleration-structure update on an animated scene (--animation): the structures are built \
                at the first of the warm-up + timed frames before --time and kept current every frame by \
                refitting (refit), rebuilding the animated ones (rebuild), rebuilding every structure (full) \
                or the default policy (policy, refit until the bounds grow 1.5x); time includes the update, \
                the error is the frame at --time",
        values: &["refit", "rebuild", "full"],
        apply: |v, s| {
            v.accel = Some(match s {
                "policy" => AccelUpdate::Policy,
                "refit" => AccelUpdate::Refit,
                "rebuild" => AccelUpdate::Rebuild,
                "full" => AccelUpdate::Full,
                _ => bail!("accel-update '{s}': expected refit, rebuild, full or policy"),
            });
            Ok(())
        },
        skip_unavailable: true,
    },
    Knob {
        name: "budget",
        about: "per-object ray-tracing budget (paper mode and fallback, no stickiness) as a share of the estimated cost of \
                tracing every visible object in this view (measured first): 0 = raster shading only, 1 = \
                every object traced",
        values: &["0", "0.1", "0.25", "0.5", "0.75", "1"],
        apply: |v, s| {
            let f: f64 = s.parse().with_context(|| format!("budget '{s}': expected a share in [0, 1]"))?;
            if !(0.0..=1.0).contains(&f) {
                bail!("budget {f}: expected a share in [0, 1]");
            }
            v.budget_share = Some(f);
            Ok(())
        },
        skip_unavailable: false,
    },
    Knob {
        name: "resolution-scale",
        about: "render at this fraction of the width and height; error after bilinear upscaling to the reference size",
        values: &["0.5", "0.75", "1"],
        apply: |v, s| {
            let f: f32 = s.parse().with_context(|| format!("resolution-scale '{s}': expected a number in (0, 1]"))?;
            if !(f > 0.0 && f <= 1.0) {
                bail!("resolution-scale {f}: expected a number in (0, 1]");
            }
            v.scale = f;
            Ok(())
        },
        skip_unavailable: false,
    },
];

pub fn find(name: &str) -> Result<&'static Knob> {
    KNOBS.iter().find(|k| k.name == name).with_context(|| {
        let names: Vec<_> = KNOBS.iter().map(|k| k.name).collect();
        format!("unknown knob '{name}' (knobs: {})", names.join(", "))
    })
}

/// A knob with the values to sweep: the table's, or the user's.
#[derive(Clone, Debug, PartialEq)]
pub struct KnobSelection {
    pub knob: &'static str,
    /// None: the knob's own values (unavailable ones skipped where allowed).
    pub values: Option<Vec<String>>,
}

/// Parses `--knobs`: comma-separated knob names, each optionally with its
/// values after '=' separated by ':' (`max-depth=0:2,mode`). Empty: every knob.
pub fn parse_selection(s: &str) -> Result<Vec<KnobSelection>> {
    parse_selection_in(s, KNOBS, find)
}

/// `parse_selection` over another knob table (the `--prt` report's), whose
/// `find` names it in its errors.
pub fn parse_selection_in(
    s: &str,
    table: &'static [Knob],
    find: fn(&str) -> Result<&'static Knob>,
) -> Result<Vec<KnobSelection>> {
    let mut out: Vec<KnobSelection> = Vec::new();
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, values) = match part.split_once('=') {
            Some((n, v)) => {
                let vals: Vec<String> =
                    v.split(':').map(|x| x.trim().to_string()).filter(|x| !x.is_empty()).collect();
                if vals.is_empty() {
                    bail!("--knobs {part}: no values after '='");
                }
                (n.trim(), Some(vals))
            }
            None => (part, None),
        };
        let knob = find(name)?;
        if out.iter().any(|k| k.knob == knob.name) {
            bail!("--knobs: {} given twice", knob.name);
        }
        // Check the values now, not after minutes of rendering.
        for v in values.iter().flatten() {
            (knob.apply)(&mut Variant::new(RenderSettings::default()), v)?;
        }
        out.push(KnobSelection { knob: knob.name, values });
    }
    if out.is_empty() {
        out = table.iter().map(|k| KnobSelection { knob: k.name, values: None }).collect();
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_default_value_applies() {
        for k in KNOBS {
            for v in k.values {
                let mut var = Variant::new(RenderSettings::default());
                (k.apply)(&mut var, v).unwrap_or_else(|e| panic!("{} {v}: {e}", k.name));
            }
        }
    }

    #[test]
    fn selection_parses_names_and_values() {
        let s = parse_selection("max-depth=0:2, mode").unwrap();
        assert_eq!(s[0], KnobSelection { knob: "max-depth", values: Some(vec!["0".into(), "2".into()]) });
        assert_eq!(s[1], KnobSelection { knob: "mode", values: None });
        assert_eq!(parse_selection("").unwrap().len(), KNOBS.len());
        assert!(parse_selection("depth").unwrap_err().to_string().contains("max-depth"));
        assert!(parse_selection("max-depth=99").is_err());
        assert!(parse_selection("mode,mode").is_err());
        let mut v = Variant::new(RenderSettings::default());
        (find("effects").unwrap().apply)(&mut v, "shadows").unwrap();
        assert!(v.settings.effects.shadows && !v.settings.effects.reflections);
    }
}
