//! The whole steps of [`super::Simulator::advance_to`] from a committed
//! grid node (its hot path): segments of the whole-step loop between phase
//! anchors and road breakpoints, the steps that a road breakpoint splits
//! with their share of the RMS time integral, and the loop's AVX2 build.
//! All the solver's `unsafe` is here: unchecked reads
//! and writes of the delay history ring, whose indices the loop keeps below
//! the ring's length, and the calls of functions compiled for AVX2, made
//! only after a run-time check that the CPU has it.
//!
//! Layer: whole steps (docs/architecture.md); it imports the solver's
//! `config`, `grid`, `grid_step`, `holding`, `inputs`, `linalg`, `modes`,
//! `observers`, `pieces`, `stepping`, `system`, `trajectory` and the
//! crate's `comfort`, `error`, `limits`, `metrics`, `model`, `monotone`,
//! `road`.
#![allow(unsafe_code)]

use super::config::SimulationConfig;
use super::grid::DelayGrid;
use super::grid_step::{FilterGridStep, GridStep, filter_combine};
use super::holding::{Holding, check_step, deflection, margin};
use super::inputs::Inputs;
use super::inputs::PHASE_ANCHOR;
use super::linalg::{add6, combine2, combine4, combine6};
use super::modes::Modes;
use super::observers::Observers;
use super::stepping::stepping;
use super::system::Filter;
use super::trajectory::Trajectory;
use crate::comfort::WK_STATES;
use crate::error::Result;
use crate::limits::DIVERGENCE_BOUNDS;
use crate::metrics::RunningRms;
use crate::model::Plant;
use crate::model::{State, V_T, X_T};
use crate::road::{RoadPiece, RoadSpec};

/// Whether every state component is within its divergence bound (false
/// for NaN), with one branch for the whole state.
#[inline(always)]
pub(super) fn within_bounds(x: &[f64; 6]) -> bool {
    let b = DIVERGENCE_BOUNDS;
    (x[0].abs() <= b[0])
        & (x[1].abs() <= b[1])
        & (x[2].abs() <= b[2])
        & (x[3].abs() <= b[3])
        & (x[4].abs() <= b[4])
        & (x[5].abs() <= b[5])
}

/// The road as the whole-step loop carries it from grid node to grid node.
pub(super) trait NodeRoad: Copy {
    /// The road's part of the step that leaves the current node.
    fn input(&self, op: &GridStep) -> [f64; 6];
    /// The road's part of the W_k filter's step that leaves the current node.
    fn filter_input(&self, filter: &FilterGridStep) -> [f64; WK_STATES];
    /// `x_g` at the current node (m).
    fn displacement(&self) -> f64;
    /// `dx_g/dt` at the current node (m/s), on the side of the step that
    /// leaves it.
    fn rate(&self, op: &GridStep) -> f64;
    /// Moves to the next node.
    fn advance(&mut self, op: &GridStep);
}

/// The harmonic road's phase `A [sin ω t_k, cos ω t_k]` at node k, rotated
/// exactly from node to node (see [`super::inputs::PHASE_ANCHOR`]).
#[derive(Clone, Copy)]
pub(super) struct HarmonicPhase(pub(super) [f64; 2]);

impl NodeRoad for HarmonicPhase {
    #[inline(always)]
    fn input(&self, op: &GridStep) -> [f64; 6] {
        combine2(&op.harmonic, &self.0)
    }
    #[inline(always)]
    fn filter_input(&self, filter: &FilterGridStep) -> [f64; WK_STATES] {
        filter_combine(&filter.harmonic, &self.0)
    }
    #[inline(always)]
    fn displacement(&self) -> f64 {
        self.0[0]
    }
    #[inline(always)]
    fn rate(&self, op: &GridStep) -> f64 {
        op.contact.angular_frequency * self.0[1]
    }
    #[inline(always)]
    fn advance(&mut self, op: &GridStep) {
        self.0 = op.rotate(self.0);
    }
}

/// One linear road piece `x_g = value + slope (t − start)` at grid node
/// `t_k = t_0 + k h`, evaluated as [`crate::road::RoadPiece::value`] does.
#[derive(Clone, Copy)]
pub(super) struct LinearPiece {
    pub(super) start_time: f64,
    pub(super) step: f64,
    pub(super) k: u64,
    pub(super) start: f64,
    pub(super) value: f64,
    pub(super) slope: f64,
}

