//! What a bake hands back: per coarse triangle its element tree and the radiance drawn for each
//! node and normal, and figures for the summary.

use glam::Vec3;

use super::context::Ctx;
use super::tree::Tree;

/// The solution for one coarse triangle: its element tree in breadth-first order.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleSolution {
    /// Normals colours are stored for, the geometric normal first.
    pub normals: Vec<[f32; 3]>,
    /// `(level, path)` of every node, breadth-first (children Top, Left, Center, Right).
    pub nodes: Vec<(u32, u32)>,
    /// Per node: whether it is split into four children.
    pub subdivided: Vec<bool>,
    /// Outgoing radiance per node and normal, node-major: `colours[k * normals.len() + j]`.
    /// Interior nodes hold the area-weighted average of their children.
    pub colours: Vec<[f32; 3]>,
    /// Outgoing radiance at each node's corners 0, 1, 2 (SPEC.md A.10) per normal, three for
    /// each colour: `corner_colours[(k * normals.len() + j) * 3 + c]`.
    pub corner_colours: Vec<[f32; 3]>,
}

/// The solution for one scene object.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectSolution {
    pub name: String,
    pub multires: bool,
    pub triangles: Vec<TriangleSolution>,
}

/// Figures for the summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeStats {
    pub coarse_triangles: usize,
    pub elements: usize,
    pub links: usize,
    /// Gather iterations summed over all solves.
    pub iterations: u32,
    /// Relative change at the end of the last solve.
    pub final_change: f32,
    /// Wall-clock seconds per phase: (name, seconds).
    pub phase_seconds: Vec<(String, f64)>,
}

/// What [`bake`](super::bake) returns.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeResult {
    pub objects: Vec<ObjectSolution>,
    pub stats: BakeStats,
}

impl Ctx<'_> {
    /// What the file stores for root `r`'s tree `t` (SPEC.md, A.9): per node and normal the
    /// radiance of the part of the element that can be seen. A leaf partly shut in (under a
    /// block on the floor, inside a spout where it meets a body: [`Ctx::open_fraction`]) holds
    /// the area average of the whole element in the solver, its shut part dark; the viewer
    /// draws the leaf where it is open, so it gets the open part's radiance
    /// ([`Ctx::source_radiance`], as it sends light). Interior nodes average their children.
    /// Drawn with the shut part counted, the teapot's body beside its spout came out 2% dark
    /// over the whole object (8.1% error; now 6.1%).
    pub(super) fn shown(&self, r: u32, t: &Tree) -> Vec<Vec3> {
        let nn = self.nn(r);
        let le = self.roots[r as usize].emission;
        let mut l = t.l.clone();
        // Breadth-first: children come after their parent, so reverse is bottom-up.
        for i in (0..t.keys.len()).rev() {
            let c = t.child[i];
            if c == u32::MAX {
                let o = t.open[i];
                if o > 0.0 && o < 1.0 {
                    for j in 0..nn {
                        l[i * nn + j] = le + (t.l[i * nn + j] - le) / o;
                    }
                }
            } else {
                for j in 0..nn {
                    let sum: Vec3 = (c as usize..c as usize + 4).map(|ch| l[ch * nn + j]).sum();
                    l[i * nn + j] = sum * 0.25;
                }
            }
        }
        l
    }
}
