//! What the mesh readers give: the triangles of a mesh file, placed in world space. Its own
//! module so that the OBJ readers (`import`'s, through tobj, and `obj_fast`'s) and the glTF
//! reader share it without naming each other.

/// The triangles of a mesh file, placed in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Triangles {
    pub positions: Vec<[f32; 3]>,
    /// Counter-clockwise triangles indexing `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// One normal per triangle corner (`3 * t + c`), when every triangle has them.
    pub corner_normals: Option<Vec<[f32; 3]>>,
    /// One linear RGB colour per vertex, `None` for vertices of a primitive or OBJ object
    /// without colours; `None` as a whole when no vertex has one.
    pub colours: Option<Vec<Option<[f32; 3]>>>,
}
