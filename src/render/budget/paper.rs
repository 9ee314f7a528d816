//! Paper mode: Walewski et al. (2019)'s formulas and greedy selection as stated (symbols in the module
//! above), in f64. Degenerate inputs never produce NaN; each function says how it treats them.

use std::cmp::Ordering;

/// What the frame measured of one object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectStats {
    /// `A`: visible pixels this frame (0: not visible, never selected).
    pub pixels: u32,
    /// Projected bounding box in pixels (x right, y down); may extend off screen.
    pub bbox_min: [f32; 2],
    pub bbox_max: [f32; 2],
    /// `D`: distance from the camera in world units.
    pub distance: f32,
    pub reflective: bool,
    pub refractive: bool,
    /// `E`: the designer's cost factor (>= 0).
    pub cost_factor: f32,
    /// `K`: the designer's relevance factor (0: never ray traced).
    pub relevance: f32,
    /// `S`: selected in the previous frame.
    pub selected_last_frame: bool,
}

/// The render target's size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Screen {
    pub width: u32,
    pub height: u32,
}

/// The frame-global inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// `T`, in the paper's abstract cost units (the unit of `C`).
    pub budget: f64,
    /// `I`: the relevance bonus of an object selected last frame.
    pub stickiness: f32,
    /// Lights that cast shadows (the first term of `Q`).
    pub shadow_lights: u32,
    /// All lights (the reflection and refraction terms of `Q`).
    pub lights: u32,
}

/// One object's scores; `object` is its index in the input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scored {
    pub object: usize,
    /// `A`, so `select` can leave out invisible objects (a sticky one has `R > 0` with no pixels).
    pub pixels: u32,
    /// `V = A·P/D`.
    pub visibility: f64,
    /// `C = A·Q·E`; +inf when `E` is not a finite number >= 0.
    pub cost: f64,
    /// `R = (S·I + V)·K`.
    pub relevance: f64,
}

/// The result of `select`.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    /// Object ids in the order they were taken.
    pub selected: Vec<usize>,
    pub spent: f64,
    /// Per object id: selected. Length is one more than the largest id in the input.
    pub mask: Vec<bool>,
}

/// Lower bound on `D` (also for negative distances): a camera inside an object's bounding volume
/// measures 0, which would make `V` infinite.
pub const MIN_DISTANCE: f64 = 1e-4;

fn centrality_f64(bbox_min: [f32; 2], bbox_max: [f32; 2], screen: Screen) -> f64 {
    let (w, h) = (screen.width as f64, screen.height as f64);
    let cx = 0.5 * (bbox_min[0] as f64 + bbox_max[0] as f64);
    let cy = 0.5 * (bbox_min[1] as f64 + bbox_max[1] as f64);
    // NaN centres fail these comparisons too.
    let on_screen = (0.0..=w).contains(&cx) && (0.0..=h).contains(&cy);
    if !on_screen || w == 0.0 || h == 0.0 {
        return 0.01;
    }
    let (hw, hh) = (0.5 * w, 0.5 * h);
    let d = ((cx - hw) / hw).hypot((cy - hh) / hh) / std::f64::consts::SQRT_2;
    (1.0 - d).clamp(0.01, 1.0)
}

/// `P`: closeness of the projected box's centre to the screen centre. The paper gives only the range
/// [0.01, 1] (1 at the centre, 0.01 off screen); our falloff is `P = clamp(1 - d, 0.01, 1)` with `d`
/// the centre's offset in half-screen units over sqrt(2) (1 at a corner). A centre off
/// `[0, w] x [0, h]`, NaN, or a zero-size screen gives 0.01.
pub fn centrality(bbox_min: [f32; 2], bbox_max: [f32; 2], screen: Screen) -> f32 {
    centrality_f64(bbox_min, bbox_max, screen) as f32
}

fn rays_per_pixel_f64(shadow_lights: u32, lights: u32, reflective: bool, refractive: bool) -> f64 {
    let l = lights as f64;
    let mut q = shadow_lights as f64;
    if reflective {
        q += l + 1.0;
    }
    if refractive {
        q += l + 4.0;
    }
    q
}

/// `Q`: one shadow ray per shadow-casting light, plus `lights + 1` when reflective, plus `lights + 4`
/// when refractive.
pub fn rays_per_pixel(shadow_lights: u32, lights: u32, reflective: bool, refractive: bool) -> f32 {
    rays_per_pixel_f64(shadow_lights, lights, reflective, refractive) as f32
}

