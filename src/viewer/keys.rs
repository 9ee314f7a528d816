//! The viewer's keys, listed once: `view --help` prints them, and a test
//! holds the README's key table to this list.

/// (keys, what they do), in the README's order.
pub const KEYS: &[(&str, &str)] = &[
    ("W A S D, Q / E", "fly forward/left/back/right, down/up (speed scales with the scene size)"),
    ("right or left mouse drag", "look around (orbit mode: rotate around the scene centre)"),
    ("Shift (held), mouse wheel", "4x speed; wheel scales the speed"),
    ("O", "toggle orbit mode around the scene-bounds centre (W/S dolly, A/D/Q/E orbit)"),
    ("C / Shift+C, Ctrl+1..9", "next / previous scene camera, scene camera N"),
    ("R", "reset to the starting camera and speed"),
    ("1..6, 0, V", "debug view albedo, normal, depth, material, object, budget selection; 0 (or the same key again) lit; V cycles"),
    ("- / =", "exposure down / up (half a stop; with auto exposure, the compensation)"),
    ("M / X", "next tone operator / next auto-exposure mode (off, log-average, histogram)"),
    ("F5 / F6 / F7", "toggle shadows / reflections / refractions (effects the scene needs)"),
    ("F8, [ / ], ;, B", "ray-tracing budget off -> effects mode -> paper mode (each from everything, keeping the stickiness and fallback); halve / double it; stickiness 0 -> 10 -> 100 -> 1000; fallback raster <-> none (the title shows T, the objects selected and the ray passes' GPU ms)"),
    ("G", "cycle anti-aliasing: edge -> fxaa -> none"),
    ("T", "hybrid / pure ray-traced mode (needs ray query)"),
    ("K", "path-traced ground truth on / off (--mode path): 4 samples per pixel a frame, accumulated while the camera, environment and scene stay still (the title shows the count); debug views are off there"),
    ("Space, , / .", "with --animation: pause / play (wall clock, or a fixed 1 / --fps s per frame when --fps is given), scrub -/+ 0.1 s"),
    ("F12 or P", "screenshot PNG (--screenshot path, else out/screenshot-*.png)"),
    ("F9", "RenderDoc capture of the next frame (when running under RenderDoc, or with --capture-frame)"),
    ("Esc", "quit"),
];

/// The keys as `view --help`'s epilogue.
pub fn help() -> String {
    let width = KEYS.iter().map(|(k, _)| k.chars().count()).max().unwrap_or(0);
    let rows: Vec<String> = KEYS.iter().map(|(k, d)| format!("  {k:<width$}  {d}")).collect();
    format!("Keys:\n{}", rows.join("\n"))
}

#[cfg(test)]
mod tests {
    /// The README's viewer key table lists these keys, in this order.
    #[test]
    fn readme_lists_the_same_keys() {
        let readme = include_str!("../../README.md");
        let section = &readme[readme.find("## Viewer").unwrap()..readme.find("## Architecture").unwrap()];
        let keys: Vec<String> = section
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| keys"))
            .map(|l| l.trim_matches('|').split(" | ").next().unwrap().trim().replace('`', ""))
            .collect();
        let ours: Vec<&str> = super::KEYS.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, ours);
    }
}
