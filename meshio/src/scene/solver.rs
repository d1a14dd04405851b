//! From an imported scene to the solver's world-space [`Scene`].
//!
//! The importer keeps everything the output writer needs (glTF indices, object-space data); the
//! solver wants world-space triangles with a reflectance and an emission per triangle. Textured
//! materials are averaged per element through the scene's reflectance hook, so an element gets
//! the mean of the texture over exactly the part of the triangle it covers.

use std::sync::Arc;

use super::{ImportedObject, ImportedScene};
use crate::solver_scene::{self as scene, Scene};

/// The solver's view of an imported scene.
pub trait ToSolver {
    /// The solver's view of object `index`: world-space corners (winding restored where the node
    /// transform mirrors), per-triangle reflectance and emission from its material, no normal
    /// sets yet.
    fn solver_object(&self, index: usize) -> scene::SolverObject;

    /// The whole scene as the solver takes it: every object (see
    /// [`ToSolver::solver_object`]) and every punctual light.
    fn solver_scene(&self) -> Scene;
}

impl ToSolver for ImportedScene {
    fn solver_object(&self, index: usize) -> scene::SolverObject {
        let o: &ImportedObject = &self.objects[index];
        let material = self.material_of(o);
        let flip = o.mirrored();
        let triangles: Vec<[u32; 3]> = o
            .indices
            .chunks_exact(3)
            .map(|c| {
                if flip {
                    [c[0], c[2], c[1]]
                } else {
                    [c[0], c[1], c[2]]
                }
            })
            .collect();
        let n = triangles.len();
        let reflectance = (0..n)
            .map(|t| material.reflectance_over(o.triangle_uvs(t)))
            .collect();
        let reflectance_fn: Option<Arc<scene::ReflectanceFn>> =
            match (&material.base_color_texture, &o.uv0) {
                (Some(texture), Some(_)) => {
                    let texture = Arc::clone(texture);
                    let factor = material.base_color;
                    let uvs: Vec<[[f32; 2]; 3]> = (0..n)
                        .map(|t| {
                            let uv = o.triangle_uvs(t).unwrap_or_default();
                            if flip {
                                [uv[0], uv[2], uv[1]]
                            } else {
                                uv
                            }
                        })
                        .collect();
                    Some(Arc::new(move |t: usize, bary: [[f32; 3]; 3]| {
                        let uv = uvs[t];
                        let at = |b: [f32; 3]| {
                            [0, 1].map(|k| b[0] * uv[0][k] + b[1] * uv[1][k] + b[2] * uv[2][k])
                        };
                        let avg = texture.average_over_triangle(bary.map(at));
                        [0, 1, 2].map(|c| factor[c] * avg[c])
                    }))
                }
                _ => None,
            };
        let emission = if material.is_emissive() {
            vec![material.emission; n]
        } else {
            Vec::new()
        };
        scene::SolverObject {
            name: o.name.clone(),
            multires: o.multires,
            positions: o.world_positions.clone(),
            triangles,
            reflectance,
            reflectance_fn,
            emission,
            normal_sets: Vec::new(),
            occluder: Vec::new(),
        }
    }

    fn solver_scene(&self) -> Scene {
        Scene {
            objects: (0..self.objects.len())
                .map(|i| self.solver_object(i))
                .collect(),
            lights: self.lights.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{import_scene, ImportOptions, ToSolver};
    use std::path::Path;

    #[test]
    fn cornell_box_converts_with_its_emitter_and_reflectances() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
        let imported = import_scene(&path, &ImportOptions::default()).unwrap();
        let scene = imported.solver_scene();
        assert_eq!(scene.triangle_count(), 32);
        scene.validate().unwrap();
        let light = scene
            .objects
            .iter()
            .find(|o| !o.emission.is_empty())
            .expect("the Cornell light is emissive");
        assert_eq!(light.emission[0], [17.0, 12.0, 4.0]);
        let red = scene
            .objects
            .iter()
            .find(|o| {
                o.reflectance
                    .first()
                    .is_some_and(|r| r[0] > 0.5 && r[1] < 0.1)
            })
            .expect("a red wall");
        assert!(
            (red.reflectance[0][0] - 0.63).abs() < 1e-3,
            "{:?}",
            red.reflectance[0]
        );
    }
}
