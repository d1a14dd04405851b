//! The output buffers of a refinement, written once for both kernels (`flat.rs`,
//! `loop_kernel.rs`): what each buffer holds and its bytes per vertex or fine triangle, the
//! counts checked to fit 32-bit indices, allocation checked against the device's limits, reuse
//! while the buffers are large enough (so that a viewer can refine every frame without
//! reallocating), and read-back.

use super::util::{check_size, read_back, storage_output};
use super::{GpuContext, GpuError};
use hce_geometry::flat::RefinedMesh;

/// Bytes per vertex of a position or normal (`x, y, z` f32) and of a colour (linear RGBA f32).
const POSITION_BYTES: u64 = 12;
const NORMAL_BYTES: u64 = 12;
const COLOUR_BYTES: u64 = 16;
/// Bytes per fine triangle of its indices (`u32` ×3) and of its face colour (RGB and area).
const INDEX_BYTES: u64 = 12;
const FACE_BYTES: u64 = 16;

/// What one refinement writes: its vertex and fine-triangle counts (checked to fit 32-bit
/// indices) and whether it writes vertex normals (the Loop kernel does).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct OutputShape {
    pub(super) vertices: u32,
    pub(super) triangles: u32,
    pub(super) normals: bool,
}

impl OutputShape {
    /// The shape of `vertices` and `triangles`, or an error when an index or the index count
    /// would not fit 32 bits.
    pub(super) fn new(vertices: u64, triangles: u64, normals: bool) -> Result<Self, GpuError> {
        let too_large = |what, needed| GpuError::TooLarge {
            what,
            needed,
            limit: u64::from(u32::MAX),
        };
        if triangles > u64::from(u32::MAX / 3) {
            return Err(too_large(
                "refined index count",
                triangles.saturating_mul(3),
            ));
        }
        Ok(Self {
            vertices: u32::try_from(vertices)
                .map_err(|_| too_large("refined vertex count", vertices))?,
            triangles: triangles as u32,
            normals,
        })
    }

    fn bytes(&self) -> [u64; 5] {
        let (v, f) = (u64::from(self.vertices), u64::from(self.triangles));
        [
            v * POSITION_BYTES,
            if self.normals { v * NORMAL_BYTES } else { 0 },
            v * COLOUR_BYTES,
            f * INDEX_BYTES,
            f * FACE_BYTES,
        ]
    }
}

/// Output buffers of a refinement: drawable as they are (`positions`, `normals` and `colours`
/// as vertex buffers, `indices` as an index buffer), in the numbering of the kernel's CPU twin.
pub struct RefinedOutput {
    pub level: u32,
    pub vertex_count: u32,
    pub triangle_count: u32,
    /// `x, y, z` f32 per vertex (stride 12).
    pub positions: wgpu::Buffer,
    /// Unit `x, y, z` f32 per vertex (stride 12), as
    /// [`hce_geometry::subdivide::Refined::normals`]: the Loop kernel's; `None` for the flat
    /// kernel's.
    pub normals: Option<wgpu::Buffer>,
    /// Linear `r, g, b, 1` f32 per vertex (stride 16).
    pub colours: wgpu::Buffer,
    /// `u32` ×3 per fine triangle.
    pub indices: wgpu::Buffer,
    /// Linear `r, g, b`, area per fine triangle.
    pub faces: wgpu::Buffer,
    /// The patches of the Loop scratch kernel's coarse triangles in flight (kernel-private).
    pub(super) scratch: Option<wgpu::Buffer>,
}

