//! A refinement as a list of steps whose items can be dispatched in pieces: the one way the Loop
//! and flat kernels record their work, whether all of it at once ([`LoopKernel::refine_into`],
//! [`FlatKernel::refine_into`]) or a piece per frame ([`GpuScene::refine_batch`]). The one
//! exception: [`GpuScene::refine_batch`] records the whole refinements of many small
//! objects together (`batch.rs`), with the parameters their jobs hold, and marks the jobs
//! recorded.
//!
//! Each step of a kernel is a pure gather or an owned write over its items (coarse triangles,
//! fine triangles or output vertices), and reads only what earlier steps wrote. Dispatching a
//! step's items in ranges (`range_first`, `range_end` in the kernel's `Params`), the steps in
//! order, therefore writes the same bytes as dispatching each step whole: only the order in
//! which the invocations of one step run changes, and the output never depended on it.
//!
//! Work is counted in fine triangles: every step of a refinement to `F` fine triangles is worth
//! `F`, so a piece of `w` covers `w / F` of the step's items (the coarse triangles of `w / 4^L`
//! of them in the Loop kernel's first step), and a viewer can spread `3 F` over frames at a rate
//! it measures.
//!
//! [`LoopKernel::refine_into`]: super::LoopKernel::refine_into
//! [`FlatKernel::refine_into`]: super::FlatKernel::refine_into
//! [`GpuScene::refine_batch`]: super::GpuScene::refine_batch

use super::bindings::{
    HCE_LIGHT, OUT_COLOURS, OUT_FACES, OUT_INDICES, OUT_NORMALS, OUT_POSITIONS, TOPO,
};
use super::outputs::RefinedOutput;
use super::util::{
    bind_buffers_at, dispatch_size, uniform_words, LightingBuffers, PassTimer, WORKGROUP,
};
use super::{GpuContext, GpuError};

/// How the invocations of a dispatch cover a range of `n` items.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lanes {
    /// One invocation per item.
    PerItem,
    /// At most this many invocations, each striding over the items (the Loop kernel's scratch
    /// slots).
    Slots(u32),
    /// One workgroup of [`WORKGROUP`] invocations per this many items (the Loop kernel's
    /// workgroup patches).
    Groups(u32),
}

impl Lanes {
    fn threads(self, n: u64) -> u64 {
        match self {
            Self::PerItem => n,
            Self::Slots(slots) => n.min(u64::from(slots)).max(1),
            Self::Groups(per) => n.div_ceil(u64::from(per.max(1))) * u64::from(WORKGROUP),
        }
    }
}

/// One step of a refinement: a pipeline, its bindings other than the parameters (binding 0),
/// and its items.
pub(super) struct Step {
    pub(super) pipeline: wgpu::ComputePipeline,
    pub(super) bindings: Vec<(u32, wgpu::Buffer)>,
    pub(super) items: u64,
    pub(super) lanes: Lanes,
}

impl Step {
    /// The faces step both kernels share: a gather over fine triangles that reads the refined
    /// positions and the lighting tree, and writes each fine triangle's indices and face colour.
    pub(super) fn faces(
        pipeline: &wgpu::ComputePipeline,
        topo: &wgpu::Buffer,
        out: &RefinedOutput,
        lighting: &LightingBuffers,
    ) -> Self {
        let mut bindings = vec![
            (TOPO, topo.clone()),
            (OUT_POSITIONS, out.positions.clone()),
            (OUT_INDICES, out.indices.clone()),
            (OUT_FACES, out.faces.clone()),
        ];
        bindings.extend(lighting.tree_bindings());
        Self {
            pipeline: pipeline.clone(),
            bindings,
            items: u64::from(out.triangle_count),
            lanes: Lanes::PerItem,
        }
    }

    /// The colours step both kernels end with: a gather over output vertices from the face
    /// colours and the lighting table. A Loop output's vertices also read their positions and
    /// normals (the smooth reconstruction at a curved vertex); a flat output has no normals.
    pub(super) fn colours(
        pipeline: &wgpu::ComputePipeline,
        topo: &wgpu::Buffer,
        out: &RefinedOutput,
        lighting: &LightingBuffers,
    ) -> Self {
        let mut bindings = vec![(TOPO, topo.clone())];
        if let Some(normals) = &out.normals {
            bindings.push((OUT_POSITIONS, out.positions.clone()));
            bindings.push((OUT_NORMALS, normals.clone()));
        }
        bindings.extend([
            (OUT_FACES, out.faces.clone()),
            (OUT_COLOURS, out.colours.clone()),
            (HCE_LIGHT, lighting.light.clone()),
        ]);
        Self {
            pipeline: pipeline.clone(),
            bindings,
            items: u64::from(out.vertex_count),
            lanes: Lanes::PerItem,
        }
    }
}

/// What one call of [`RefineJob::encode`] recorded.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Encoded {
    /// Work recorded, in fine triangles (see the module documentation).
    pub work: u64,
    /// The timer passes it wrote timestamps to (none without timing).
    pub passes: std::ops::Range<u32>,
}

/// A refinement under way: its steps and how far their dispatches have been recorded. The
/// output buffers it writes belong to whoever started it ([`LoopKernel::begin`],
/// [`FlatKernel::begin`]); they hold the refined mesh once every piece has been recorded and
/// submitted.
///
/// [`LoopKernel::begin`]: super::LoopKernel::begin
/// [`FlatKernel::begin`]: super::FlatKernel::begin
pub struct RefineJob {
    label: &'static str,
    /// The kernel's `Params` as words, the range at `range_at` and `range_at + 1`.
    params: Vec<u32>,
    range_at: usize,
    steps: Vec<Step>,
    /// Fine triangles: the work of each step.
    per_step: u64,
    /// The step being recorded and its next item.
    step: usize,
    next: u64,
}

