//! The viewer's camera: an orbit camera around a pivot that can also fly (move the eye and the
//! pivot together, look around from the eye), and the camera paths of scripted runs.
//!
//! The state is an eye, a heading (yaw about +y, pitch above the horizon) and the distance to the
//! pivot straight ahead; the runtime's [`Camera`] (eye, target, vertical field of view) is read
//! off it every frame, so a camera given as eye and target comes back unchanged.

use glam::Vec3;
use hce_runtime::gpu::Camera;

/// Pitch stays this far (radians) from straight up or down, where yaw is undefined.
const PITCH_LIMIT: f32 = 1.55;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCamera {
    pub eye: Vec3,
    /// Radians about +y; 0 looks down −z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Distance from the eye to the orbit pivot, straight ahead.
    pub distance: f32,
    pub fov_y_degrees: f32,
}

impl ViewCamera {
    pub fn from_camera(c: &Camera) -> Self {
        let eye = Vec3::from(c.eye);
        let d = Vec3::from(c.target) - eye;
        let distance = d.length().max(1e-6);
        let dir = d / distance;
        Self {
            eye,
            yaw: (-dir.x).atan2(-dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin(),
            distance,
            fov_y_degrees: c.fov_y_degrees,
        }
    }

    /// Unit vector from the eye towards the pivot.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, sp, -cy * cp)
    }

    /// Unit vector to the right of the view, horizontal.
    pub fn right(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        Vec3::new(cy, 0.0, -sy)
    }

    pub fn up(&self) -> Vec3 {
        self.right().cross(self.forward())
    }

    pub fn pivot(&self) -> Vec3 {
        self.eye + self.forward() * self.distance
    }

    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye.into(),
            target: self.pivot().into(),
            fov_y_degrees: self.fov_y_degrees,
        }
    }

    /// Turns the view by `dyaw`, `dpitch` radians about the pivot (the eye moves, the pivot
    /// stays): orbiting.
    pub fn orbit(&mut self, dyaw: f32, dpitch: f32) {
        let pivot = self.pivot();
        self.turn(dyaw, dpitch);
        self.eye = pivot - self.forward() * self.distance;
    }

    /// Turns the view by `dyaw`, `dpitch` radians about the eye (the pivot moves): looking
    /// around while flying.
    pub fn turn(&mut self, dyaw: f32, dpitch: f32) {
        self.yaw = (self.yaw + dyaw).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + dpitch).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves the eye and the pivot together by `right`, `up`, `forward` world units along the
    /// view's axes: flying and panning.
    pub fn translate(&mut self, right: f32, up: f32, forward: f32) {
        self.eye += self.right() * right + self.up() * up + self.forward() * forward;
    }

    /// Moves the eye towards the pivot (`factor` < 1) or away from it, keeping the pivot.
    pub fn dolly(&mut self, factor: f32) {
        let pivot = self.pivot();
        self.distance = (self.distance * factor).max(1e-4);
        self.eye = pivot - self.forward() * self.distance;
    }
}

/// The camera of each frame of a scripted run (`--camera-path`).
#[derive(Clone, Debug, PartialEq)]
pub enum CameraPath {
    /// Through these cameras in order, linearly (eye, target and field of view), the first at
    /// the first frame and the last at the last.
    Keys(Vec<Camera>),
    /// From the start camera towards its target, ending `1 - fraction` of the way there: a
    /// walk into the scene that raises the levels as objects come closer.
    Approach { fraction: f32 },
}

