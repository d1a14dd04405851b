//! The scene the radiosity solver (`hce-bake`) and the reference path tracer (`hce-reference`)
//! both read: world-space triangle objects with diffuse materials, emissive triangles and
//! punctual lights. It lives here, below both, so that the path tracer can read the solver's
//! input without sharing any of the solver's code; the importer (`scene`, feature
//! `import`) produces it and `ToSolver` turns its output into one.
//!
//! Units follow glTF: positions in metres; punctual light intensity in candela for point and
//! spot lights and in lux for directional lights. Emission and every colour the solver returns
//! are outgoing *radiance* in the same linear units (what a viewer displays), so a material with
//! emission `e` shows as `e`, and a white (`ρ = 1`) surface lit head-on by a directional light
//! of `E` lux shows as `E / π`.

use std::sync::Arc;

use glam::Vec3;

/// Most normals a triangle's set may hold (n0 included).
pub const MAX_NORMALS_PER_TRIANGLE: usize = 64;

/// Why a [`Scene`] cannot be solved or path-traced: the first problem [`Scene::validate`]
/// finds, naming the object or light.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    #[error("{object}: {reason}")]
    InvalidObject { object: String, reason: String },
    #[error("{light}: {reason}")]
    InvalidLight { light: String, reason: String },
    #[error(
        "the scene has no light source: add a punctual light (KHR_lights_punctual) or an \
         emissive material"
    )]
    NoLight,
}

/// Diffuse reflectance of part of a triangle: called with the triangle index and the
/// barycentric coordinates of the element's three corners, returns the average reflectance
/// over that element (so a textured material can average its texture over exactly the area
/// the element covers).
pub type ReflectanceFn = dyn Fn(usize, [[f32; 3]; 3]) -> [f32; 3] + Send + Sync;

/// One object as the solver (and the reference path tracer) sees it: a triangle mesh in world
/// space with per-triangle materials. An imported file's objects become these through
/// `ToSolver::solver_object` (feature `import`).
#[derive(Clone)]
pub struct SolverObject {
    pub name: String,
    /// Multiresolution objects get a normal set per coarse triangle and one radiosity per
    /// normal; flat objects get one colour per element.
    pub multires: bool,
    /// World-space vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Counter-clockwise (seen from the front) vertex index triples.
    pub triangles: Vec<[u32; 3]>,
    /// Per-triangle diffuse reflectance, each channel in `[0, 1]`.
    pub reflectance: Vec<[f32; 3]>,
    /// Optional per-element reflectance (texture average); overrides `reflectance` where set.
    pub reflectance_fn: Option<Arc<ReflectanceFn>>,
    /// Per-triangle emitted radiance (non-negative); empty means no emission.
    pub emission: Vec<[f32; 3]>,
    /// For multiresolution objects: per coarse triangle its representative normals, the
    /// geometric normal first (chosen by `hce_bake::normal_sets`). Empty means "geometric normal only"
    /// for every triangle.
    pub normal_sets: Vec<Vec<[f32; 3]>>,
    /// The surface that casts this object's shadows, when it is not its own triangles: for a
    /// multiresolution object, its Loop refinement (world space), each triangle with the
    /// coarse triangle it refines. The refined surface is what a renderer draws, and the
    /// control mesh's folds are deeper (a teapot's spout shades the body beside it more than
    /// the refined spout does). Empty: its own triangles.
    pub occluder: Vec<([[f32; 3]; 3], u32)>,
}

impl std::fmt::Debug for SolverObject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolverObject")
            .field("name", &self.name)
            .field("multires", &self.multires)
            .field("vertices", &self.positions.len())
            .field("triangles", &self.triangles.len())
            .field("reflectance_fn", &self.reflectance_fn.is_some())
            .finish()
    }
}

