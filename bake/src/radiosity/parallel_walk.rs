//! A root's refinement in parts that run in parallel: the walk of
//! [`refine`](super::refine) takes a bounded number of pairs from its stack, and the pairs it
//! leaves go on in parallel, the same way. Where the parts fall depends on the step count
//! alone, so the result does not depend on the thread count.

use rayon::prelude::*;

use super::links::RawLinks;

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
pub(super) fn refine_in_parallel<P: Send>(
    run: &(dyn Fn(Vec<P>) -> (RawLinks, Vec<P>) + Sync),
    stack: Vec<P>,
) -> RawLinks {
    // The parts' results in order, joined once at the end.
    fn parts<P: Send>(
        run: &(dyn Fn(Vec<P>) -> (RawLinks, Vec<P>) + Sync),
        stack: Vec<P>,
    ) -> Vec<RawLinks> {
        let (links, left) = run(stack);
        let mut out = vec![links];
        if !left.is_empty() {
            let rest: Vec<Vec<RawLinks>> = left
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
    let mut links = RawLinks::with_capacity(
        all.iter().map(|p| p.links.len()).sum(),
        all.iter().map(|p| p.k.len()).sum(),
    );
    for part in all {
        links.append(part);
    }
    links
}
