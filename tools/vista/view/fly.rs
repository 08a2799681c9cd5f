//! The fly camera of `vista view` (WASD + mouse look, speed on the wheel,
//! Shift faster) and the scripted flights of `--path`.

use anyhow::{bail, Context as _, Result};
use glam::DVec3;
use std::path::Path;
use vista::render::Camera;
use winit::keyboard::KeyCode;

/// Degrees of yaw or pitch per pixel the mouse moves.
const LOOK_DEG_PER_PX: f64 = 0.15;
/// Speed factor of one wheel notch, and of Shift held.
const WHEEL_STEP: f64 = 1.25;
const SHIFT_FACTOR: f64 = 5.0;

pub struct FlyCamera {
    pub camera: Camera,
    /// Metres per second.
    pub speed_mps: f64,
    held: Vec<KeyCode>,
}

impl FlyCamera {
    /// Starts at `camera`, moving a tenth of the world's extent per second.
    pub fn new(camera: Camera, extent_m: [f64; 2]) -> FlyCamera {
        FlyCamera { camera, speed_mps: extent_m[0].max(extent_m[1]) / 10.0, held: Vec::new() }
    }

    pub fn key(&mut self, code: KeyCode, pressed: bool) {
        self.held.retain(|k| *k != code);
        if pressed {
            self.held.push(code);
        }
    }

    /// Forgets held keys (the window lost focus: their releases go elsewhere).
    pub fn release_all(&mut self) {
        self.held.clear();
    }

    pub fn wheel(&mut self, notches: f64) {
        self.speed_mps = (self.speed_mps * WHEEL_STEP.powf(notches)).clamp(0.1, 1e6);
    }

    pub fn look(&mut self, dx_px: f64, dy_px: f64) {
        let c = &mut self.camera;
        c.yaw_deg = (c.yaw_deg + dx_px * LOOK_DEG_PER_PX).rem_euclid(360.0);
        c.pitch_deg = (c.pitch_deg - dy_px * LOOK_DEG_PER_PX).clamp(-89.0, 89.0);
    }

    /// Moves by the held keys over `dt` seconds: W/S along the view, A/D
    /// sideways, E/Q up and down.
    pub fn update(&mut self, dt_s: f64) {
        let [forward, right, _] = self.camera.basis();
        let held = |k| self.held.contains(&k);
        let axis = |plus, minus| f64::from(u8::from(held(plus))) - f64::from(u8::from(held(minus)));
        let dir = forward * axis(KeyCode::KeyW, KeyCode::KeyS)
            + right * axis(KeyCode::KeyD, KeyCode::KeyA)
            + DVec3::Z * axis(KeyCode::KeyE, KeyCode::KeyQ);
        if dir == DVec3::ZERO {
            return;
        }
        let fast = if held(KeyCode::ShiftLeft) || held(KeyCode::ShiftRight) { SHIFT_FACTOR } else { 1.0 };
        let step = dir.normalize() * self.speed_mps * fast * dt_s;
        let p = &mut self.camera.position_m;
        *p = (DVec3::from_array(*p) + step).to_array();
    }
}

/// A scripted flight: cameras in `--camera` form, one per line (`#`
/// comments), flown through at even spacing over the run's frames; a line
/// `size WxH` asks the window for that size when the flight reaches it, a
/// line `minimise` minimises it there (`minimise.rs`), a line `lose-surface`
/// makes the next swapchain acquisition report a lost surface (injected, as
/// a window system may report it), which the viewer remakes; a line
/// `scene FILE` (relative to the flight's file) takes that scene's stamps
/// there, as an edit of the scene file would (`scene_edit.rs`).
pub struct FlightPath {
    keys: Vec<Camera>,
    /// (cameras before it, size).
    sizes: Vec<(usize, [u32; 2])>,
    /// Cameras before each `minimise` line.
    minimises: Vec<usize>,
    /// Cameras before each `lose-surface` line.
    surface_losses: Vec<usize>,
    /// (cameras before it, the scene file) of each `scene` line.
    scenes: Vec<(usize, std::path::PathBuf)>,
}

