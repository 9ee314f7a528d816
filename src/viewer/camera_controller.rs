//! Fly / orbit camera for the viewer.
//!
//! Fly: WASD moves along the view direction and sideways, Q/E down/up, mouse look while a mouse button
//! (right or left) is held; Shift is 4x faster, the wheel scales the speed. Orbit (O): the camera
//! circles the scene-bounds centre; dragging rotates around it, W/S dolly, A/D and Q/E orbit.
//! C / Shift+C cycle the scene's cameras, Ctrl+1..9 pick one, R resets.
//!
//! Speeds scale with the scene bounds so a 1 m and a 100 m scene take the same time to cross. Until the
//! user moves, [`CameraController::camera`] returns the starting camera unchanged (no yaw/pitch round
//! trip), so a still viewer shows exactly what a headless render of that camera shows.

use glam::Vec3;
use winit::keyboard::KeyCode;

use crate::scene::{Aabb, Camera};

/// Radians per pixel of mouse motion.
pub const MOUSE_SENSITIVITY: f32 = 0.003;
/// Pitch limit (just short of straight up/down, where yaw is undefined).
pub const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;
/// Speed factor while Shift is held.
pub const FAST_FACTOR: f32 = 4.0;
/// Seconds to fly across the scene's bounding-box diagonal at base speed.
pub const CROSSING_SECONDS: f32 = 4.0;
/// Orbit angular speed (A/D/Q/E in orbit mode), radians per second.
pub const ORBIT_RATE: f32 = 1.0;
/// Speed change per mouse-wheel notch.
pub const WHEEL_STEP: f32 = 1.2;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Fly,
    Orbit,
}

/// Unit view direction for yaw (about +Y, 0 = looking down -Z, positive
/// turns right towards +X) and pitch (positive looks up).
pub fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), -pitch.cos() * yaw.cos())
}

/// Inverse of [`direction`]: (yaw, pitch) of a direction (need not be unit).
pub fn yaw_pitch(dir: Vec3) -> (f32, f32) {
    let d = dir.try_normalize().unwrap_or(Vec3::NEG_Z);
    let pitch = d.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
    let yaw = if d.x.abs() < 1e-9 && d.z.abs() < 1e-9 { 0.0 } else { d.x.atan2(-d.z) };
    (yaw, pitch)
}

/// Base speed (m/s) for a scene: its bounding-box diagonal in
/// [`CROSSING_SECONDS`]; 1 m-ish when the bounds are empty.
pub fn base_speed(bounds: &Aabb) -> f32 {
    let size = bounds.extent().length();
    let size = if size.is_finite() && size > 0.0 { size } else { 1.0 };
    size.max(1e-4) / CROSSING_SECONDS
}

#[derive(Clone, Copy, Debug, Default)]
struct Held {
    forward: bool,
    back: bool,
    left: bool,
    right: bool,
    up: bool,
    down: bool,
    shift_left: bool,
    shift_right: bool,
}

impl Held {
    fn axis(pos: bool, neg: bool) -> f32 {
        pos as i32 as f32 - neg as i32 as f32
    }
    fn any_motion(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
    fn fast(&self) -> bool {
        self.shift_left || self.shift_right
    }
}

pub struct CameraController {
    /// The camera the viewer started with (R returns to it).
    initial: Camera,
    initial_index: Option<usize>,
    /// The scene's cameras (C cycles them).
    cameras: Vec<Camera>,
    /// Which scene camera is shown, until the user moves.
    index: Option<usize>,
    /// Shown unchanged until the user moves or turns.
    pristine: Option<Camera>,
    position: Vec3,
    yaw: f32,
    pitch: f32,
    yfov: f32,
    znear: f32,
    mode: Mode,
    center: Vec3,
    orbit_distance: f32,
    base_speed: f32,
    speed_scale: f32,
    held: Held,
    buttons_down: u32,
    look: (f32, f32),
}

impl CameraController {
    /// `start` is the camera to show first; `start_index` its index in
    /// `cameras` when it is one of the scene's.
    pub fn new(bounds: Aabb, cameras: Vec<Camera>, start: Camera, start_index: Option<usize>) -> Self {
        let center = if bounds.is_empty() { Vec3::ZERO } else { bounds.center() };
        let mut c = CameraController {
            initial: start.clone(),
            initial_index: start_index,
            cameras,
            index: start_index,
            pristine: None,
            position: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            yfov: start.yfov,
            znear: start.znear,
            mode: Mode::Fly,
            center,
            orbit_distance: 1.0,
            base_speed: base_speed(&bounds),
            speed_scale: 1.0,
            held: Held::default(),
            buttons_down: 0,
            look: (0.0, 0.0),
        };
        c.show(start);
        c
    }

