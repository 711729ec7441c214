//! The whole steps of [`super::Simulator::advance_to`] from a committed
//! grid node: the segments of the hot loop ([`super::kernel`]) between
//! phase anchors and road breakpoints, the steps that a road breakpoint
//! splits with their share of the RMS time integral, and the node each run
//! commits. Its one `unsafe` calls the AVX2 build of the piecewise-linear
//! roads' steps after a run-time check that the CPU has it.
//!
//! Layer: whole steps (docs/architecture.md); it imports the solver's
//! `config`, `grid`, `inputs`, `kernel`, `modes`, `observers`, `pieces`,
//! `stepping`, `system`, `trajectory` and the crate's `error`, `limits`,
//! `metrics`, `model`, `monotone`, `road`.

#![allow(unsafe_code)]

use super::config::SimulationConfig;
use super::grid::DelayGrid;
use super::holding::Holding;
use super::inputs::Inputs;
use super::inputs::PHASE_ANCHOR;
#[cfg(target_arch = "x86_64")]
use super::kernel::wide_vectors;
use super::kernel::{
    HarmonicPhase, HotState, LinearPiece, Segment, SegmentEnd, run_segment, within_bounds,
};
use super::modes::Modes;
use super::observers::Observers;
use super::stepping::stepping;
use super::system::Filter;
use super::trajectory::Trajectory;
use crate::error::Result;
use crate::metrics::RunningRms;
use crate::model::Plant;
use crate::model::{State, V_T, X_T};
use crate::road::{RoadPiece, RoadSpec};
/// A view of a simulator for its whole steps: the configuration, plant,
/// grid, modes and inputs, and the trajectory and observers that the
/// whole steps move (the simulator's own fields, borrowed for one call).
pub(super) struct WholeSteps<'a> {
    pub(super) config: &'a SimulationConfig,
    pub(super) plant: &'a Plant,
    pub(super) grid: DelayGrid,
    pub(super) modes: &'a mut Modes,
    pub(super) inputs: &'a mut Inputs,
    pub(super) trajectory: &'a mut Trajectory,
    pub(super) observers: &'a mut Observers,
}