impl FlightPath {
    pub fn load(path: &Path) -> Result<FlightPath> {
        let text = std::fs::read_to_string(path).with_context(|| format!("--path {}", path.display()))?;
        let (mut keys, mut sizes, mut minimises, mut surface_losses) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut scenes = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if let Some(size) = line.strip_prefix("size ") {
                let size = crate::render_cmd::parse_size(size.trim())
                    .map_err(|e| anyhow::anyhow!("--path {} line {}: {e}", path.display(), n + 1))?;
                sizes.push((keys.len(), size));
                continue;
            }
            if line == "minimise" {
                minimises.push(keys.len());
                continue;
            }
            if line == "lose-surface" {
                surface_losses.push(keys.len());
                continue;
            }
            if let Some(file) = line.strip_prefix("scene ") {
                let dir = path.parent().unwrap_or(Path::new("."));
                let scene = vista::world::resolve_relative(dir, Path::new(file.trim()));
                // Checked now, not when the flight gets there: a typo is a
                // missing file, not a world that differs.
                if !scene.is_file() {
                    bail!("--path {} line {}: scene {}: no such file", path.display(), n + 1, scene.display());
                }
                scenes.push((keys.len(), scene));
                continue;
            }
            let arg = crate::render_cmd::parse_camera(line)
                .map_err(|e| anyhow::anyhow!("--path {} line {}: {e}", path.display(), n + 1))?;
            let [yaw_deg, pitch_deg] = arg.angles.ok_or_else(|| {
                anyhow::anyhow!("--path {} line {}: give X,Y,Z,YAW,PITCH (the heading matters)", path.display(), n + 1)
            })?;
            keys.push(Camera { position_m: arg.position, yaw_deg, pitch_deg });
        }
        if keys.is_empty() {
            bail!("--path {}: no camera in it (one X,Y,Z,YAW,PITCH per line)", path.display());
        }
        Ok(FlightPath { keys, sizes, minimises, surface_losses, scenes })
    }

    /// The frame of `frames` at which the flight reaches the line that
    /// followed `k` cameras.
    fn reached(&self, k: usize, frames: u32) -> u32 {
        let last = (self.keys.len() - 1).max(1) as f64;
        (k.saturating_sub(1) as f64 / last * f64::from(frames.saturating_sub(1))).round() as u32
    }

    /// The window size the flight asks for at `frame` of `frames`, once.
    pub fn size_at(&self, frame: u32, frames: u32) -> Option<[u32; 2]> {
        self.sizes.iter().find(|(k, _)| self.reached(*k, frames) == frame).map(|(_, s)| *s)
    }

    /// Whether the flight minimises the window at `frame` of `frames`.
    pub fn minimise_at(&self, frame: u32, frames: u32) -> bool {
        self.minimises.iter().any(|&k| self.reached(k, frames) == frame)
    }

    /// Whether the flight loses the window's surface at `frame` of `frames`.
    pub fn surface_lost_at(&self, frame: u32, frames: u32) -> bool {
        self.surface_losses.iter().any(|&k| self.reached(k, frames) == frame)
    }

    /// The scene file the flight switches to at `frame` of `frames`.
    pub fn scene_at(&self, frame: u32, frames: u32) -> Option<&Path> {
        self.scenes.iter().find(|(k, _)| self.reached(*k, frames) == frame).map(|(_, p)| p.as_path())
    }

    pub fn first(&self) -> Camera {
        self.keys[0]
    }

    /// The camera at `frame` of `frames` (the last frame at the last key).
    pub fn at(&self, frame: u32, frames: u32) -> Camera {
        let last = self.keys.len() - 1;
        if last == 0 || frames <= 1 {
            return self.keys[last];
        }
        let t = f64::from(frame.min(frames - 1)) / f64::from(frames - 1) * last as f64;
        let i = (t.floor() as usize).min(last - 1);
        let f = t - i as f64;
        let (a, b) = (self.keys[i], self.keys[i + 1]);
        let lerp = |x: f64, y: f64| x + (y - x) * f;
        // The shorter way round the compass.
        let dyaw = (b.yaw_deg - a.yaw_deg + 180.0).rem_euclid(360.0) - 180.0;
        Camera {
            position_m: std::array::from_fn(|k| lerp(a.position_m[k], b.position_m[k])),
            yaw_deg: a.yaw_deg + dyaw * f,
            pitch_deg: lerp(a.pitch_deg, b.pitch_deg),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(x: f64, yaw: f64) -> Camera {
        Camera { position_m: [x, 0.0, 100.0], yaw_deg: yaw, pitch_deg: -10.0 }
    }

    #[test]
    fn a_path_starts_at_its_first_key_and_ends_at_its_last() {
        let p = FlightPath {
            keys: vec![cam(0.0, 350.0), cam(100.0, 10.0), cam(300.0, 10.0)],
            sizes: vec![(2, [64, 32])],
            minimises: vec![1],
            surface_losses: vec![2],
            scenes: vec![(3, "s.toml".into())],
        };
        assert_eq!(p.at(0, 5), cam(0.0, 350.0));
        assert_eq!(p.at(4, 5), cam(300.0, 10.0));
        let mid = p.at(1, 5);
        assert!((mid.position_m[0] - 50.0).abs() < 1e-9);
        // Half-way from 350 to 10 degrees the short way is 360 (= 0).
        assert!((mid.yaw_deg.rem_euclid(360.0)).abs() < 1e-9, "{}", mid.yaw_deg);
        // After the second camera: reached at frame 2 of 5.
        assert_eq!(p.size_at(2, 5), Some([64, 32]));
        assert_eq!(p.size_at(3, 5), None);
        // After the first camera: the start.
        assert!(p.minimise_at(0, 5) && !p.minimise_at(1, 5));
        assert!(p.surface_lost_at(2, 5) && !p.surface_lost_at(0, 5));
        assert_eq!(p.scene_at(4, 5), Some(Path::new("s.toml")));
    }

    #[test]
    fn keys_move_the_camera_along_its_view() {
        let mut f = FlyCamera::new(Camera { position_m: [0.0; 3], yaw_deg: 90.0, pitch_deg: 0.0 }, [100.0, 100.0]);
        f.key(KeyCode::KeyW, true);
        f.update(1.0);
        // Yaw 90 looks toward +x; 10 m/s for a 100 m world.
        assert!((f.camera.position_m[0] - 10.0).abs() < 1e-9, "{:?}", f.camera.position_m);
        f.key(KeyCode::KeyW, false);
        f.update(1.0);
        assert!((f.camera.position_m[0] - 10.0).abs() < 1e-9);
    }
}
