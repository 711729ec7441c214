//! Observers: what a run accumulates up to the committed point for its
//! outputs, and the one place where a run of the time averages is closed
//! and a new one starts.
//!
//! The time averages keep `∫ y² dt` as a closed part and an open run of
//! grid nodes (see `integrals`); a run closes where f or f' may jump (a
//! road breakpoint on a node, a change of the external road input, a
//! switch of the tire's contact) and after a step integrated piece by
//! piece. The observers are told of these points by the driver (the
//! simulator), which alone moves the committed point; the squares at a
//! point come from stepping ([`Stepping::squares_at`]).
//!
//! It imports the integrals, the stepping view, the road-holding
//! accumulators and the lift-off log; nothing of the driver.

use super::contact::LiftOffLog;
use super::holding::Holding;
use super::integrals::{Accumulated, INTEGRALS, SquareIntegral, Squares, add};
use super::stepping::{Committed, Stepping};
use super::system::Filter;
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::Result;
use crate::metrics::RunningRms;
use crate::model::State;
use crate::road::RoadPiece;

/// What the run accumulates up to the committed point, for its outputs.
#[derive(Debug, Clone)]
pub(super) struct Observers {
    /// `Σ y²` of BA, SDD, TDD over the grid nodes of the open run (after
    /// the anchor of `integral`, up to the grid index).
    pub(super) rms: RunningRms,
    /// The time integral of `y²` (see `integrals`).
    pub(super) integral: SquareIntegral,
    /// `Σ a_w²`, `Σ a_w⁴` over the grid nodes of the open run (as `rms`).
    pub(super) weighted: [f64; 2],
    /// Road holding and working space up to the committed point.
    pub(super) holding: Holding,
    /// The dynamic tire load at the start (N).
    pub(super) start_load: f64,
    /// Lift-offs not yet taken by a front-end's event log (boxed: made
    /// once, and a simulator moves without copying it).
    pub(super) lift_off_log: Box<LiftOffLog>,
}

impl Observers {
    /// At the start time, before the squares there are known.
    pub(super) fn new(start_time: f64) -> Observers {
        Observers {
            rms: RunningRms::default(),
            integral: SquareIntegral::new(start_time, Default::default()),
            weighted: [0.0; 2],
            holding: Holding::new(0.0, 1.0, start_time),
            start_load: 0.0,
            lift_off_log: Box::default(),
        }
    }

    /// Writes the sums of the open run and the time integral: the RMS sums
    /// of squares and sample count, the closed integral, the anchor's
    /// index, time, squares and their rates, and the `a_w` sums.
    pub(super) fn write_sums(&self, w: &mut ByteWriter) {
        self.rms.sums_of_squares.iter().for_each(|&v| w.f64(v));
        w.u64(self.rms.samples);
        let integral = &self.integral;
        integral.closed.iter().for_each(|&v| w.f64(v));
        w.u64(integral.anchor_index);
        w.f64(integral.anchor_time);
        integral.anchor.value.iter().for_each(|&v| w.f64(v));
        integral.anchor.rate.iter().for_each(|&v| w.f64(v));
        self.weighted.iter().for_each(|&v| w.f64(v));
    }

    /// Reads what [`Observers::write_sums`] wrote (checked against the
    /// run by the caller).
    pub(super) fn read_sums(&mut self, r: &mut ByteReader) -> Result<()> {
        let mut rms = RunningRms::default();
        for v in rms.sums_of_squares.iter_mut() {
            *v = r.f64()?;
        }
        rms.samples = r.u64()?;
        self.rms = rms;
        for v in self.integral.closed.iter_mut() {
            *v = r.f64()?;
        }
        self.integral.anchor_index = r.u64()?;
        self.integral.anchor_time = r.f64()?;
        for v in self.integral.anchor.value.iter_mut() {
            *v = r.f64()?;
        }
        for v in self.integral.anchor.rate.iter_mut() {
            *v = r.f64()?;
        }
        for v in self.weighted.iter_mut() {
            *v = r.f64()?;
        }
        Ok(())
    }

    /// Starts a new, empty run at grid index k and time t (s): the anchor
    /// moves there, its squares unchanged.
    #[inline]
    pub(super) fn start_run(&mut self, k: u64, t: f64) {
        self.rms = RunningRms::default();
        self.weighted = [0.0; 2];
        self.integral.anchor_index = k;
        self.integral.anchor_time = t;
    }

    /// Closes the open run at the committed point `at` (its integral added
    /// to the closed part) and starts a new, empty one there.
    pub(super) fn close_run_at_committed(&mut self, s: &mut Stepping, at: &Committed) {
        let (closed, _) = self.integral_to_committed(s, at);
        self.integral.closed = closed;
        self.start_run(at.k, at.time);
    }

    /// `∫_{t_0} f` up to the committed point `at` (the end of the open
    /// run), and the squares there.
    pub(super) fn integral_to_committed(
        &self,
        s: &mut Stepping,
        at: &Committed,
    ) -> ([f64; INTEGRALS], Squares) {
        if self.rms.samples == 0 {
            return (self.integral.closed, self.integral.anchor);
        }
        let (k, t, x, w) = (at.k, at.time, at.state, at.filter);
        let piece = s.inputs.piece_from(t);
        let at_node = s.squares_at(k, t, &x, &w, (t, x), &piece);
        (
            self.integral
                .through_run(s.grid.step, &self.rms, &self.weighted, &at_node),
            at_node,
        )
    }

