//! Synthetic inputs for the kernels' tests and benchmarks (features `testing` and `bench`): a
//! deterministic generator, objects with random HCE trees on any mesh, and two small meshes.

/// A small deterministic generator (SplitMix64) for test and benchmark inputs, so the crate
/// needs no random-number dependency and every run sees the same data.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % u64::from(n.max(1))) as u32
    }

    pub fn unit_vector(&mut self) -> [f32; 3] {
        loop {
            let v = [
                2.0 * self.unit() - 1.0,
                2.0 * self.unit() - 1.0,
                2.0 * self.unit() - 1.0,
            ];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.1 && l <= 1.0 {
                return v.map(|x| x / l);
            }
        }
    }
}

/// Shape of the random HCE data [`random_object`] attaches to a mesh.
#[derive(Clone, Copy, Debug)]
pub struct RandomTrees {
    /// Deepest tree level, at most [`hce_format::MAX_TREE_DEPTH`] (deeper is taken as that).
    /// Default 4.
    pub max_depth: u32,
    /// Probability that a node above `max_depth` is subdivided. Default 0.6.
    pub split_probability: f32,
    /// Extra representative normals per triangle: `0 ..= max_extra_normals`. Default 4.
    pub max_extra_normals: u32,
}

impl Default for RandomTrees {
    fn default() -> Self {
        Self {
            max_depth: 4,
            split_probability: 0.6,
            max_extra_normals: 4,
        }
    }
}

/// An object over `positions`/`triangles` (edge ids filled in, other adjacency tables left
/// empty) with random breadth-first trees, normal sets and colours: valid input for the
/// decoding and flat kernels, built entirely in code.
pub fn random_object(
    name: &str,
    positions: Vec<f32>,
    triangles: Vec<u32>,
    shape: RandomTrees,
    seed: u64,
) -> hce_format::Object {
    use hce_format::{rgb9e5, ControlMesh, Object, ObjectKind, TriangleRecord};
    let mut rng = SplitMix(seed);
    let edges = hce_geometry::flat::edge_ids(&triangles);
    let mesh = ControlMesh {
        positions,
        triangles,
        edges,
        ..Default::default()
    };
    let max_depth = shape.max_depth.min(hce_format::MAX_TREE_DEPTH);
    let mut records = Vec::new();
    let mut normals = Vec::new();
    let mut bits = hce_format::BitWriter::new();
    let mut colours = Vec::new();
    for t in 0..mesh.triangle_count() {
        let p = mesh.triangle(t).map(|v| mesh.position(v));
        let (geometric, _) = hce_geometry::flat::normal_and_area(p);
        let normal_count = 1 + rng.below(shape.max_extra_normals + 1);
        let normal_start = normals.len() as u32;
        normals.push(geometric);
        for _ in 1..normal_count {
            normals.push(rng.unit_vector());
        }
        // Breadth-first: a node's flag, then its children queued behind the current level.
        let mut queue = std::collections::VecDeque::from([0u32]);
        let mut flags = Vec::new();
        while let Some(depth) = queue.pop_front() {
            let split = depth < max_depth && rng.unit() < shape.split_probability;
            flags.push(split);
            if split {
                queue.extend([depth + 1; 4]);
            }
        }
        // Complete by construction and no deeper than the format allows.
        let bits_start = bits
            .push_tree(&flags)
            .expect("a breadth-first tree within MAX_TREE_DEPTH");
        let record = TriangleRecord {
            bits_start: bits_start as u32,
            colour_start: colours.len() as u32,
            normal_start,
            normal_count,
        };
        for _ in 0..flags.len() as u32 * normal_count {
            let scale = 4.0 * rng.unit();
            colours.push(rgb9e5::encode([
                scale * rng.unit(),
                scale * rng.unit(),
                scale * rng.unit(),
            ]));
        }
        records.push(record);
    }
    let (bits, bit_len) = bits.finish();
    Object {
        name: name.to_string(),
        kind: ObjectKind::Flat,
        geometry_hash: 0,
        mesh,
        triangles: records,
        normals,
        bits,
        bit_len,
        colours,
        corner_colours: Vec::new(),
    }
}

/// Test meshes: a closed octahedron and an open 3×2 grid (boundary edges and corners).
pub fn octahedron() -> (Vec<f32>, Vec<u32>) {
    let positions = vec![
        1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0,
    ];
    let triangles = vec![
        0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
    ];
    (positions, triangles)
}

