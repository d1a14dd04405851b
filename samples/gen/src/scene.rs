//! The scene model the generators fill and the GLB writer serialises: named objects made of
//! primitives with diffuse or emissive materials.

use glam::DVec3;

use crate::mesh::Mesh;

/// A diffuse material, optionally emissive.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse reflectance, linear RGB in `[0, 1]`.
    pub base_color: [f64; 3],
    /// Emission, linear RGB; components above 1 are written as `emissiveFactor` normalised to
    /// a maximum of 1 times `KHR_materials_emissive_strength`.
    pub emission: [f64; 3],
}

impl Material {
    /// A purely diffuse material.
    pub fn diffuse(name: &str, base_color: [f64; 3]) -> Self {
        Self {
            name: name.to_string(),
            base_color,
            emission: [0.0; 3],
        }
    }

    /// An emitter (an area light); its reflectance is that of a white diffuser.
    pub fn emitter(name: &str, emission: [f64; 3]) -> Self {
        Self {
            name: name.to_string(),
            base_color: [0.78; 3],
            emission,
        }
    }
}

/// Triangles sharing one material.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    pub mesh: Mesh,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

/// A named node with its own mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub name: String,
    /// Node translation in metres; the mesh is in the node's frame.
    pub translation: DVec3,
    pub primitives: Vec<Primitive>,
    /// Written as node extras `{"hce": {"multires": true}}`, which `hce bake` reads as "Loop
    /// subdivide this object at render time".
    pub multires: bool,
}

impl Object {
    /// An object of one primitive at the origin.
    pub fn new(name: &str, mesh: Mesh, material: usize) -> Self {
        Self {
            name: name.to_string(),
            translation: DVec3::ZERO,
            primitives: vec![Primitive { mesh, material }],
            multires: false,
        }
    }

    /// Sets the translation.
    pub fn at(mut self, translation: DVec3) -> Self {
        self.translation = translation;
        self
    }

    /// Flags the object multiresolution.
    pub fn multires(mut self) -> Self {
        self.multires = true;
        self
    }

    /// Triangles over all primitives.
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().map(|p| p.mesh.triangles.len()).sum()
    }
}

/// A suggested viewpoint, written as a glTF perspective camera node so that viewers and
/// `hce render` can show the scene as intended without being told where to look.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    pub eye: DVec3,
    pub target: DVec3,
    /// Vertical field of view in degrees.
    pub yfov_degrees: f64,
}

/// A whole sample scene, Y up, in metres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    pub name: String,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub camera: Option<Camera>,
}

impl Scene {
    /// Adds a material and returns its index.
    pub fn material(&mut self, material: Material) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Triangles over all objects.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(Object::triangle_count).sum()
    }

    /// The object called `name`, if any.
    pub fn object(&self, name: &str) -> Option<&Object> {
        self.objects.iter().find(|o| o.name == name)
    }
}