impl CameraPath {
    /// Parses `approach[:FRACTION]` or cameras `EYE:TARGET[:FOV]` separated by `;`.
    pub fn parse(s: &str) -> anyhow::Result<Self> {
        use anyhow::{bail, Context};
        if let Some(rest) = s.strip_prefix("approach") {
            let fraction = match rest.strip_prefix(':') {
                Some(f) => f
                    .parse::<f32>()
                    .ok()
                    .filter(|f| *f > 0.0 && *f < 1.0)
                    .with_context(|| {
                        format!("--camera-path {s:?}: the fraction must be between 0 and 1")
                    })?,
                None if rest.is_empty() => 0.9,
                None => bail!("--camera-path {s:?}: expected approach or approach:FRACTION"),
            };
            return Ok(Self::Approach { fraction });
        }
        let keys = s
            .split(';')
            .map(|k| match crate::cmd::render::parse_camera(k.trim())? {
                Some(c) => Ok(c),
                None => bail!("--camera-path: `auto` cannot be a key; give EYE:TARGET[:FOV]"),
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        if keys.len() < 2 {
            bail!("--camera-path {s:?}: give at least two cameras EYE:TARGET[:FOV] separated by ;, or approach");
        }
        Ok(Self::Keys(keys))
    }

    /// The camera of frame `frame` of `frames`, starting from `start`.
    pub fn at(&self, start: &Camera, frame: u32, frames: u32) -> Camera {
        let t = if frames <= 1 {
            1.0
        } else {
            frame.min(frames - 1) as f32 / (frames - 1) as f32
        };
        match self {
            Self::Approach { fraction } => {
                let eye = Vec3::from(start.eye);
                let target = Vec3::from(start.target);
                Camera {
                    eye: eye.lerp(target, t * fraction).into(),
                    ..*start
                }
            }
            Self::Keys(keys) => {
                let span = t * (keys.len() - 1) as f32;
                let i = (span.floor() as usize).min(keys.len() - 2);
                let u = span - i as f32;
                let (a, b) = (&keys[i], &keys[i + 1]);
                Camera {
                    eye: Vec3::from(a.eye).lerp(Vec3::from(b.eye), u).into(),
                    target: Vec3::from(a.target).lerp(Vec3::from(b.target), u).into(),
                    fov_y_degrees: a.fov_y_degrees + (b.fov_y_degrees - a.fov_y_degrees) * u,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f32; 3], b: [f32; 3]) -> bool {
        (Vec3::from(a) - Vec3::from(b)).length() < 1e-4
    }

    #[test]
    fn a_camera_round_trips_and_orbiting_keeps_the_pivot() {
        let c = Camera {
            eye: [3.0, 2.0, 5.0],
            target: [0.5, 0.0, -1.0],
            fov_y_degrees: 35.0,
        };
        let mut v = ViewCamera::from_camera(&c);
        let back = v.camera();
        assert!(
            close(back.eye, c.eye) && close(back.target, c.target),
            "{back:?}"
        );
        assert_eq!(back.fov_y_degrees, 35.0);
        let (pivot, dist) = (v.pivot(), v.distance);
        v.orbit(0.7, -0.3);
        assert!(close(v.pivot().into(), pivot.into()));
        assert!(((v.eye - pivot).length() - dist).abs() < 1e-4);
        assert!(!close(v.eye.into(), c.eye), "orbiting moved nothing");
        // Turning keeps the eye and moves the pivot.
        let eye = v.eye;
        v.turn(0.2, 0.1);
        assert_eq!(v.eye, eye);
        assert!(!close(v.pivot().into(), pivot.into()));
        // Pitch stops short of the pole.
        v.turn(0.0, 10.0);
        assert_eq!(v.pitch, PITCH_LIMIT);
    }

    #[test]
    fn flying_moves_eye_and_pivot_along_the_view() {
        let mut v = ViewCamera::from_camera(&Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0; 3],
            fov_y_degrees: 40.0,
        });
        v.translate(1.0, 0.0, 2.0);
        assert!(close(v.eye.into(), [1.0, 0.0, 3.0]), "{:?}", v.eye);
        assert!(close(v.pivot().into(), [1.0, 0.0, -2.0]));
        v.dolly(0.5);
        assert!(close(v.eye.into(), [1.0, 0.0, 0.5]), "{:?}", v.eye);
    }

    #[test]
    fn paths_interpolate_and_explain_bad_input() {
        let start = Camera {
            eye: [0.0, 0.0, 10.0],
            target: [0.0; 3],
            fov_y_degrees: 40.0,
        };
        let p = CameraPath::parse("approach").unwrap();
        assert!(close(p.at(&start, 0, 5).eye, [0.0, 0.0, 10.0]));
        assert!(close(p.at(&start, 4, 5).eye, [0.0, 0.0, 1.0]));
        let p = CameraPath::parse("0,0,4:0,0,0:30;0,0,2:0,0,0:50;2,0,2:0,0,0:50").unwrap();
        let mid = p.at(&start, 1, 5);
        assert!(close(mid.eye, [0.0, 0.0, 3.0]), "{mid:?}");
        assert_eq!(mid.fov_y_degrees, 40.0);
        assert!(close(p.at(&start, 4, 5).eye, [2.0, 0.0, 2.0]));
        assert!(CameraPath::parse("0,0,4:0,0,0").is_err());
        assert!(CameraPath::parse("approach:1.5").is_err());
        assert!(CameraPath::parse("auto;0,0,4:0,0,0").is_err());
    }
}