    /// Shows `cam` unchanged and takes its pose as the starting point for moves.
    fn show(&mut self, cam: Camera) {
        self.position = cam.position();
        (self.yaw, self.pitch) = yaw_pitch(cam.forward());
        self.yfov = cam.yfov;
        self.znear = cam.znear;
        self.orbit_distance = self.position.distance(self.center).max(self.min_distance());
        self.pristine = Some(cam);
        if self.mode == Mode::Orbit {
            self.enter_orbit();
        }
    }

    fn min_distance(&self) -> f32 {
        self.base_speed * CROSSING_SECONDS * 1e-3
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Index of the scene camera being shown, while unmoved.
    pub fn camera_index(&self) -> Option<usize> {
        self.index
    }

    /// Current translation speed in m/s (Shift included).
    pub fn speed(&self) -> f32 {
        self.base_speed * self.speed_scale * if self.held.fast() { FAST_FACTOR } else { 1.0 }
    }

    pub fn position(&self) -> Vec3 {
        self.position
    }

    pub fn forward(&self) -> Vec3 {
        direction(self.yaw, self.pitch)
    }

    /// True while the starting / selected camera is shown untouched.
    pub fn is_pristine(&self) -> bool {
        self.pristine.is_some()
    }

    /// The camera to render this frame.
    pub fn camera(&self) -> Camera {
        match &self.pristine {
            Some(c) => c.clone(),
            None => Camera::look_at(
                "viewer",
                self.position,
                self.position + self.forward(),
                self.yfov,
                self.znear,
            ),
        }
    }

    fn touch(&mut self) {
        self.pristine = None;
        self.index = None;
    }

    /// Handles a key; returns whether the controller used it. `ctrl`: a
    /// Control key is held (Ctrl+1..9 selects scene camera 1..9).
    pub fn key(&mut self, code: KeyCode, pressed: bool, ctrl: bool) -> bool {
        let h = &mut self.held;
        match code {
            KeyCode::KeyW => h.forward = pressed,
            KeyCode::KeyS => h.back = pressed,
            KeyCode::KeyA => h.left = pressed,
            KeyCode::KeyD => h.right = pressed,
            KeyCode::KeyQ => h.down = pressed,
            KeyCode::KeyE => h.up = pressed,
            KeyCode::ShiftLeft => h.shift_left = pressed,
            KeyCode::ShiftRight => h.shift_right = pressed,
            KeyCode::KeyO if pressed => self.toggle_orbit(),
            KeyCode::KeyR if pressed => self.reset(),
            KeyCode::KeyC if pressed => {
                let step = if self.held.fast() { -1 } else { 1 };
                self.cycle_camera(step);
            }
            _ if pressed && ctrl => match digit(code) {
                Some(d) if d >= 1 => {
                    self.select_camera(d as usize - 1);
                }
                _ => return false,
            },
            _ => return false,
        }
        true
    }

    /// Forgets held keys and buttons (the window lost focus).
    pub fn release_all(&mut self) {
        self.held = Held::default();
        self.buttons_down = 0;
    }

    /// A mouse button (left or right) went down or up.
    pub fn mouse_button(&mut self, pressed: bool) {
        if pressed {
            self.buttons_down += 1;
        } else {
            self.buttons_down = self.buttons_down.saturating_sub(1);
        }
    }

    pub fn is_looking(&self) -> bool {
        self.buttons_down > 0
    }

    /// Cursor motion in pixels; turns the camera while a button is held.
    pub fn mouse_motion(&mut self, dx: f32, dy: f32) {
        if self.is_looking() && dx.is_finite() && dy.is_finite() {
            self.look.0 += dx;
            self.look.1 += dy;
        }
    }

    /// Mouse wheel, in notches (positive = faster).
    pub fn scroll(&mut self, notches: f32) {
        if notches.is_finite() {
            self.speed_scale = (self.speed_scale * WHEEL_STEP.powf(notches)).clamp(1e-3, 1e3);
        }
    }

    pub fn toggle_orbit(&mut self) {
        match self.mode {
            Mode::Fly => {
                self.mode = Mode::Orbit;
                self.enter_orbit();
                self.touch();
            }
            Mode::Orbit => self.mode = Mode::Fly,
        }
        log::info!("camera: {:?} mode", self.mode);
    }

    /// Looks at the bounds centre from the current distance.
    fn enter_orbit(&mut self) {
        self.orbit_distance = self.position.distance(self.center).max(self.min_distance());
        (self.yaw, self.pitch) = yaw_pitch(self.center - self.position);
        self.place_on_orbit();
    }

    fn place_on_orbit(&mut self) {
        self.position = self.center - self.forward() * self.orbit_distance;
    }

    /// Back to the starting camera, speed and fly mode.
    pub fn reset(&mut self) {
        self.mode = Mode::Fly;
        self.speed_scale = 1.0;
        self.look = (0.0, 0.0);
        self.show(self.initial.clone());
        self.index = self.initial_index;
        log::info!("camera: reset");
    }

    /// Shows scene camera `i` (ignored when it does not exist).
    pub fn select_camera(&mut self, i: usize) -> bool {
        let Some(cam) = self.cameras.get(i).cloned() else {
            log::info!("camera: the scene has no camera {} (it has {})", i + 1, self.cameras.len());
            return false;
        };
        log::info!("camera: scene camera {} '{}'", i + 1, cam.name);
        self.show(cam);
        self.index = Some(i);
        true
    }

    /// Next (`step` = 1) or previous (-1) scene camera, wrapping around.
    pub fn cycle_camera(&mut self, step: i32) {
        let n = self.cameras.len() as i32;
        if n == 0 {
            return;
        }
        let next = match self.index {
            Some(i) => (i as i32 + step).rem_euclid(n),
            None if step >= 0 => 0,
            None => n - 1,
        };
        self.select_camera(next as usize);
    }

    /// Applies the input gathered since the last frame over `dt` seconds; whether the camera changed.
    pub fn update(&mut self, dt: f32) -> bool {
        let dt = if dt.is_finite() { dt.clamp(0.0, 0.25) } else { 0.0 };
        let (dx, dy) = std::mem::take(&mut self.look);
        let turning = dx != 0.0 || dy != 0.0;
        let moving = self.held.any_motion() && dt > 0.0;
        if !turning && !moving {
            return false;
        }
        self.touch();
        self.yaw = (self.yaw + dx * MOUSE_SENSITIVITY).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch - dy * MOUSE_SENSITIVITY).clamp(-MAX_PITCH, MAX_PITCH);
        let h = self.held;
        match self.mode {
            Mode::Fly => {
                let fwd = self.forward();
                let right = fwd.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
                let dir = fwd * Held::axis(h.forward, h.back)
                    + right * Held::axis(h.right, h.left)
                    + Vec3::Y * Held::axis(h.up, h.down);
                if let Some(dir) = dir.try_normalize() {
                    self.position += dir * self.speed() * dt;
                }
            }
            Mode::Orbit => {
                let fast = if h.fast() { FAST_FACTOR } else { 1.0 };
                self.yaw -= Held::axis(h.right, h.left) * ORBIT_RATE * fast * dt;
                self.pitch = (self.pitch + Held::axis(h.up, h.down) * ORBIT_RATE * fast * dt)
                    .clamp(-MAX_PITCH, MAX_PITCH);
                self.orbit_distance = (self.orbit_distance
                    - Held::axis(h.forward, h.back) * self.speed() * dt)
                    .max(self.min_distance());
                self.place_on_orbit();
            }
        }
        true
    }
}

/// 0..9 for the digit keys (main row and keypad).
pub fn digit(code: KeyCode) -> Option<u32> {
    Some(match code {
        KeyCode::Digit0 | KeyCode::Numpad0 => 0,
        KeyCode::Digit1 | KeyCode::Numpad1 => 1,
        KeyCode::Digit2 | KeyCode::Numpad2 => 2,
        KeyCode::Digit3 | KeyCode::Numpad3 => 3,
        KeyCode::Digit4 | KeyCode::Numpad4 => 4,
        KeyCode::Digit5 | KeyCode::Numpad5 => 5,
        KeyCode::Digit6 | KeyCode::Numpad6 => 6,
        KeyCode::Digit7 | KeyCode::Numpad7 => 7,
        KeyCode::Digit8 | KeyCode::Numpad8 => 8,
        KeyCode::Digit9 | KeyCode::Numpad9 => 9,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(size: f32) -> Aabb {
        Aabb { min: Vec3::splat(-0.5 * size), max: Vec3::splat(0.5 * size) }
    }

    fn cam(from: Vec3, to: Vec3) -> Camera {
        Camera::look_at("t", from, to, 1.0, 0.01)
    }

    fn controller(size: f32) -> CameraController {
        let start = cam(Vec3::new(0.0, 0.0, size), Vec3::ZERO);
        CameraController::new(cube(size), vec![start.clone()], start, Some(0))
    }

    fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
        (a - b).length() <= eps
    }

    #[test]
    fn direction_and_yaw_pitch_round_trip() {
        assert!(close(direction(0.0, 0.0), Vec3::NEG_Z, 1e-6));
        assert!(close(direction(std::f32::consts::FRAC_PI_2, 0.0), Vec3::X, 1e-6));
        assert!(close(direction(0.0, 0.5), Vec3::new(0.0, 0.5f32.sin(), -0.5f32.cos()), 1e-6));
        for d in [Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, -1.0, 0.5), Vec3::new(0.3, 0.0, -2.0)] {
            let (y, p) = yaw_pitch(d);
            assert!(close(direction(y, p), d.normalize(), 1e-5), "{d}");
        }
        // Straight up clamps the pitch instead of producing NaN.
        let (y, p) = yaw_pitch(Vec3::Y);
        assert!(y.is_finite() && (p - MAX_PITCH).abs() < 1e-6);
    }

    #[test]
    fn unmoved_camera_is_the_start_camera_exactly() {
        let start = Camera { yfov: 0.7, ..cam(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, 0.0)) };
        let mut c = CameraController::new(cube(2.0), vec![], start.clone(), None);
        assert!(!c.update(0.016));
        let got = c.camera();
        assert_eq!(got.world, start.world);
        assert_eq!((got.yfov, got.znear), (start.yfov, start.znear));
        // Motion without a held button does not turn the camera.
        c.mouse_motion(50.0, 20.0);
        assert!(!c.update(0.016));
        assert!(c.is_pristine());
    }

