//! The whole-step loop, the solver's hot path: `X_{k+1} = Φ X_k + Γ_uH
//! n_k + road_k` from grid node to grid node within a segment (no phase
//! anchor, road breakpoint or start of the history crossed), the road as
//! the loop carries it ([`NodeRoad`]), and the loop's AVX2 build. Its
//! `unsafe` is unchecked reads and writes of the delay history ring, whose
//! indices the loop keeps below the ring's length, and the calls of
//! functions compiled for AVX2, made only after a run-time check that the
//! CPU has it. The segments' orchestration is [`super::whole_steps`].
//!
//! Layer: hot loop (docs/architecture.md); it imports the solver's
//! `grid_step`, `holding`, `linalg` and the crate's `comfort`, `limits`,
//! `metrics`, `model`.

#![allow(unsafe_code)]

use super::grid_step::{FilterGridStep, GridStep, filter_combine};
use super::holding::{Holding, check_step, deflection, may_fall_through_zero};
use super::linalg::{add6, combine2, combine4, combine6};
use crate::comfort::WK_STATES;
use crate::limits::DIVERGENCE_BOUNDS;
use crate::metrics::RunningRms;
use crate::model::dynamics::{SWITCHES, Switch};
use crate::model::{V_T, X_T};

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
/// With road holding, every step is tested for contact loss and every new
/// node enters the largest |SDD| ([`super::holding`]). Stops at `end`,
/// before a state out of bounds, or before a step in which a switching
/// element of the grid step's list may switch (its switch function, in
/// the mode of every element's first law where the loop runs, may fall
/// through 0: the unilateral tire may lift off) ([`SegmentEnd`]).
/// `DELAY`: the delay is resolved on the grid;
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
    let (contact, switching) = (op.contact, op.switching);
    // The switching elements' sides at node k: their switch functions in
    // the loop's mode; the tire's is the margin of the road-holding test.
    let mut sides = switching.sides(&x, road.displacement(), road.rate(op));
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
            let next_sides = switching.sides(&x_next, road_next.displacement(), road_next.rate(op));
            let switches = (0..SWITCHES.len()).any(|i| {
                may_fall_through_zero(contact.step, sides[i], next_sides[i]) && switching.applies[i]
            });
            if switches {
                // An element may switch in this step (the wheel may lift
                // off): it is left to the caller (nothing of it is
                // committed).
                end = SegmentEnd::Switch;
                break;
            }
            if op.holding {
                let tire = Switch::Tire as usize;
                if let Some(loss) = check_step(contact, k, sides[tire], next_sides[tire]) {
                    holding.add_step(loss);
                }
                let next_bend = deflection(&x_next);
                holding.add_deflection(contact.step, bend, next_bend);
                bend = next_bend;
            }
            sides = next_sides;
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
/// steps along when the grid step has it, the sides' test when the grid
/// step keeps road holding ([`super::Metrics`]: the filter implies it) or
/// has a switching element (which stops the loop before it may switch;
/// the road-holding accumulators run only with road holding).
pub(super) fn run_segment<R: NodeRoad, const DELAY: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
    before: bool,
) -> SegmentEnd {
    match (
        seg.op.filter.is_some(),
        seg.op.holding || seg.op.switching.any(),
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