    /// Everything accumulated from `t_0` to time t with state x: `∫ f`,
    /// the road-holding accumulators (with the stretch from the committed
    /// point `at` to t) and the filter state at t. `drift`: t snaps to the
    /// committed point (a time drift, not a different time).
    pub(super) fn accumulated(
        &self,
        s: &mut Stepping,
        at: &Committed,
        (t, x): (f64, State),
        drift: bool,
    ) -> Accumulated {
        let (base, at_committed) = self.integral_to_committed(s, at);
        let (tc, xc, wc) = (at.time, at.state, at.filter);
        let mut holding = self.holding;
        if t == tc {
            return Accumulated {
                integral: base,
                holding,
                filter: wc,
            };
        }
        if drift {
            // A drift away from the committed point: its Taylor series,
            // `δ f + δ²/2 f'` (the next term, δ³/6 f'', is below 1e-30 of
            // the integral).
            let delta = t - tc;
            let piece = s.inputs.piece_from(tc);
            if s.config.metrics.road_holding()
                && !s.config.tire_contact.is_unilateral()
                && s.margin_at(tc, &xc, &piece)[0] < 0.0
            {
                holding.lost_time += delta;
            }
            return Accumulated {
                integral: std::array::from_fn(|i| {
                    base[i] + delta * (at_committed.value[i] + 0.5 * delta * at_committed.rate[i])
                }),
                holding,
                filter: s.filter_near(at, delta),
            };
        }
        let k = at.k;
        let w = s.filter_within_step(k, (tc, xc), &wc, t);
        let (stretch, _, _) =
            s.integral_within_step(k, (tc, xc), &wc, at_committed, t, (&x, &w), &mut holding);
        Accumulated {
            integral: add(base, stretch),
            holding,
            filter: w,
        }
    }

    /// `∫_{t_0}^{t} y² dt` of BA, SDD and TDD at time t with state x, the
    /// first three of [`Self::accumulated`]'s integral to the bit. The
    /// squares, at the committed point `at` and at t, are taken without
    /// the W_k filter's, which these three do not need, and neither the
    /// road-holding accumulators nor the filter state are carried to t.
    /// `inside`: t lies inside the step, neither on the committed point
    /// nor within a drift of it.
    pub(super) fn rms_integral(
        &self,
        s: &mut Stepping,
        at: &Committed,
        (t, x): (f64, State),
        inside: bool,
    ) -> [f64; 3] {
        let tc = at.time;
        let (base, squares) = if self.rms.samples == 0 {
            (self.integral.closed, self.integral.anchor)
        } else {
            let (k, xc) = (at.k, at.state);
            let piece = s.inputs.piece_from(tc);
            let at_node = s.squares_with(k, tc, &xc, None, (tc, xc), &piece);
            let base = self
                .integral
                .through_run(s.grid.step, &self.rms, &self.weighted, &at_node);
            (base, at_node)
        };
        if inside {
            // As in `accumulated`: the stretch from the committed point.
            let (k, xc) = (at.k, at.state);
            let (stretch, _, _) = s.stretch_integral(k, (tc, xc), None, squares, (t, &x), None);
            return std::array::from_fn(|i| base[i] + stretch[i]);
        }
        // As in `accumulated`: the committed point's integral, or its
        // Taylor series over a drift away from it.
        let delta = t - tc;
        std::array::from_fn(|i| {
            if t == tc {
                base[i]
            } else {
                base[i] + delta * (squares.value[i] + 0.5 * delta * squares.rate[i])
            }
        })
    }

    /// Closes the open run at node k (time t, state x, filter state w;
    /// `run` and `weighted`: its sums, node k included) and starts a new
    /// one there: `left` and `right` are the road pieces on either side of
    /// the node.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn close_run_at_node(
        &mut self,
        s: &mut Stepping,
        k: u64,
        (t, x, w): (f64, &State, &Filter),
        run: &mut RunningRms,
        weighted: &mut [f64; 2],
        left: &RoadPiece,
        right: &RoadPiece,
    ) {
        let at_left = if run.samples > 0 || left == right {
            Some(s.squares_at(k, t, x, w, (t, *x), left))
        } else {
            None
        };
        if let (true, Some(at_left)) = (run.samples > 0, at_left) {
            self.integral.closed = self
                .integral
                .through_run(s.grid.step, run, weighted, &at_left);
        }
        let at_right = match at_left {
            Some(at) if left == right => at,
            _ => s.squares_at(k, t, x, w, (t, *x), right),
        };
        self.integral.anchor_index = k;
        self.integral.anchor_time = t;
        self.integral.anchor = at_right;
        *run = RunningRms::default();
        *weighted = [0.0; 2];
    }

    /// Starts a new run at node k (time t, state x, filter state w) after
    /// `step_integral` over the step that ends there was added to the
    /// closed part (the history must already hold node k). `arrival`: the
    /// squares at the node from the left and the road piece they used,
    /// which serve from the right too when the node is not a road
    /// breakpoint.
    pub(super) fn restart_run_after_step(
        &mut self,
        s: &mut Stepping,
        k: u64,
        (t, x, w): (f64, &State, &Filter),
        step_integral: [f64; INTEGRALS],
        arrival: (Squares, RoadPiece),
    ) {
        self.integral.closed = add(self.integral.closed, step_integral);
        let piece = s.inputs.piece_from(t);
        let at_node = if piece == arrival.1 {
            arrival.0
        } else {
            s.squares_at(k, t, x, w, (t, *x), &piece)
        };
        self.start_run(k, t);
        self.integral.anchor = at_node;
    }

    /// After the external road input changed, or the tire's contact
    /// switched, at the committed point `at` (the anchor): the anchor's
    /// squares from the right, with the new input.
    pub(super) fn reanchor(&mut self, s: &mut Stepping, at: &Committed) {
        let (k, t, x, w) = (at.k, at.time, at.state, at.filter);
        let piece = s.inputs.piece_from(t);
        self.integral.anchor = s.squares_at(k, t, &x, &w, (t, x), &piece);
    }
}

#[cfg(test)]
pub(super) mod tests;