    #[test]
    fn first_move_continues_from_the_start_pose() {
        let start = cam(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, 0.0));
        let mut c = CameraController::new(cube(2.0), vec![], start.clone(), None);
        c.key(KeyCode::KeyW, true, false);
        assert!(c.update(0.01));
        let moved = c.camera();
        assert!(close(moved.forward(), start.forward(), 1e-5));
        let step = c.speed() * 0.01;
        assert!(close(moved.position(), start.position() + start.forward() * step, 1e-5));
    }

    #[test]
    fn speed_scales_with_the_scene_size() {
        let mut small = controller(1.0);
        let mut big = controller(100.0);
        for c in [&mut small, &mut big] {
            c.key(KeyCode::KeyW, true, false);
            c.update(0.1);
        }
        let d_small = small.position().distance(Vec3::new(0.0, 0.0, 1.0));
        let d_big = big.position().distance(Vec3::new(0.0, 0.0, 100.0));
        assert!((d_big / d_small - 100.0).abs() < 1e-2, "{d_small} {d_big}");
        // Crossing the diagonal takes CROSSING_SECONDS at base speed.
        assert!((small.speed() * CROSSING_SECONDS - 3f32.sqrt()).abs() < 1e-5);
    }

    #[test]
    fn shift_and_wheel_change_the_speed() {
        let mut c = controller(10.0);
        let base = c.speed();
        c.key(KeyCode::ShiftLeft, true, false);
        assert!((c.speed() / base - FAST_FACTOR).abs() < 1e-5);
        c.key(KeyCode::ShiftLeft, false, false);
        c.scroll(2.0);
        assert!((c.speed() / base - WHEEL_STEP * WHEEL_STEP).abs() < 1e-4);
        c.scroll(-2.0);
        assert!((c.speed() / base - 1.0).abs() < 1e-5);
    }

    #[test]
    fn strafe_and_vertical_moves() {
        let mut c = controller(4.0); // at (0,0,4) looking down -Z
        c.key(KeyCode::KeyD, true, false);
        c.update(0.1);
        let p = c.position();
        assert!(p.x > 0.0 && p.y.abs() < 1e-6 && (p.z - 4.0).abs() < 1e-5, "{p}");
        c.key(KeyCode::KeyD, false, false);
        c.key(KeyCode::KeyE, true, false);
        c.update(0.1);
        assert!(c.position().y > 0.0);
    }

    #[test]
    fn mouse_look_turns_and_clamps_pitch() {
        let mut c = controller(2.0);
        c.mouse_button(true);
        c.mouse_motion(100.0, 0.0); // right
        assert!(c.update(0.016));
        assert!(c.forward().x > 0.0);
        c.mouse_motion(0.0, -1e6); // far up
        c.update(0.016);
        let (_, pitch) = yaw_pitch(c.forward());
        assert!((pitch - MAX_PITCH).abs() < 1e-4);
        assert!(c.camera().world.is_finite());
        c.mouse_button(false);
        c.mouse_motion(10.0, 10.0);
        assert!(!c.update(0.016));
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_centre() {
        let bounds = Aabb { min: Vec3::new(1.0, 1.0, 1.0), max: Vec3::new(3.0, 3.0, 3.0) };
        let start = cam(Vec3::new(2.0, 2.0, 10.0), Vec3::new(0.0, 2.0, 0.0)); // not aimed at the centre
        let mut c = CameraController::new(bounds, vec![], start, None);
        let centre = Vec3::splat(2.0);
        c.toggle_orbit();
        assert_eq!(c.mode(), Mode::Orbit);
        let r = c.position().distance(centre);
        assert!((r - 8.0).abs() < 1e-4);
        c.mouse_button(true);
        for _ in 0..10 {
            c.mouse_motion(37.0, -11.0);
            c.key(KeyCode::KeyA, true, false);
            c.update(0.05);
            assert!((c.position().distance(centre) - r).abs() < 1e-3);
            assert!(close(c.forward(), (centre - c.position()).normalize(), 1e-4));
        }
        c.key(KeyCode::KeyA, false, false);
        c.key(KeyCode::KeyW, true, false);
        c.update(0.1);
        assert!(c.position().distance(centre) < r);
        // Dollying never passes through the centre.
        c.update(0.25);
        c.update(0.25);
        c.update(0.25);
        assert!(c.position().distance(centre) > 0.0);
        c.toggle_orbit();
        assert_eq!(c.mode(), Mode::Fly);
    }

    #[test]
    fn cameras_cycle_select_and_reset() {
        let cams = vec![cam(Vec3::Z, Vec3::ZERO), cam(Vec3::X, Vec3::ZERO), cam(Vec3::Y * 2.0, Vec3::ZERO)];
        let mut c = CameraController::new(cube(1.0), cams.clone(), cams[0].clone(), Some(0));
        c.key(KeyCode::KeyC, true, false);
        assert_eq!(c.camera_index(), Some(1));
        assert_eq!(c.camera().world, cams[1].world);
        c.cycle_camera(1);
        c.cycle_camera(1);
        assert_eq!(c.camera_index(), Some(0));
        c.cycle_camera(-1);
        assert_eq!(c.camera_index(), Some(2));
        assert!(c.key(KeyCode::Digit2, true, true));
        assert_eq!(c.camera_index(), Some(1));
        assert!(!c.key(KeyCode::Digit2, true, false), "plain digits are the viewer's");
        assert!(!c.select_camera(7));
        // Move away, then R brings back the starting camera exactly.
        c.key(KeyCode::KeyW, true, false);
        c.update(0.1);
        assert!(c.camera_index().is_none());
        c.key(KeyCode::KeyW, false, false);
        c.scroll(3.0);
        c.key(KeyCode::KeyR, true, false);
        assert_eq!(c.camera().world, cams[0].world);
        assert_eq!(c.camera_index(), Some(0));
        assert!((c.speed() - base_speed(&cube(1.0))).abs() < 1e-6);
    }

    #[test]
    fn empty_bounds_still_give_a_usable_speed() {
        assert!((base_speed(&Aabb::EMPTY) - 1.0 / CROSSING_SECONDS).abs() < 1e-6);
        let c = CameraController::new(Aabb::EMPTY, vec![], cam(Vec3::Z, Vec3::ZERO), None);
        assert!(c.speed() > 0.0 && c.speed().is_finite());
    }
}