impl SolverObject {
    /// A flat object with one reflectance for every triangle and no emission.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<[f32; 3]>,
        triangles: Vec<[u32; 3]>,
        reflectance: [f32; 3],
    ) -> Self {
        let n = triangles.len();
        SolverObject {
            name: name.into(),
            multires: false,
            positions,
            triangles,
            reflectance: vec![reflectance; n],
            reflectance_fn: None,
            emission: Vec::new(),
            normal_sets: Vec::new(),
            occluder: Vec::new(),
        }
    }

    /// Sets the same emitted radiance on every triangle.
    pub fn with_emission(mut self, emission: [f32; 3]) -> Self {
        self.emission = vec![emission; self.triangles.len()];
        self
    }

    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|v| Vec3::from(self.positions[v as usize]))
    }

    pub fn emission_of(&self, t: usize) -> [f32; 3] {
        self.emission.get(t).copied().unwrap_or([0.0; 3])
    }

    /// The normals the solver stores radiosity for on triangle `t`: the normal set of a
    /// multiresolution object, or the geometric normal alone.
    pub fn normals_of(&self, t: usize) -> Vec<Vec3> {
        if self.multires {
            if let Some(set) = self.normal_sets.get(t) {
                if !set.is_empty() {
                    return set.iter().map(|&n| Vec3::from(n).normalize()).collect();
                }
            }
        }
        let [a, b, c] = self.corners(t);
        vec![(b - a).cross(c - a).normalize()]
    }
}

/// The kind of a punctual light (KHR_lights_punctual), as the importer reads it and the solver
/// takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Emits `intensity` candela in every direction from `position`.
    Point,
    /// As a point light inside a cone around `direction`; angles in radians from the axis,
    /// with glTF's smooth falloff between them.
    Spot {
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
    /// Parallel light travelling along `direction`; `intensity` in lux.
    Directional,
}

/// A punctual light placed in world space: the one light type of the importer, the solver and
/// the reference path tracer. Units are those of KHR_lights_punctual: candela
/// for point and spot lights, lux for directional lights.
#[derive(Clone, Debug, PartialEq)]
pub struct PunctualLight {
    /// The light's name, else its node's, else `light {i}` (its index in the scene's lights).
    pub name: String,
    pub kind: LightKind,
    /// World position (ignored for directional lights).
    pub position: [f32; 3],
    /// World direction the light travels (the node's -Z; spot axis / directional), need not be
    /// unit; unused for point lights.
    pub direction: [f32; 3],
    /// Linear RGB colour multiplying `intensity`.
    pub color: [f32; 3],
    /// Candela (point, spot) or lux (directional).
    pub intensity: f32,
    /// glTF `range`: beyond it the light contributes nothing; `None` is infinite.
    pub range: Option<f32>,
}

/// Everything the solver needs.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub objects: Vec<SolverObject>,
    pub lights: Vec<PunctualLight>,
}

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