impl LinearPiece {
    #[inline(always)]
    pub(super) fn value_now(&self) -> f64 {
        let t = self.start_time + self.k as f64 * self.step;
        self.value + self.slope * (t - self.start)
    }
}

impl NodeRoad for LinearPiece {
    #[inline(always)]
    fn input(&self, op: &GridStep) -> [f64; 6] {
        combine2(&op.linear, &[self.value_now(), self.slope])
    }
    #[inline(always)]
    fn filter_input(&self, filter: &FilterGridStep) -> [f64; WK_STATES] {
        filter_combine(&filter.linear, &[self.value_now(), self.slope])
    }
    #[inline(always)]
    fn displacement(&self) -> f64 {
        self.value_now()
    }
    #[inline(always)]
    fn rate(&self, _: &GridStep) -> f64 {
        self.slope
    }
    #[inline(always)]
    fn advance(&mut self, _: &GridStep) {
        self.k += 1;
    }
}

/// Why a run of the whole-step loop ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum SegmentEnd {
    /// At its end node.
    Reached,
    /// Before a step whose end state (returned) is out of bounds.
    Diverged([f64; 6]),
    /// Before a step in which a unilateral tire may lift off (the margin's
    /// cubic goes negative), which the caller integrates with the switch.
    Switch,
}

/// What the whole-step loop carries from node to node.
#[derive(Clone, Copy)]
pub(super) struct HotState<R> {
    pub(super) x: [f64; 6],
    pub(super) road: R,
    pub(super) k: u64,
    /// Ring slot of node k + 1 (it holds node k − m until overwritten).
    pub(super) slot: usize,
    pub(super) rms: RunningRms,
    /// The W_k filter state at node k (zero without the filter).
    pub(super) w: [f64; WK_STATES],
    /// `Σ a_w²`, `Σ a_w⁴` over the nodes of the open run, as `rms`.
    pub(super) weighted: [f64; 2],
    /// Road holding and working space so far.
    pub(super) holding: Holding,
}

/// One run of the whole-step loop, within which neither a phase anchor
/// (harmonic road), a road breakpoint (linear roads) nor the start of the
/// history is crossed.
pub(super) struct Segment<'a> {
    pub(super) op: &'a GridStep,
    pub(super) history: &'a mut [[f64; 2]],
    /// The node the segment stops at.
    pub(super) end: u64,
    /// The nodes `[x, 0, x, 0]` of the constant history before the start.
    pub(super) before_start: [f64; 4],
}

/// The hot loop: `X_{k+1} = Φ X_k + Γ_uH n_k + road_k`, the road moved on,
/// the new node stored in the history. The BA, SDD, TDD of every node
/// after the first are added to the RMS sums, except the last one's, which
/// the caller adds (on the harmonic road its phase is exact at an anchor).
/// Every step is tested for contact loss and every new node enters the
/// largest |SDD| ([`super::holding`]). Stops at `end`, before a state out
/// of bounds, or (unilateral tire) before a step that may lift the wheel
/// off ([`SegmentEnd`]). `DELAY`: the delay is resolved on the grid;
/// `BEFORE`: all the delayed nodes lie before the start; `FILTER`: the W_k
/// filter steps along ([`FilterGridStep`]) and its `a_w²`, `a_w⁴` are
/// summed like the RMS sums.
///
/// It stays one function on purpose: it is the loop every run spends its
/// time in, and its state (x, the road, the sums, the ring slot) lives in
/// locals that the compiler keeps in registers across the whole segment;
/// the const parameters give one specialized copy per case instead of
/// branches inside it.
#[inline(always)]
pub(super) fn segment<
    R: NodeRoad,
    const DELAY: bool,
    const BEFORE: bool,
    const FILTER: bool,
    const HOLDING: bool,
