//! Progress of a long load (issue 36 item 4): which stage runs and how far it is, shown only once the
//! load has run for [`SHOW_AFTER`], so short loads stay quiet. On a terminal (stderr) one line is
//! rewritten in place (a ticker thread keeps it current); elsewhere (CI logs, pipes) plain log
//! lines, one per stage and per half of a stage. Stages are reported from any layer and thread (`stage`, `percent`); a command brackets the
//! whole load with [`begin`] (nested begins are no-ops, so library callers may begin too).

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Loads shorter than this print nothing ...
pub const SHOW_AFTER: Duration = Duration::from_secs(2);
/// ... unless this environment variable gives another time in ms (tests show every stage with 0).
pub const SHOW_AFTER_ENV: &str = "HYBRID_RT_PROGRESS_AFTER_MS";

struct State {
    start: Instant,
    show_after: Duration,
    stage: String,
    /// Percent of the stage done, when it reports any.
    percent: Option<u32>,
    /// The last (stage, quarter) a log line went out for.
    logged: Option<(String, u32)>,
    tty: bool,
    /// A terminal line is open (needs a newline at the end).
    line: bool,
}

static STATE: Mutex<Option<State>> = Mutex::new(None);

/// Ends the load when dropped: a terminal line is closed with the total time.
#[must_use = "the load ends when the guard drops"]
pub struct Load {
    outer: bool,
}

impl Drop for Load {
    fn drop(&mut self) {
        if !self.outer {
            return;
        }
        let Ok(mut s) = STATE.lock() else { return };
        if let Some(st) = s.take() {
            let secs = st.start.elapsed().as_secs_f64();
            if st.line {
                eprintln!("\r\x1b[2Kloaded in {secs:.1} s");
            } else if st.logged.is_some() {
                log::info!("load: done in {secs:.1} s");
            }
        }
    }
}

/// Starts a load (a no-op guard inside one already running).
pub fn begin() -> Load {
    let Ok(mut s) = STATE.lock() else { return Load { outer: false } };
    if s.is_some() {
        return Load { outer: false };
    }
    let show_after = std::env::var(SHOW_AFTER_ENV)
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map_or(SHOW_AFTER, Duration::from_millis);
    *s = Some(State {
        start: Instant::now(),
        show_after,
        stage: String::new(),
        percent: None,
        logged: None,
        tty: std::io::stderr().is_terminal(),
        line: false,
    });
    // A stage that reports nothing for a while (one long build) still shows once the load passes
    // SHOW_AFTER, and a terminal line keeps its clock running.
    let _ = std::thread::Builder::new().name("progress".into()).spawn(|| {
        while active() {
            std::thread::sleep(TICK);
            update(|_| {});
        }
    });
    Load { outer: true }
}

/// How often a running load's line is refreshed.
const TICK: Duration = Duration::from_millis(250);

/// The load enters stage `name` (ignored outside a load).
pub fn stage(name: impl Into<String>) {
    update(|st| {
        st.stage = name.into();
        st.percent = None;
    });
}

/// `done` of `total` of the current stage.
pub fn percent(done: usize, total: usize) {
    let p = (100 * done.min(total) / total.max(1)) as u32;
    update(|st| st.percent = Some(p));
}

fn update(f: impl FnOnce(&mut State)) {
    let Ok(mut s) = STATE.lock() else { return };
    let Some(st) = s.as_mut() else { return };
    f(st);
    let elapsed = st.start.elapsed();
    if elapsed < st.show_after || st.stage.is_empty() {
        return;
    }
    let text = match st.percent {
        Some(p) => format!("{} {p}%", st.stage),
        None => format!("{}...", st.stage),
    };
    if st.tty {
        eprint!("\r\x1b[2Kloading ({:.0} s): {text}", elapsed.as_secs_f64());
        let _ = std::io::stderr().flush();
        st.line = true;
    } else {
        // One line per stage and per half of it (the end is the next stage's line).
        let key = (st.stage.clone(), st.percent.unwrap_or(0).min(99) / 50);
        if st.logged.as_ref() != Some(&key) {
            log::info!("load ({:.1} s): {text}", elapsed.as_secs_f64());
            st.logged = Some(key);
        }
    }
}

/// Whether a load is under way (the ticker's loop condition; tests).
pub fn active() -> bool {
    STATE.lock().map(|s| s.is_some()).unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_loads_keep_the_outer_one_and_stages_outside_a_load_are_ignored() {
        // (The only test that begins a load in the library's tests: the state is process-wide.)
        stage("outside");
        percent(1, 2);
        let outer = begin();
        assert!(active());
        {
            let _inner = begin();
            stage("inner");
            percent(3, 4);
        }
        assert!(active(), "an inner guard does not end the load");
        {
            let st = STATE.lock().unwrap();
            let st = st.as_ref().unwrap();
            assert_eq!((st.stage.as_str(), st.percent), ("inner", Some(75)));
            // Under two seconds: nothing shown yet.
            assert!(st.logged.is_none() && !st.line);
        }
        drop(outer);
        assert!(!active());
        percent(5, 0); // a stage of nothing: no division by zero
    }
}
