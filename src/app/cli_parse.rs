//! Value parsers of the command line's numbers: each error says what the
//! flag expects (clap prefixes the flag).

use crate::render::supersample;

/// "A,B": two finite floats.
pub fn parse_pair(s: &str, what: &str) -> Result<(f32, f32), String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [a, b] = parts[..] else { return Err(format!("'{s}': expected {what}")) };
    let num = |t: &str| -> Result<f32, String> {
        t.trim()
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or(format!("'{t}' is not a finite number (expected {what})"))
    };
    Ok((num(a)?, num(b)?))
}

pub fn parse_percentiles(s: &str) -> Result<(f32, f32), String> {
    let (lo, hi) = parse_pair(s, "LOW,HIGH with 0 <= LOW < HIGH <= 1")?;
    if (0.0..1.0).contains(&lo) && lo < hi && hi <= 1.0 {
        Ok((lo, hi))
    } else {
        Err(format!("{lo},{hi} is out of range (expected LOW,HIGH with 0 <= LOW < HIGH <= 1)"))
    }
}

pub fn parse_speeds(s: &str) -> Result<(f32, f32), String> {
    let (b, d) = parse_pair(s, "BRIGHTEN,DARKEN in EV per second, > 0")?;
    if b > 0.0 && d > 0.0 {
        Ok((b, d))
    } else {
        Err(format!("{b},{d} is out of range (expected BRIGHTEN,DARKEN in EV per second, > 0)"))
    }
}

/// A finite float for `flag` that `ok` accepts; `range` says what is.
pub fn parse_f32(s: &str, range: &str, ok: impl Fn(f32) -> bool) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|e| format!("{e} (expected {range})"))?;
    if v.is_finite() && ok(v) {
        Ok(v)
    } else {
        Err(format!("{v} is out of range (expected {range})"))
    }
}

/// An integer in `lo..=hi`; parsed wide so that negative values get the
/// range message instead of "invalid digit".
pub fn parse_int(s: &str, lo: i64, hi: i64, what: &str) -> Result<i64, String> {
    let v: i64 = s.trim().parse().map_err(|e| format!("{e} (expected {what} {lo}..={hi})"))?;
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is out of range (expected {what} {lo}..={hi})"))
    }
}

pub fn parse_resolution(s: &str) -> Result<u32, String> {
    parse_int(s, 1, 16384, "a resolution of").map(|v| v as u32)
}

pub fn parse_max_depth(s: &str) -> Result<u32, String> {
    parse_int(s, 0, 64, "a depth of").map(|v| v as u32)
}

pub fn parse_count(s: &str) -> Result<usize, String> {
    parse_int(s, 1, i64::MAX, "a frame count of").map(|v| v as usize)
}

pub fn parse_reps(s: &str) -> Result<usize, String> {
    parse_int(s, 1, 1000, "a repetition count of").map(|v| v as usize)
}

pub fn parse_supersample(s: &str) -> Result<u32, String> {
    parse_int(s, 1, supersample::MAX_FACTOR as i64, "samples per axis").map(|v| v as u32)
}

pub fn parse_exposure(s: &str) -> Result<f32, String> {
    parse_f32(s, "finite, > 0", |v| v > 0.0)
}

pub fn parse_fov(s: &str) -> Result<f32, String> {
    parse_f32(s, "degrees in (0, 180)", |v| v > 0.0 && v < 180.0)
}

pub fn parse_min_weight(s: &str) -> Result<f32, String> {
    parse_f32(s, "finite, in [0, 1]", |v| (0.0..=1.0).contains(&v))
}

pub fn parse_share(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': expected a share in [0, 1]")),
    }
}

pub fn parse_time(s: &str) -> Result<f32, String> {
    parse_f32(s, "finite seconds", |_| true)
}

pub fn parse_fps(s: &str) -> Result<f32, String> {
    parse_f32(s, "finite, > 0", |v| v > 0.0)
}