impl WholeSteps<'_> {
    /// Whether times `a` and `b` are the same on this grid
    /// ([`super::pieces::coincide`]).
    fn coincide(&self, a: f64, b: f64) -> bool {
        super::pieces::coincide(a, b, self.grid.step)
    }

    /// Commits the grid nodes `grid_index + 1 ..= last`, each by one whole
    /// step from the node before (the committed state is on node
    /// `grid_index`). Each node's state is a function of its index alone.
    /// Returns `true` when it stopped early, before a step in which a
    /// unilateral tire may lift off or a road breakpoint splits (the caller
    /// integrates that step with its switches, `solver::contact`).
    #[inline]
    pub(super) fn whole_steps(&mut self, last: u64) -> Result<bool> {
        let harmonic = matches!(self.config.road, RoadSpec::Harmonic { .. });
        match (self.grid.resolves_delay(), harmonic) {
            (true, true) => self.harmonic_whole_steps::<true>(last),
            (false, true) => self.harmonic_whole_steps::<false>(last),
            (true, false) => self.whole_steps_with::<true>(last),
            (false, false) => self.whole_steps_with::<false>(last),
        }
    }

    /// [`Self::whole_steps`] on the harmonic road: segments that end at the
    /// phase anchors (and at node m, where the history starts), each run by
    /// [`super::kernel::segment`].
    #[inline]
    fn harmonic_whole_steps<const DELAY: bool>(&mut self, last: u64) -> Result<bool> {
        let m = self.grid.delay_steps();
        let first = self.trajectory.grid_index;
        let len = self.inputs.history.len();
        let before_start = self.inputs.before_start();
        let mut hot = HotState {
            x: self.trajectory.committed_state.into(),
            road: HarmonicPhase(self.inputs.harmonic_phase(first)),
            k: first,
            slot: ((first + 1) % len as u64) as usize,
            rms: self.observers.rms,
            w: self.trajectory.committed_filter.into(),
            weighted: self.observers.weighted,
            holding: self.observers.holding,
        };
        let mut end_reason = SegmentEnd::Reached;
        while hot.k < last {
            let start = hot.k;
            let mut end = last.min((hot.k / PHASE_ANCHOR + 1) * PHASE_ANCHOR);
            let before_history = DELAY && hot.k < m;
            if before_history {
                end = end.min(m);
            }
            let segment = Segment {
                op: &self.modes.grid_step,
                history: &mut self.inputs.history,
                end,
                before_start,
            };
            end_reason = run_segment::<_, DELAY>(segment, &mut hot, before_history);
            if hot.k.is_multiple_of(PHASE_ANCHOR) {
                hot.road = HarmonicPhase(self.inputs.exact_phase(hot.k));
            }
            // The node that ends the segment, reached without diverging,
            // joins the run's sums.
            if hot.k > start && !matches!(end_reason, SegmentEnd::Diverged(_)) {
                self.modes
                    .grid_step
                    .count(&mut hot.rms, &hot.x, hot.road.0[0]);
                self.modes
                    .grid_step
                    .count_weighted(&hot.w, &mut hot.weighted);
            }
            if end_reason != SegmentEnd::Reached {
                break;
            }
        }
        self.observers.rms = hot.rms;
        self.observers.weighted = hot.weighted;
        self.observers.holding = hot.holding;
        self.inputs.keep_node_phase(hot.k, hot.road.0);
        self.set_committed_node(first, hot.k, hot.x, hot.w);
        match end_reason {
            SegmentEnd::Diverged(x) => {
                crate::limits::check_divergence(self.inputs.node_time(hot.k + 1), &State::from(x))
                    .map(|()| false)
            }
            SegmentEnd::Switch => Ok(true),
            SegmentEnd::Reached => Ok(false),
        }
    }

    /// Records node k (reached by the whole-step loop from node `first`) as
    /// the committed and current state, with its filter state w.
    fn set_committed_node(&mut self, first: u64, k: u64, x: [f64; 6], w: [f64; 8]) {
        if k > first {
            let time = self.inputs.node_time(k);
            self.trajectory
                .commit_node(k, time, State::from(x), Filter::from(w));
            self.inputs.road.release_before(time);
        }
    }

    /// [`Self::whole_steps`] on piecewise-linear roads: runs of the hot
    /// loop inside each road piece, the node at a piece's end closing the
    /// RMS run, and [`Self::split_step`] for a step that a breakpoint
    /// splits. It stays one function on purpose: the run's state (state,
    /// filter state, sums, road holding, ring slot) lives in locals from
    /// one run of the loop to the next, which the AVX2 build keeps in
    /// registers.
    #[inline(always)]
    pub(super) fn whole_steps_with_body<const DELAY: bool>(&mut self, last: u64) -> Result<bool> {
        let m = self.grid.delay_steps();
        let len = self.inputs.history.len();
        let first = self.trajectory.grid_index;
        let mut k = first;
        let mut x: [f64; 6] = self.trajectory.committed_state.into();
        let before_start = self.inputs.before_start();
        // Ring slot of node k + 1, which holds node k − m until overwritten.
        let mut slot = ((k + 1) % len as u64) as usize;
        let mut rms = self.observers.rms;
        let mut w: [f64; 8] = self.trajectory.committed_filter.into();
        let mut weighted = self.observers.weighted;
        let mut holding = self.observers.holding;
        // A local copy: the compiler then knows that the history writes do
        // not change it.
        let op = self.modes.grid_step.clone();
        // The piece at the node just reached, looked up for its road
        // displacement and used again for the step that leaves it.
        let mut piece_at_node = None;
        let result = loop {
            if k >= last {
                break Ok(false);
            }
            let (t, to) = (self.inputs.node_time(k), self.inputs.node_time(k + 1));
            let covering = self.inputs.piece_over(t, to, piece_at_node.take());
            if let Some(
                piece @ RoadPiece::Linear {
                    start,
                    end,
                    value,
                    slope,
                },
            ) = covering
            {
                // The steps whose end nodes lie inside this piece, and the
                // one after them that reaches its end, in the hot loop (no
                // road lookup, no breakpoint test per step).
                let mut inside = self.last_node_inside(k, last, end);
                let before = DELAY && k < m;
                if before {
                    inside = inside.min(m);
                }
                let stop = inside.max(k + 1);
                let mut hot = HotState {
                    x,
                    road: LinearPiece {
                        start_time: self.config.start_time,
                        step: self.grid.step,
                        k,
                        start,
                        value,
                        slope,
                    },
                    k,
                    slot,
                    rms,
                    w,
                    weighted,
                    holding,
                };
                let segment = Segment {
                    op: &op,
                    history: &mut self.inputs.history,
                    end: stop,
                    before_start,
                };
                let end_reason = run_segment::<_, DELAY>(segment, &mut hot, before);
                let started = k;
                (x, k, slot, rms) = (hot.x, hot.k, hot.slot, hot.rms);
                (w, weighted, holding) = (hot.w, hot.weighted, hot.holding);
                match end_reason {
                    SegmentEnd::Diverged(x_next) => {
                        break crate::limits::check_divergence(
                            self.inputs.node_time(k + 1),
                            &State::from(x_next),
                        )
                        .map(|()| false);
                    }
                    SegmentEnd::Switch => {
                        if k > started {
                            op.count(&mut rms, &x, piece.value(self.inputs.node_time(k)));
                            op.count_weighted(&w, &mut weighted);
                        }
                        break Ok(true);
                    }
                    SegmentEnd::Reached => {}
                }
                let now = self.inputs.node_time(k);
                // `road.piece(now)` is this piece exactly when the node lies
                // inside it.
                let piece_now = if k == inside {
                    piece
                } else {
                    self.inputs.road.piece(now)
                };
                op.count(&mut rms, &x, piece_now.value(now));
                op.count_weighted(&w, &mut weighted);
                if k != inside && self.coincide(end, now) {
                    // The node is a road breakpoint: x_g has a kink there,
                    // so the RMS run of nodes closes at it.
                    let after = self.inputs.piece_from(now);
                    self.observers.close_run_at_node(
                        &mut stepping!(self),
                        k,
                        (now, &State::from(x), &Filter::from(w)),
                        &mut rms,
                        &mut weighted,
                        &piece,
                        &after,
                    );
                }
                self.inputs
                    .road
                    .release_before(self.inputs.node_time(k - 1));
                piece_at_node = Some(piece_now);
                continue;
            }
            if op.switching.any() {
                // A step that a road breakpoint splits, with an element
                // that may switch inside it: the caller integrates it.
                break Ok(true);
            }
            // A step that a road breakpoint splits.
            match self.split_step(
                k,
                (t, to),
                (x, w),
                slot,
                (&mut rms, &mut weighted),
                &mut holding,
            ) {
                Ok((x_next, w_next, piece_next)) => {
                    piece_at_node = Some(piece_next);
                    (x, w) = (x_next, w_next);
                    slot = if slot + 1 == len { 0 } else { slot + 1 };
                    k += 1;
                }
                Err(e) => break Err(e),
            }
        };
        self.observers.rms = rms;
        self.observers.weighted = weighted;
        self.observers.holding = holding;
        self.set_committed_node(first, k, x, w);
        result
    }

    /// A step of the whole-step loop that a road breakpoint splits, from
    /// node k at t (state and filter state `node`) to node k + 1 at `to`:
    /// the open run (`sums`: its RMS and a_w sums) closes at node k, the
    /// step is integrated piece by piece, node k + 1 goes into the history
    /// ring at `slot` and starts the next run. Returns node k + 1's state,
    /// filter state and road piece; a state out of bounds is an error.
    #[cold]
    #[inline(never)]
    fn split_step(
        &mut self,
        k: u64,
        (t, to): (f64, f64),
        (x, w): ([f64; 6], [f64; 8]),
        slot: usize,
        (rms, weighted): (&mut RunningRms, &mut [f64; 2]),
        holding: &mut Holding,
    ) -> Result<([f64; 6], [f64; 8], RoadPiece)> {
        let node = State::from(x);
        let node_filter = Filter::from(w);
        let piece_at_start = self.inputs.piece_from(t);
        self.observers.close_run_at_node(
            &mut stepping!(self),
            k,
            (t, &node, &node_filter),
            rms,
            weighted,
            &piece_at_start,
            &piece_at_start,
        );
        let anchor = self.observers.integral.anchor;
        let mut step_holding = *holding;
        let (x_end, w_end, step_integral, at_end, last_piece) = stepping!(self)
            .integrate_split_step(k, t, node, node_filter, anchor, to, &mut step_holding);
        let x_next: [f64; 6] = x_end.into();
        if (k + 1).is_multiple_of(PHASE_ANCHOR) {
            self.inputs.road.release_before(t);
        }
        let piece_next = self.inputs.road.piece(to);
        if !within_bounds(&x_next) {
            crate::limits::check_divergence(to, &State::from(x_next))?;
        }
        self.inputs.history[slot] = [x_next[X_T], x_next[V_T]];
        if self.config.metrics.road_holding() {
            *holding = step_holding;
            holding.add_node(&x_next);
        }
        self.observers.restart_run_after_step(
            &mut stepping!(self),
            k + 1,
            (to, &x_end, &w_end),
            step_integral,
            (at_end, last_piece),
        );
        Ok((x_next, w_end.into(), piece_next))
    }

    /// The largest node index `n` in `[k, last]` such that the nodes
    /// `k + 1 ..= n` lie strictly inside a road piece that ends at `end`
    /// (before it and not coinciding with it).
    fn last_node_inside(&self, k: u64, last: u64, end: f64) -> u64 {
        let inside = |j: u64| {
            let t = self.inputs.node_time(j);
            t < end && !self.coincide(end, t)
        };
        let estimate = ((end - self.config.start_time) / self.grid.step).floor();
        let guess = if estimate > k as f64 {
            estimate as u64
        } else {
            k
        };
        crate::monotone::last_index_where(k, last, guess, inside)
    }

    /// [`Self::whole_steps`] on piecewise-linear roads: a step that a road
    /// breakpoint splits goes through
    /// [`Stepping::integrate_split_step`](super::stepping::Stepping::integrate_split_step).
    pub(super) fn whole_steps_with<const DELAY: bool>(&mut self, last: u64) -> Result<bool> {
        #[cfg(target_arch = "x86_64")]
        if wide_vectors() {
            // SAFETY: the CPU supports AVX2 (checked at run time).
            return unsafe { self.whole_steps_with_avx2::<DELAY>(last) };
        }
        self.whole_steps_with_body::<DELAY>(last)
    }

    /// [`Self::whole_steps_with`] compiled for AVX2 (bit-identical).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn whole_steps_with_avx2<const DELAY: bool>(&mut self, last: u64) -> Result<bool> {
        self.whole_steps_with_body::<DELAY>(last)
    }
}
