//! A root's refinement in parts that run in parallel: the walk of
//! [`refine`](super::refine) takes a bounded number of pairs from its stack, and the pairs it
//! leaves go on in parallel, the same way. Where the parts fall depends on the step count
//! alone, so the result does not depend on the thread count.

use rayon::prelude::*;

use super::links::RawLink;

/// Pairs one part of a root's refinement takes before it hands the pairs left on its stack
/// to parts that run in parallel ([`refine_in_parallel`]).
pub(super) const REFINE_STEPS: usize = 16384;

/// Refines `stack` (of the walk's pairs, `P`) with `run`
/// ([`Ctx::refine_root`](super::context::Ctx::refine_root)'s depth-first walk of at most
/// [`REFINE_STEPS`] pairs), then each pair it left in parallel, the same way; the links in
/// the order the walk would have popped them, their coefficients' offsets moved to match.
/// Where the parts fall depends on the step count alone, so the links come out the same for
/// any number of threads. A room of a few large coarse triangles was refined one triangle per
/// thread, and the floor's alone took most of the time (the Cornell box: 1.2 cores busy of 2).
#[allow(clippy::type_complexity)]
pub(super) fn refine_in_parallel<P: Send>(
    run: &(dyn Fn(Vec<P>) -> (Vec<RawLink>, Vec<f32>, Vec<P>) + Sync),
    stack: Vec<P>,
) -> (Vec<RawLink>, Vec<f32>) {
    // The parts' results in order, joined once at the end.
    #[allow(clippy::type_complexity)]
    fn parts<P: Send>(
        run: &(dyn Fn(Vec<P>) -> (Vec<RawLink>, Vec<f32>, Vec<P>) + Sync),
        stack: Vec<P>,
    ) -> Vec<(Vec<RawLink>, Vec<f32>)> {
        let (links, ks, left) = run(stack);
        let mut out = vec![(links, ks)];
        if !left.is_empty() {
            let rest: Vec<Vec<(Vec<RawLink>, Vec<f32>)>> = left
                .into_par_iter()
                .rev()
                .map(|p| parts(run, vec![p]))
                .collect();
            out.extend(rest.into_iter().flatten());
        }
        out
    }
    let mut all = parts(run, stack);
    if all.len() == 1 {
        return all.pop().unwrap_or_default();
    }
    let (mut links, mut ks) = (
        Vec::with_capacity(all.iter().map(|p| p.0.len()).sum()),
        Vec::with_capacity(all.iter().map(|p| p.1.len()).sum()),
    );
    for (part_links, part_ks) in all {
        let offset = ks.len() as u32;
        links.extend(part_links.into_iter().map(|mut l| {
            l.k_start += offset;
            l
        }));
        ks.extend(part_ks);
    }
    (links, ks)
}