>(
    seg: Segment,
    hot: &mut HotState<R>,
) -> SegmentEnd {
    let op = seg.op;
    let history = seg.history;
    let len = history.len();
    assert!(hot.slot < len);
    let HotState {
        mut x,
        mut road,
        mut k,
        mut slot,
        mut rms,
        mut w,
        mut weighted,
        mut holding,
    } = *hot;
    let filter = if FILTER { op.filter.as_ref() } else { None };
    let contact = op.contact;
    let mut edge = margin(contact.limit, &x, road.displacement(), road.rate(op));
    let mut bend = deflection(&x);
    let mut end = SegmentEnd::Reached;
    // Node k, where the segment starts, was counted in the RMS sums already;
    // each later node is counted in the step that leaves it.
    let mut count = false;
    while k < seg.end {
        let next_slot = if slot + 1 == len { 0 } else { slot + 1 };
        let mut input = road.input(op);
        let nodes = if DELAY {
            let nodes = if BEFORE {
                seg.before_start
            } else {
                debug_assert!(slot < len && next_slot < len);
                // SAFETY: both slots are < len (the ring's length): slot
                // starts below len and next_slot wraps to 0 at len.
                let ([x0, v0], [x1, v1]) = unsafe {
                    (
                        *history.get_unchecked(slot),
                        *history.get_unchecked(next_slot),
                    )
                };
                [x0, v0, x1, v1]
            };
            input = add6(combine4(&op.nodes, &nodes), input);
            nodes
        } else {
            [0.0; 4]
        };
        let x_next = add6(combine6(&op.transition, &x), input);
        if !within_bounds(&x_next) {
            if count {
                op.count(&mut rms, &x, road.displacement());
                if let Some(f) = filter {
                    f.count(&w, &mut weighted);
                }
            }
            end = SegmentEnd::Diverged(x_next);
            break;
        }
        let mut road_next = road;
        road_next.advance(op);
        if HOLDING {
            let next_edge = margin(
                contact.limit,
                &x_next,
                road_next.displacement(),
                road_next.rate(op),
            );
            if let Some(loss) = check_step(contact, k, edge, next_edge) {
                if contact.unilateral && (loss.whole || loss.first.is_some()) {
                    // The wheel may lift off in this step: it is left to
                    // the caller (nothing of it is committed).
                    end = SegmentEnd::Switch;
                    break;
                }
                if op.holding {
                    holding.add_step(loss);
                }
            }
            if op.holding {
                let next_bend = deflection(&x_next);
                holding.add_deflection(contact.step, bend, next_bend);
                bend = next_bend;
            }
            edge = next_edge;
        }
        if count {
            op.count(&mut rms, &x, road.displacement());
            if let Some(f) = filter {
                f.count(&w, &mut weighted);
            }
        }
        count = true;
        if let Some(f) = filter {
            // The inputs first, then `Φ_ww w` as a pairwise sum added last:
            // the filter's own recurrence is then a short chain.
            let mut inputs = filter_combine(&f.plant, &x);
            for part in [
                filter_combine(&f.nodes, &nodes),
                filter_combine(&f.next_node, &[x_next[X_T], x_next[V_T]]),
                road.filter_input(f),
            ] {
                for i in 0..WK_STATES {
                    inputs[i] += part[i];
                }
            }
            let own = f.transition_times(&w);
            w = std::array::from_fn(|i| own[i] + inputs[i]);
        }
        road = road_next;
        // SAFETY: slot < len, as above.
        unsafe { *history.get_unchecked_mut(slot) = [x_next[X_T], x_next[V_T]] };
        x = x_next;
        slot = next_slot;
        k += 1;
    }
    *hot = HotState {
        x,
        road,
        k,
        slot,
        rms,
        w,
        weighted,
        holding,
    };
    end
}

/// [`segment`] compiled for AVX2 (the same operations in the same order,
/// without FMA, so the results are bit-identical).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) fn segment_avx2<
    R: NodeRoad,
    const DELAY: bool,
    const BEFORE: bool,
    const FILTER: bool,
    const HOLDING: bool,
>(
    seg: Segment,
    hot: &mut HotState<R>,
) -> SegmentEnd {
    segment::<R, DELAY, BEFORE, FILTER, HOLDING>(seg, hot)
}

/// Runs [`segment`] with the widest vector unit available; the filter
/// steps along when the grid step has it, the contact test when the grid
/// step keeps road holding ([`super::Metrics`]: the filter implies it) or
/// has a unilateral tire (which stops at a lift-off; its accumulators run
/// only with road holding).
pub(super) fn run_segment<R: NodeRoad, const DELAY: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
    before: bool,
) -> SegmentEnd {
    match (
        seg.op.filter.is_some(),
        seg.op.holding || seg.op.contact.unilateral,
    ) {
        (true, _) => run_segment_with::<R, DELAY, true, true>(seg, hot, before),
        (false, true) => run_segment_with::<R, DELAY, false, true>(seg, hot, before),
        (false, false) => run_segment_with::<R, DELAY, false, false>(seg, hot, before),
    }
}