impl RefinedOutput {
    /// `out` ready for a refinement to `level` of `shape`: reused when its buffers are large
    /// enough (and it has normals exactly where `shape` does), else allocated anew and checked
    /// against the device's limits; its level and counts set to the refinement's.
    pub(super) fn prepare<'a>(
        ctx: &GpuContext,
        out: &'a mut Option<Self>,
        level: u32,
        shape: OutputShape,
    ) -> Result<&'a mut Self, GpuError> {
        if !out.as_ref().is_some_and(|o| o.fits(shape)) {
            *out = Some(Self::allocate(ctx, shape)?);
        }
        let o = out.as_mut().expect("allocated above");
        o.level = level;
        o.vertex_count = shape.vertices;
        o.triangle_count = shape.triangles;
        Ok(o)
    }

    fn fits(&self, shape: OutputShape) -> bool {
        let [p, n, c, i, f] = shape.bytes();
        self.normals.is_some() == shape.normals
            && self.positions.size() >= p
            && self.normals.as_ref().is_none_or(|b| b.size() >= n)
            && self.colours.size() >= c
            && self.indices.size() >= i
            && self.faces.size() >= f
    }

    fn allocate(ctx: &GpuContext, shape: OutputShape) -> Result<Self, GpuError> {
        let [p, n, c, i, f] = shape.bytes();
        // Written by a kernel, or copied in from the pooled outputs of a batch (batch.rs).
        let copied = wgpu::BufferUsages::COPY_DST;
        let vertex = wgpu::BufferUsages::VERTEX | copied;
        let buffer = |what, bytes, usage| -> Result<wgpu::Buffer, GpuError> {
            Ok(storage_output(
                ctx,
                what,
                check_size(ctx, what, bytes)?,
                usage,
            ))
        };
        Ok(Self {
            level: 0,
            vertex_count: shape.vertices,
            triangle_count: shape.triangles,
            positions: buffer("refined positions", p, vertex)?,
            normals: if shape.normals {
                Some(buffer("refined normals", n, vertex)?)
            } else {
                None
            },
            colours: buffer("refined colours", c, vertex)?,
            indices: buffer("refined indices", i, wgpu::BufferUsages::INDEX | copied)?,
            faces: buffer("refined faces", f, copied)?,
            scratch: None,
        })
    }

    /// Copies the refined mesh (without normals) back to the CPU.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<RefinedMesh, GpuError> {
        let v = self.vertex_count as usize;
        let f = self.triangle_count as usize;
        Ok(RefinedMesh {
            level: self.level,
            positions: read_back(ctx, &self.positions, 3 * v)?,
            colours: read_back(ctx, &self.colours, 4 * v)?,
            indices: read_back(ctx, &self.indices, 3 * f)?,
            face_colours: read_back(ctx, &self.faces, 4 * f)?,
        })
    }

    /// Copies the vertex normals back to the CPU (`x, y, z` per vertex); an error for the flat
    /// kernel's output, which has none.
    pub fn read_back_normals(&self, ctx: &GpuContext) -> Result<Vec<f32>, GpuError> {
        let normals = self.normals.as_ref().ok_or_else(|| {
            GpuError::InvalidParams(
                "a flat refinement has no vertex normals (the Loop kernel writes them)".into(),
            )
        })?;
        read_back(ctx, normals, 3 * self.vertex_count as usize)
    }

    /// Bytes the kernel writes to the outputs (positions, normals, colours, indices, face
    /// colours); the scratch traffic of the Loop patches is not counted.
    #[cfg_attr(not(feature = "bench"), allow(dead_code))]
    pub(crate) fn bytes_written(&self) -> u64 {
        OutputShape {
            vertices: self.vertex_count,
            triangles: self.triangle_count,
            normals: self.normals.is_some(),
        }
        .bytes()
        .iter()
        .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_must_fit_32_bit_indices() {
        let shape = OutputShape::new(10, 4, true).unwrap();
        assert_eq!(shape.bytes(), [120, 120, 160, 48, 64]);
        assert_eq!(OutputShape::new(10, 4, false).unwrap().bytes()[1], 0);
        let max = u64::from(u32::MAX);
        assert!(OutputShape::new(max, max / 3, false).is_ok());
        assert!(matches!(
            OutputShape::new(max + 1, 1, false),
            Err(GpuError::TooLarge {
                what: "refined vertex count",
                ..
            })
        ));
        assert!(matches!(
            OutputShape::new(1, max / 3 + 1, false),
            Err(GpuError::TooLarge {
                what: "refined index count",
                ..
            })
        ));
    }
}