/// 0 for NaN and infinities.
fn finite_or_zero(x: f32) -> f64 {
    if x.is_finite() {
        x as f64
    } else {
        0.0
    }
}

/// `V`, `C` and `R` of every object, in input order. Degenerate inputs:
/// - `D` is clamped below by `MIN_DISTANCE`; NaN or infinite `D` is infinitely far (`V = 0`);
/// - a NaN, infinite or negative `E` makes `C` +inf: never fits, not even an infinite budget;
/// - a non-finite `K` or `I` counts as 0;
/// - a NaN bounding box gives `P = 0.01`.
///
/// Negative `K` or `I` are used as given (`K < 0`: `R <= 0`, never selected).
pub fn score(objects: &[ObjectStats], screen: Screen, params: &Params) -> Vec<Scored> {
    let stickiness = finite_or_zero(params.stickiness);
    let (shadow_lights, lights) = (params.shadow_lights, params.lights);
    objects
        .iter()
        .enumerate()
        .map(|(object, o)| {
            let a = o.pixels as f64;
            let visibility = if o.distance.is_finite() {
                let p = centrality_f64(o.bbox_min, o.bbox_max, screen);
                a * p / (o.distance as f64).max(MIN_DISTANCE)
            } else {
                0.0
            };
            let q = rays_per_pixel_f64(shadow_lights, lights, o.reflective, o.refractive);
            let e = o.cost_factor;
            let cost = if e.is_finite() && e >= 0.0 { a * q * e as f64 } else { f64::INFINITY };
            let s = if o.selected_last_frame { 1.0 } else { 0.0 };
            let relevance = (s * stickiness + visibility) * finite_or_zero(o.relevance);
            Scored { object, pixels: o.pixels, visibility, cost, relevance }
        })
        .collect()
}

/// Visible (`A > 0`), relevant (`R > 0`) and of finite cost >= 0. NaN fails.
pub(super) fn candidate(s: &Scored) -> bool {
    s.pixels > 0 && s.relevance > 0.0 && s.cost.is_finite() && s.cost >= 0.0
}

/// Higher `R` first, then lower cost (leaves more budget), then lower id: a total order on
/// candidates, so the result does not depend on input order.
pub(super) fn rank(a: &Scored, b: &Scored) -> Ordering {
    let by = |x: f64, y: f64| x.partial_cmp(&y).unwrap_or(Ordering::Equal);
    by(b.relevance, a.relevance).then(by(a.cost, b.cost)).then(a.object.cmp(&b.object))
}