pub fn grid(nx: u32, ny: u32) -> (Vec<f32>, Vec<u32>) {
    let mut positions = Vec::new();
    for y in 0..=ny {
        for x in 0..=nx {
            // A gentle bump so fine normals differ from triangle to triangle.
            let z = 0.3 * ((x as f32) * 0.9).sin() * ((y as f32) * 1.3).cos();
            positions.extend([x as f32, y as f32, z]);
        }
    }
    let mut triangles = Vec::new();
    let id = |x: u32, y: u32| y * (nx + 1) + x;
    for y in 0..ny {
        for x in 0..nx {
            triangles.extend([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
            triangles.extend([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
        }
    }
    (positions, triangles)
}

/// A scene of `count` small flat objects, as architecture and props give: bumpy grids of 2×2
/// to 5×5 quads (8 to 50 triangles) and octahedra (every third object) side by side, each with
/// random trees of depth 1 to 3 (so their levels differ), one instance each, in a `.hce`
/// container loaded from memory. The same `seed` gives the same scene.
pub fn small_flat_scene(count: usize, seed: u64) -> Result<crate::asset::Asset, super::GpuError> {
    small_scene(count, seed, hce_format::ObjectKind::Flat)
}

/// [`small_flat_scene`] with objects of `kind`: multiresolution objects have up to four
/// representative normals per triangle besides the geometric one.
pub fn small_scene(
    count: usize,
    seed: u64,
    kind: hce_format::ObjectKind,
) -> Result<crate::asset::Asset, super::GpuError> {
    use crate::asset::{Asset, AssetFormat, OpenOptions};
    let mut rng = SplitMix(seed);
    let objects = (0..count)
        .map(|i| {
            // Every third a closed octahedron, whose every edge folds (its vertices split,
            // SPEC.md F.5); the others open bumpy grids.
            let (nx, ny) = (2 + rng.below(4), 2 + rng.below(4));
            let (mut positions, triangles) = if i % 3 == 2 {
                octahedron()
            } else {
                grid(nx, ny)
            };
            // Side by side on a square plot, one unit apart.
            let side = (count as f32).sqrt().ceil() as usize;
            let (ox, oy) = ((i % side) as f32 * 6.0, (i / side) as f32 * 6.0);
            for p in positions.chunks_exact_mut(3) {
                p[0] += ox;
                p[1] += oy;
            }
            // Flat objects have one normal per triangle (SPEC.md).
            let shape = RandomTrees {
                max_depth: 1 + rng.below(3),
                max_extra_normals: match kind {
                    hce_format::ObjectKind::Flat => 0,
                    hce_format::ObjectKind::Multiresolution => 4,
                },
                ..RandomTrees::default()
            };
            // The container carries the full control mesh (SPEC.md A.5), flat objects too.
            let mesh = hce_geometry::topology::build_control_mesh(
                &positions
                    .chunks_exact(3)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect::<Vec<_>>(),
                &triangles
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect::<Vec<_>>(),
                None,
                &Default::default(),
            )
            .map_err(|e| super::GpuError::InvalidParams(format!("a generated scene: {e}")))?
            .mesh;
            let mut object = random_object(
                &format!("prop {i}"),
                mesh.positions.clone(),
                mesh.triangles.clone(),
                shape,
                rng.next_u64(),
            );
            object.mesh = mesh;
            object.kind = kind;
            object.geometry_hash = hce_format::geometry_hash(
                (0..object.mesh.triangle_count())
                    .flat_map(|t| object.mesh.triangle(t))
                    .map(|v| object.mesh.position(v)),
            );
            Ok(object)
        })
        .collect::<Result<Vec<_>, super::GpuError>>()?;
    let container = hce_format::Container {
        metadata: hce_format::Metadata {
            generator: "hce-runtime small_scene".into(),
            ..Default::default()
        },
        objects,
    };
    let bytes = hce_format::write(&container)
        .map_err(|e| super::GpuError::InvalidParams(format!("a generated scene: {e}")))?;
    Asset::from_bytes(
        std::path::Path::new("small scene.hce"),
        AssetFormat::Hce,
        &bytes,
        |_| Err("a container has no external buffers".into()),
        &OpenOptions::default(),
    )
    .map_err(|e| super::GpuError::InvalidParams(format!("a generated scene: {e}")))
}