fn run_segment_with<R: NodeRoad, const DELAY: bool, const FILTER: bool, const HOLDING: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
    before: bool,
) -> SegmentEnd {
    #[cfg(target_arch = "x86_64")]
    if wide_vectors() {
        // SAFETY: the CPU supports AVX2 (checked at run time).
        return unsafe {
            match (DELAY, before) {
                (true, true) => segment_avx2::<R, true, true, FILTER, HOLDING>(seg, hot),
                (true, false) => segment_avx2::<R, true, false, FILTER, HOLDING>(seg, hot),
                _ => segment_avx2::<R, false, false, FILTER, HOLDING>(seg, hot),
            }
        };
    }
    match (DELAY, before) {
        (true, true) => segment::<R, true, true, FILTER, HOLDING>(seg, hot),
        (true, false) => segment::<R, true, false, FILTER, HOLDING>(seg, hot),
        _ => segment::<R, false, false, FILTER, HOLDING>(seg, hot),
    }
}

/// Whether the AVX2 loop is used: the CPU has it and `TDVASS_NO_AVX2` is
/// not set (to compare the two loops).
#[cfg(target_arch = "x86_64")]
pub(super) fn wide_vectors() -> bool {
    use std::sync::OnceLock;
    static WIDE: OnceLock<bool> = OnceLock::new();
    *WIDE.get_or_init(|| {
        std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("TDVASS_NO_AVX2").is_none()
    })
}

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
            self.trajectory.grid_index = k;
            self.trajectory.committed_time = time;
            self.trajectory.committed_state = State::from(x);
            self.trajectory.committed_filter = Filter::from(w);
            self.trajectory
                .set_current(time, self.trajectory.committed_state);
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
            if op.contact.unilateral {
                // A step that a road breakpoint splits, with a tire that
                // may lift off inside it: the caller integrates it.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::SimulationConfig;
    use crate::solver::Simulator;

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_loop_is_bit_identical_to_the_baseline_loop() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        /// Runs 1000 steps from `sim`'s node with the baseline and the AVX2
        /// loop; returns the bits of state, RMS sums and history of each.
        fn both<R: NodeRoad>(sim: &Simulator, road: R) -> Vec<Vec<u64>> {
            let start = HotState {
                x: sim.trajectory.committed_state.into(),
                road,
                k: sim.trajectory.grid_index,
                slot: ((sim.trajectory.grid_index + 1) % sim.inputs.history.len() as u64) as usize,
                rms: sim.observers.rms,
                w: sim.trajectory.committed_filter.into(),
                weighted: sim.observers.weighted,
                holding: sim.observers.holding,
            };
            let mut results = Vec::new();
            for wide in [false, true] {
                let mut history = sim.inputs.history.clone();
                let mut hot = HotState { ..start };
                let seg = Segment {
                    op: &sim.modes.grid_step,
                    history: &mut history,
                    end: sim.trajectory.grid_index + 1000,
                    before_start: [0.0; 4],
                };
                if wide {
                    // SAFETY: AVX2 was detected by the caller.
                    unsafe { segment_avx2::<_, true, false, true, true>(seg, &mut hot) };
                } else {
                    segment::<_, true, false, true, true>(seg, &mut hot);
                }
                let mut v: Vec<u64> = hot.x.iter().map(|v| v.to_bits()).collect();
                v.extend(hot.rms.sums_of_squares.map(f64::to_bits));
                v.extend(hot.w.map(f64::to_bits));
                v.extend(hot.weighted.map(f64::to_bits));
                v.push(hot.holding.max_deflection.to_bits());
                v.push(hot.holding.lost_time.to_bits());
                v.push(hot.road.displacement().to_bits());
                v.extend(history.iter().flatten().map(|v| v.to_bits()));
                results.push(v);
            }
            results
        }
        let mut sim = Simulator::new(SimulationConfig {
            metrics: crate::solver::Metrics::Comfort,
            ..SimulationConfig::default()
        })
        .unwrap();
        sim.advance_to(0.01).unwrap();
        let phase = HarmonicPhase(sim.inputs.harmonic_phase(sim.trajectory.grid_index));
        let [baseline, wide] = &both(&sim, phase)[..] else {
            unreachable!()
        };
        assert_eq!(baseline, wide);
        // A linear piece (a ramp of the road) from the same state.
        let ramp = LinearPiece {
            start_time: 0.0,
            step: sim.grid.step,
            k: sim.trajectory.grid_index,
            start: 0.005,
            value: 0.01,
            slope: -0.3,
        };
        let [baseline, wide] = &both(&sim, ramp)[..] else {
            unreachable!()
        };
        assert_eq!(baseline, wide);
    }
}