/// The paper's greedy selection: while budget remains (`> 0`), take the most relevant candidate
/// (visible, `R > 0`, finite cost >= 0) whose cost fits, ties by `rank`. An infinite budget takes
/// every candidate; cost-0 objects are taken only while budget remains, so nothing is taken once it
/// is used up exactly or when it is <= 0 or NaN. A repeated id is taken at most once.
///
/// One scan in rank order instead of a search per step, same result: costs are non-negative, so an
/// object that did not fit never fits later, and the first fitting object from the scan position is
/// the one the loop would take. `tests::scan_equals_the_literal_loop` checks this.
pub fn select(scored: &[Scored], budget: f64) -> Selection {
    let ids = scored.iter().map(|s| s.object + 1).max().unwrap_or(0);
    let mut out = Selection { selected: Vec::new(), spent: 0.0, mask: vec![false; ids] };
    let mut order: Vec<&Scored> = scored.iter().filter(|s| candidate(s)).collect();
    order.sort_by(|a, b| rank(a, b));
    let mut remaining = budget;
    for s in order {
        // A budget <= 0 or NaN ends it before anything is taken.
        if remaining.is_nan() || remaining <= 0.0 {
            break;
        }
        if s.cost <= remaining && !out.mask[s.object] {
            out.mask[s.object] = true;
            out.selected.push(s.object);
            out.spent += s.cost;
            remaining -= s.cost;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCREEN: Screen = Screen { width: 200, height: 100 };

    /// Opaque, E = K = 1, not selected last frame, its box centred on `c`.
    fn obj(pixels: u32, c: [f32; 2], distance: f32) -> ObjectStats {
        ObjectStats {
            pixels,
            bbox_min: [c[0] - 10.0, c[1] - 10.0],
            bbox_max: [c[0] + 10.0, c[1] + 10.0],
            distance,
            reflective: false,
            refractive: false,
            cost_factor: 1.0,
            relevance: 1.0,
            selected_last_frame: false,
        }
    }

    fn params(stickiness: f32) -> Params {
        Params { budget: 0.0, stickiness, shadow_lights: 2, lights: 3 }
    }

    fn close(got: f64, want: f64) {
        assert!((got - want).abs() <= 1e-9 * want.abs(), "got {got}, want {want}");
    }

    fn sc(object: usize, cost: f64, relevance: f64) -> Scored {
        Scored { object, pixels: 1, visibility: 0.0, cost, relevance }
    }

    #[test]
    fn scores_match_hand_computed_values() {
        // Screen 200x100: centre (100, 50), half size (100, 50); 2 shadow
        // lights of 3; I = 0.5. Per object, A, box, D, reflective,
        // refractive, E, K, S, then by hand:
        // 0: centre (100, 50): P = 1. V = 1000·1/2 = 500. Q = 2.
        //    C = 1000·2·1.5 = 3000. R = (0 + 500)·1 = 500.
        // 1: centre (200, 50), on the right edge, the box leaving the
        //    screen: d = |(1, 0)|/√2, P = 1 - 1/√2 = 0.29289321881345254.
        //    V = 400·P/4 = 29.289321881345252. Q = 2 + (3 + 1) = 6.
        //    C = 400·6·1 = 2400. R = (1·0.5 + V)·2 = 59.578643762690504.
        // 2: centre (-40, 0), off screen: P = 0.01. V = 250·0.01/0.5 = 5.
        //    Q = 2 + (3 + 4) = 9. C = 250·9·2 = 4500. R = (0.5 + 5)·0.5 = 2.75.
        // 3: centre (150, 75): offset (0.5, 0.5), d = √0.5/√2 = 0.5, P = 0.5.
        //    V = 100·0.5/10 = 5. Q = 2 + 4 + 7 = 13. C = 100·13·0.5 = 650.
        //    R = (0 + 5)·3 = 15.
        let rows = [
            (1000, [80.0, 40.0], [120.0, 60.0], 2.0, false, false, 1.5, 1.0, false),
            (400, [150.0, 25.0], [250.0, 75.0], 4.0, true, false, 1.0, 2.0, true),
            (250, [-60.0, -20.0], [-20.0, 20.0], 0.5, false, true, 2.0, 0.5, true),
            (100, [140.0, 65.0], [160.0, 85.0], 10.0, true, true, 0.5, 3.0, false),
        ];
        let objects = rows.map(|(a, min, max, d, refl, refr, e, k, s)| {
            let mut o = obj(a, [0.0; 2], d);
            (o.bbox_min, o.bbox_max, o.reflective, o.refractive) = (min, max, refl, refr);
            (o.cost_factor, o.relevance, o.selected_last_frame) = (e, k, s);
            o
        });
        let want = [(500.0, 3000.0, 500.0), (29.289321881345252, 2400.0, 59.578643762690504)];
        let want = [want[0], want[1], (5.0, 4500.0, 2.75), (5.0, 650.0, 15.0)];
        let scored = score(&objects, SCREEN, &params(0.5));
        assert_eq!(scored.len(), 4);
        for (i, (s, (v, c, r))) in scored.iter().zip(want).enumerate() {
            assert_eq!((s.object, s.pixels), (i, objects[i].pixels));
            close(s.visibility, v);
            close(s.cost, c);
            close(s.relevance, r);
        }
        let q = objects.map(|o| rays_per_pixel(2, 3, o.reflective, o.refractive));
        assert_eq!(q, [2.0, 6.0, 9.0, 13.0]);
        // Budget 4000: 0 (R 500, 3000; 1000 left), 1 (R 59.6, 2400) does
        // not fit, 3 (R 15, 650; 350 left), 2 (R 2.75, 4500) does not fit.
        let s = select(&scored, 4000.0);
        assert_eq!((s.selected, s.spent, s.mask), (vec![0, 3], 3650.0, vec![true, false, false, true]));
    }

    #[test]
    fn centrality_is_one_at_the_centre_and_falls_to_a_hundredth() {
        let p =
            |x: f32, y: f32| centrality(obj(1, [x, y], 1.0).bbox_min, obj(1, [x, y], 1.0).bbox_max, SCREEN);
        assert_eq!(p(100.0, 50.0), 1.0);
        for (x, y) in [(-0.5, 50.0), (200.5, 50.0), (100.0, -0.5), (100.0, 100.5), (f32::NAN, 50.0)] {
            assert_eq!(p(x, y), 0.01, "centre ({x}, {y}) is off screen");
        }
        // A box mostly off screen whose centre (10, 50) is on it: 1 - 0.9/√2.
        let edge = centrality([-50.0, 0.0], [70.0, 100.0], SCREEN);
        assert!((edge - 0.363_603_9).abs() < 1e-6, "{edge}");
        assert_eq!(centrality([0.0; 2], [0.0; 2], Screen { width: 0, height: 0 }), 0.01);
        // Towards each corner: P = max(1 - t, 0.01), strictly falling.
        for (cx, cy) in [(0.0, 0.0), (200.0, 0.0), (0.0, 100.0), (200.0, 100.0)] {
            let mut last = 1.0;
            for t in (1..=20).map(|i| i as f32 / 20.0) {
                let now = p(100.0 + t * (cx - 100.0), 50.0 + t * (cy - 50.0));
                assert!((now - (1.0 - t).max(0.01)).abs() < 1e-6, "t {t}: {now}");
                assert!(now < last || now == 0.01, "t {t}: {now} after {last}");
                last = now;
            }
            assert_eq!(last, 0.01);
        }
        for x in (-100..=300).step_by(7) {
            for y in (-50..=150).step_by(7) {
                let v = p(x as f32, y as f32);
                assert!((0.01..=1.0).contains(&v), "({x}, {y}): {v}");
            }
        }
    }

    #[test]
    fn worked_example_with_budget_400() {
        // Ours (in the spirit of the paper's Figure 4), ids A..H = 0..7:
        //   A C 450 R 10 | B 150 9 | C 300 8 | D 120 7 | E 90 5 | F 40 2 | G 10 1 | H 0 0.5
        // A, the most relevant, never fits 400. B: 250 left. C fits no
        // more (300 > 250); the cheaper, less relevant D does: 130 left.
        // E: 40 left. F: 0 left, the budget used up exactly, so neither G,
        // which would fit 10, nor H, of cost 0, is taken.
        let table = [(450.0, 10.0), (150.0, 9.0), (300.0, 8.0), (120.0, 7.0), (90.0, 5.0), (40.0, 2.0)];
        let table = [&table[..], &[(10.0, 1.0), (0.0, 0.5)]].concat();
        let all: Vec<Scored> = table.iter().enumerate().map(|(i, &(c, r))| sc(i, c, r)).collect();
        let shuffled: Vec<Scored> = [4, 6, 1, 7, 0, 5, 3, 2].iter().map(|&i| all[i]).collect();
        let s = select(&shuffled, 400.0);
        assert_eq!((s.selected, s.spent), (vec![1, 3, 4, 5], 400.0));
        assert_eq!(s.mask, [false, true, false, true, true, true, false, false]);
        // 10 more: G, then none is left for H. 5 more: G does not fit, H does.
        assert_eq!(select(&shuffled, 410.0).selected, [1, 3, 4, 5, 6]);
        assert_eq!(select(&shuffled, 405.0).selected, [1, 3, 4, 5, 7]);
    }

    #[test]
    fn ties_go_to_the_cheaper_then_the_lower_id_in_any_input_order() {
        // All R = 5. Cheapest first: 3 (30; 100 left), 1 and 2 (50 each, 1
        // first by id; 0 left); 0 (100) does not fit. By id alone it would
        // be 0 then 3.
        let items = [sc(0, 100.0, 5.0), sc(1, 50.0, 5.0), sc(2, 50.0, 5.0), sc(3, 30.0, 5.0)];
        for mut k in 0..24 {
            // The k-th of the 4! input orders.
            let (mut pool, mut order) = (items.to_vec(), Vec::new());
            while !pool.is_empty() {
                let n = pool.len();
                order.push(pool.remove(k % n));
                k /= n;
            }
            assert_eq!(select(&order, 130.0).selected, [3, 1, 2], "input {order:?}");
        }
        // From score: identical objects, room for one: the lower id.
        let o = obj(100, [100.0, 50.0], 1.0);
        let scored = score(&[o, o], SCREEN, &params(0.0));
        assert_eq!(scored[0].relevance, scored[1].relevance);
        assert_eq!(select(&scored, 250.0).selected, [0]);
        assert_eq!(select(&[scored[1], scored[0]], 250.0).selected, [0]);
    }

    #[test]
    fn invisible_and_irrelevant_objects_are_never_selected() {
        let o = obj(100, [100.0, 50.0], 1.0);
        // 0: sticky with no pixels: R = (1·1 + 0)·1 = 1 > 0, yet invisible.
        // 1: K = 0. 3: E = 0, costs nothing.
        let objects = [
            ObjectStats { pixels: 0, selected_last_frame: true, ..o },
            ObjectStats { relevance: 0.0, ..o },
            o,
            ObjectStats { cost_factor: 0.0, ..o },
        ];
        let scored = score(&objects, SCREEN, &params(1.0));
        assert_eq!((scored[0].relevance, scored[3].cost), (1.0, 0.0));
        assert_eq!(select(&scored, f64::INFINITY).selected, [3, 2]);
        for budget in [0.0, -1.0, f64::NAN, f64::NEG_INFINITY] {
            let s = select(&scored, budget);
            assert!(s.selected.is_empty() && s.spent == 0.0 && s.mask == [false; 4], "{budget}: {s:?}");
        }
        assert_eq!(select(&scored, 1e-9).selected, [3]);
    }

    #[test]
    fn stickiness_favours_last_frames_selection() {
        let o = obj(100, [100.0, 50.0], 1.0);
        let objects = [o, ObjectStats { selected_last_frame: true, ..o }];
        // Room for one (cost 200 each): equal without stickiness (lower id).
        assert_eq!(select(&score(&objects, SCREEN, &params(0.0)), 300.0).selected, [0]);
        assert_eq!(select(&score(&objects, SCREEN, &params(0.5)), 300.0).selected, [1]);
    }

    #[test]
    fn degenerate_inputs_give_no_nan() {
        let o = obj(100, [100.0, 50.0], 1.0);
        let objects = [
            ObjectStats { distance: 0.0, ..o },
            ObjectStats { distance: -3.0, ..o },
            ObjectStats { distance: f32::INFINITY, selected_last_frame: true, ..o },
            ObjectStats { distance: f32::NAN, ..o },
            ObjectStats { cost_factor: f32::NAN, ..o },
            ObjectStats { cost_factor: f32::INFINITY, pixels: 0, ..o },
            ObjectStats { cost_factor: -1.0, ..o },
            ObjectStats { relevance: f32::NAN, ..o },
            ObjectStats { relevance: f32::INFINITY, ..o },
            ObjectStats { bbox_min: [f32::NAN; 2], ..o },
        ];
        for stickiness in [0.5, f32::NAN] {
            let scored = score(&objects, SCREEN, &params(stickiness));
            for s in &scored {
                assert!(!(s.visibility.is_nan() || s.cost.is_nan() || s.relevance.is_nan()), "{s:?}");
            }
            close(scored[0].visibility, 100.0 / MIN_DISTANCE);
            close(scored[1].visibility, 100.0 / MIN_DISTANCE);
            let sticky = if stickiness.is_nan() { 0.0 } else { 0.5 };
            assert_eq!((scored[2].visibility, scored[2].relevance, scored[3].visibility), (0.0, sticky, 0.0));
            assert!([4, 5, 6].iter().all(|&i| scored[i].cost == f64::INFINITY));
            assert_eq!((scored[7].relevance, scored[8].relevance), (0.0, 0.0));
            close(scored[9].visibility, 1.0);
            let want: &[usize] = if sticky > 0.0 { &[0, 1, 9, 2] } else { &[0, 1, 9] };
            assert_eq!(select(&scored, f64::INFINITY).selected, want);
        }
    }

    #[test]
    fn scan_equals_the_literal_loop() {
        fn literal(scored: &[Scored], budget: f64) -> Vec<usize> {
            let (mut taken, mut out, mut left) = (vec![false; scored.len()], Vec::new(), budget);
            while left > 0.0 {
                let fits = |&(i, s): &(usize, &Scored)| !taken[i] && candidate(s) && s.cost <= left;
                let Some((i, s)) = scored.iter().enumerate().filter(fits).min_by(|a, b| rank(a.1, b.1))
                else {
                    break;
                };
                (taken[i], left) = (true, left - s.cost);
                out.push(s.object);
            }
            out
        }
        let mut seed = 12345u64;
        let mut next = |n: u64| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) % n
        };
        for _ in 0..500 {
            let n = next(12) as usize;
            let scored: Vec<Scored> = (0..n)
                .map(|i| Scored { pixels: next(4) as u32, ..sc(i, (next(5) * 50) as f64, next(6) as f64) })
                .collect();
            // Coarse costs and budgets: ties, costs of 0 and budgets used
            // up exactly are common.
            for budget in [(next(13) * 50) as f64, f64::INFINITY] {
                assert_eq!(select(&scored, budget).selected, literal(&scored, budget), "{scored:?} {budget}");
            }
        }
    }
}