impl RefineJob {
    /// A job of `steps` over a refinement to `fine` fine triangles; `params` is the kernel's
    /// uniform block, whose `range_first` and `range_end` sit at word `range_at`. An error when
    /// a step dispatched whole would not fit the device's grid (then no piece does).
    pub(super) fn new<P: bytemuck::Pod>(
        ctx: &GpuContext,
        label: &'static str,
        params: &P,
        range_at: usize,
        fine: u64,
        steps: Vec<Step>,
    ) -> Result<Self, GpuError> {
        for step in &steps {
            dispatch_size(ctx, step.lanes.threads(step.items))?;
        }
        let params: Vec<u32> = bytemuck::pod_collect_to_vec(bytemuck::bytes_of(params));
        debug_assert!(range_at + 1 < params.len());
        let mut job = Self {
            label,
            params,
            range_at,
            steps,
            per_step: fine.max(1),
            step: 0,
            next: 0,
        };
        job.skip_empty();
        Ok(job)
    }

    fn skip_empty(&mut self) {
        while self.step < self.steps.len() && self.next >= self.steps[self.step].items {
            self.step += 1;
            self.next = 0;
        }
    }

    /// Whether nothing has been recorded yet.
    pub(super) fn is_untouched(&self) -> bool {
        self.step == 0 && self.next == 0 && !self.is_done()
    }

    /// The kernel's `Params` as words (its range at `range_at` left as given to [`RefineJob::new`]).
    pub(super) fn params(&self) -> &[u32] {
        &self.params
    }

    /// Marks the whole refinement as recorded by someone else, who wrote the same outputs (the
    /// batched path, `batch.rs`); returns its work.
    pub(super) fn recorded_elsewhere(&mut self) -> u64 {
        let work = self.work_left();
        self.step = self.steps.len();
        self.next = 0;
        work
    }

    /// Whether every piece has been recorded.
    pub fn is_done(&self) -> bool {
        self.step >= self.steps.len()
    }

    /// Work of the whole refinement, in fine triangles (the steps together).
    pub fn total_work(&self) -> u64 {
        self.per_step * self.steps.len() as u64
    }

    /// Work not recorded yet.
    pub fn work_left(&self) -> u64 {
        if self.is_done() {
            return 0;
        }
        let items = self.steps[self.step].items.max(1);
        let done_here =
            (u128::from(self.next) * u128::from(self.per_step) / u128::from(items)) as u64;
        self.total_work() - self.step as u64 * self.per_step - done_here
    }

    /// Records the whole refinement in one submission, each step's dispatch timestamped under
    /// `timer_label` when `measure` (this then waits for the GPU): the total GPU time and each
    /// step's, when the adapter has timestamp queries.
    pub(super) fn submit_whole(
        mut self,
        ctx: &GpuContext,
        timer_label: &'static str,
        measure: bool,
    ) -> Result<Option<(f64, Vec<f64>)>, GpuError> {
        let mut timer = PassTimer::new(ctx, timer_label, self.steps.len() as u32, measure);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        self.encode(ctx, &mut encoder, u64::MAX, Some(&mut timer))?;
        timer.resolve(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        timer.read(ctx)
    }

    /// Records about `work` of the refinement (see the module documentation) into `encoder`,
    /// at least one item when any is left, one compute pass per dispatch, each timestamped by
    /// `timer` while it has room. Steps follow one another in the order recorded: wgpu orders
    /// the passes of a queue, so each sees the previous ones' writes.
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        work: u64,
        mut timer: Option<&mut PassTimer>,
    ) -> Result<Encoded, GpuError> {
        let first_pass = timer.as_ref().map_or(0, |t| t.used());
        let before = self.work_left();
        let mut left = work;
        while !self.is_done() {
            let step = &self.steps[self.step];
            let remaining = step.items - self.next;
            // The items `left` is worth in this step, at least one.
            let wanted =
                (u128::from(left) * u128::from(step.items)).div_ceil(u128::from(self.per_step));
            let n = (wanted.min(u128::from(remaining)) as u64).max(1);
            let first = self.next;
            let mut params = self.params.clone();
            params[self.range_at] = first as u32;
            params[self.range_at + 1] = (first + n) as u32;
            let uniform = uniform_words(ctx, self.label, &params);
            let mut entries: Vec<(u32, &wgpu::Buffer)> = vec![(super::bindings::UNIFORM, &uniform)];
            entries.extend(step.bindings.iter().map(|(b, buf)| (*b, buf)));
            let group = bind_buffers_at(
                ctx,
                self.label,
                &step.pipeline.get_bind_group_layout(0),
                &entries,
            );
            let size = dispatch_size(ctx, step.lanes.threads(n))?;
            let pass_index = timer.as_mut().and_then(|t| t.next_pass());
            {
                let writes = match (&timer, pass_index) {
                    (Some(t), Some(i)) => t.writes(i),
                    _ => None,
                };
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(self.label),
                    timestamp_writes: writes,
                });
                pass.set_pipeline(&step.pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(size.0, size.1, 1);
            }
            let worth = (u128::from(n) * u128::from(self.per_step) / u128::from(step.items)) as u64;
            self.next += n;
            self.skip_empty();
            left = left.saturating_sub(worth.max(1));
            if left == 0 {
                break;
            }
        }
        Ok(Encoded {
            work: before - self.work_left(),
            passes: first_pass..timer.as_ref().map_or(0, |t| t.used()),
        })
    }
}