impl Scene {
    /// Checks every index, count and value the solver relies on; returns the first problem.
    pub fn validate(&self) -> Result<(), SceneError> {
        let mut any_emitter = false;
        for (oi, o) in self.objects.iter().enumerate() {
            let obj = || format!("object {oi} ('{}')", o.name);
            let bad = |reason: String| SceneError::InvalidObject {
                object: obj(),
                reason,
            };
            if o.positions.iter().any(|p| !finite3(*p)) {
                return Err(bad("a vertex position is not finite".into()));
            }
            if o.reflectance.len() != o.triangles.len() {
                return Err(bad(format!(
                    "{} reflectances for {} triangles (give one per triangle)",
                    o.reflectance.len(),
                    o.triangles.len()
                )));
            }
            if !o.emission.is_empty() && o.emission.len() != o.triangles.len() {
                return Err(bad(format!(
                    "{} emissions for {} triangles (give one per triangle or none)",
                    o.emission.len(),
                    o.triangles.len()
                )));
            }
            if o.multires && !o.normal_sets.is_empty() && o.normal_sets.len() != o.triangles.len() {
                return Err(bad(format!(
                    "{} normal sets for {} triangles (give one per triangle or none)",
                    o.normal_sets.len(),
                    o.triangles.len()
                )));
            }
            for (t, tri) in o.triangles.iter().enumerate() {
                if let Some(&v) = tri.iter().find(|&&v| v as usize >= o.positions.len()) {
                    return Err(bad(format!(
                        "triangle {t} uses vertex {v} but there are {} vertices",
                        o.positions.len()
                    )));
                }
                let [a, b, c] = o.corners(t);
                let area2 = (b - a).cross(c - a).length();
                if !(area2 > 0.0 && area2.is_finite()) {
                    return Err(bad(format!(
                        "triangle {t} is degenerate (zero area); remove it before baking"
                    )));
                }
                let r = o.reflectance[t];
                if !finite3(r) || r.iter().any(|&c| !(0.0..=1.0).contains(&c)) {
                    return Err(bad(format!(
                        "triangle {t} has reflectance {r:?}; each channel must lie in [0, 1]"
                    )));
                }
                let e = o.emission_of(t);
                if !finite3(e) || e.iter().any(|&c| c < 0.0) {
                    return Err(bad(format!(
                        "triangle {t} has emission {e:?}; it must be finite and non-negative"
                    )));
                }
                any_emitter |= e.iter().any(|&c| c > 0.0);
                if o.multires {
                    if let Some(set) = o.normal_sets.get(t) {
                        if set.len() > MAX_NORMALS_PER_TRIANGLE {
                            return Err(bad(format!(
                                "triangle {t} has {} normals; at most {} are supported",
                                set.len(),
                                MAX_NORMALS_PER_TRIANGLE
                            )));
                        }
                        if set
                            .iter()
                            .any(|n| !finite3(*n) || Vec3::from(*n).length_squared() < 1e-12)
                        {
                            return Err(bad(format!(
                                "triangle {t} has a zero or non-finite normal in its set"
                            )));
                        }
                    }
                }
            }
        }
        for (li, l) in self.lights.iter().enumerate() {
            let bad = |reason: &str| SceneError::InvalidLight {
                light: format!("light {li} ('{}')", l.name),
                reason: reason.to_string(),
            };
            if !finite3(l.position) || !finite3(l.color) || !l.intensity.is_finite() {
                return Err(bad("position, colour and intensity must be finite"));
            }
            if l.intensity < 0.0 || l.color.iter().any(|&c| c < 0.0) {
                return Err(bad("intensity and colour must be non-negative"));
            }
            if l.kind != LightKind::Point && Vec3::from(l.direction).length_squared() < 1e-20 {
                return Err(bad(
                    "a spot or directional light needs a non-zero direction",
                ));
            }
            if let Some(r) = l.range {
                if r.is_nan() || r <= 0.0 {
                    return Err(bad("range must be positive when given"));
                }
            }
            if l.intensity > 0.0 && l.color.iter().any(|&c| c > 0.0) {
                any_emitter = true;
            }
        }
        if !any_emitter {
            return Err(SceneError::NoLight);
        }
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> SolverObject {
        SolverObject::new(
            "t",
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
            [0.5; 3],
        )
        .with_emission([1.0; 3])
    }

    fn err(scene: Scene) -> String {
        scene.validate().unwrap_err().to_string()
    }

    #[test]
    fn bad_scenes_get_errors_naming_object_and_triangle() {
        let mut o = tri();
        o.triangles[0] = [0, 1, 7];
        let e = err(Scene {
            objects: vec![o],
            lights: vec![],
        });
        assert!(
            e.contains("'t'") && e.contains("triangle 0") && e.contains("vertex 7"),
            "{e}"
        );
        let mut o = tri();
        o.reflectance[0] = [1.5, 0.0, 0.0];
        assert!(err(Scene {
            objects: vec![o],
            lights: vec![]
        })
        .contains("[0, 1]"));
        let mut o = tri();
        o.positions[2] = [2.0, 0.0, 0.0];
        assert!(err(Scene {
            objects: vec![o],
            lights: vec![]
        })
        .contains("degenerate"));
        let mut o = tri();
        o.emission.clear();
        let mut s = Scene {
            objects: vec![o],
            lights: vec![],
        };
        assert!(err(s.clone()).contains("no light source"));
        s.lights.push(PunctualLight {
            name: "sun".into(),
            kind: LightKind::Directional,
            position: [0.0; 3],
            direction: [0.0; 3],
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
        });
        assert!(err(s.clone()).contains("non-zero direction"));
        s.lights[0].direction = [0.0, 0.0, -1.0];
        assert!(s.validate().is_ok());
    }
}
