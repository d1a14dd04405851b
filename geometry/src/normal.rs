//! Triangle normals: the area-weighted face normal that vertex normals sum, and the unit normal
//! glTF output needs. Below refinement and the split, which both sum face normals.

/// Area-weighted (unnormalised) normal of a triangle.
pub fn face_normal(p: [[f32; 3]; 3]) -> [f32; 3] {
    let u = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
    let w = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
    [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ]
}

/// `n` normalised, or +Y when it has no direction (glTF requires unit normals).
pub fn unit_or_up(n: [f32; 3]) -> [f32; 3] {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        n.map(|x| x / len)
    } else {
        [0.0, 1.0, 0.0]
    }
}
