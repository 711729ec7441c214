//! Running RMS values as time averages (Eq. (6) with the mean taken over
//! time): for y = BA, SDD, TDD,
//! `RMS(t) = sqrt( (1 / (t − t_0)) ∫_{t_0}^{t} y(s)² ds )`,
//! 0 at `t_0`, continuous in t, and independent of the internal grid.
//!
//! **How the integral of `f = y²` is kept.** Over a run of grid nodes
//! `t_a, …, t_n` across which f and f' are continuous, the trapezoid rule
//! with its Euler–Maclaurin end correction,
//! `∫_{t_a}^{t_n} f = h (f_a/2 + f_{a+1} + … + f_{n−1} + f_n/2) − h²/12 (f'_n − f'_a) + O(h⁴)`,
//! is fourth-order accurate: the next term, `h⁴/720 (f'''(t_n) − f'''(t_a))`,
//! sums the jumps of f''' over the run, which are O(h) each. The whole-step
//! loop keeps `Σ f_k` as it always did ([`RunningRms`]); the end terms are
//! added when the integral is read. Where f or f' may jump, the run is
//! closed: its integral moves into [`SquareIntegral::closed`] and a new run
//! starts there. That happens at a road breakpoint that falls on a grid
//! node (TDD has a kink there), and where an external road input changes.
//! A step with a road breakpoint inside it, and the stretch from the last
//! committed point to the current time, are integrated piece by piece
//! (split at the breakpoints) with the corrected trapezoid of each piece,
//! `∫_a^b f = (b − a)/2 (f_a + f_b) − (b − a)²/12 (f'_b − f'_a) + O((b − a)⁵)`,
//! from the exact dense output at the piece ends. f' comes from the exact
//! output derivatives, `d(y²)/dt = 2 y ẏ`.
//!
//! With the W_k filter on, `a_w²` and `a_w⁴` are integrated the same way
//! (for the RMS of a_w and the vibration dose value): a_w is a state
//! output of the filter, so it and its rate `ȧ_w = c_w (A_w w + b_w BA)`
//! are continuous everywhere, also across road breakpoints. Without the
//! filter these two integrals stay 0.
//!
//! With a delay shorter than the step (`0 < tau < h`), the delayed input's
//! second derivative jumps inside every step (at `t_k + tau`), so f''' does
//! too and the rule is third order there: the extra error is below
//! `h⁴ |Δf'''| / 384` per step.

use super::Simulator;
use super::holding::{Holding, deflection, margin};
use super::stepping::stepping;
use super::system::Filter;
use crate::metrics::{RmsValues, RunningRms};
use crate::model::{State, V_S, X_S, X_T};
use crate::road::RoadPiece;

/// Number of time integrals kept: `BA²`, `SDD²`, `TDD²`, `a_w²`, `a_w⁴`.
pub(crate) const INTEGRALS: usize = 5;
/// Index of `a_w²` among the integrals.
pub(crate) const WEIGHTED_SQUARE: usize = 3;
/// Index of `a_w⁴` among the integrals.
pub(crate) const WEIGHTED_FOURTH: usize = 4;

/// The integrands `f` and their rates at one instant: `y²` of BA, SDD,
/// TDD, and `a_w²`, `a_w⁴`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Squares {
    /// `f` (BA in (m/s²)², SDD and TDD in m², a_w² in (m/s²)², a_w⁴ in
    /// (m/s²)⁴).
    pub value: [f64; INTEGRALS],
    /// `df/dt` (`2 y ẏ` for the squares, `4 a_w³ ȧ_w`).
    pub rate: [f64; INTEGRALS],
}

impl Squares {
    /// From the outputs `y` and their rates `ẏ`, and `[a_w, ȧ_w]`.
    fn of(y: [f64; 3], rate: [f64; 3], weighted: [f64; 2]) -> Squares {
        let [a, a_rate] = weighted;
        let (square, square_rate) = (a * a, 2.0 * a * a_rate);
        let mut value = [0.0; INTEGRALS];
        let mut rates = [0.0; INTEGRALS];
        for i in 0..3 {
            value[i] = y[i] * y[i];
            rates[i] = 2.0 * y[i] * rate[i];
        }
        value[WEIGHTED_SQUARE] = square;
        rates[WEIGHTED_SQUARE] = square_rate;
        value[WEIGHTED_FOURTH] = square * square;
        rates[WEIGHTED_FOURTH] = 2.0 * square * square_rate;
        Squares { value, rate: rates }
    }
}

/// `∫_a^b f` over one smooth piece of signed length `b − a` from the values
/// and rates at its ends: `(b − a)/2 (f_a + f_b) − (b − a)²/12 (f'_b − f'_a)`
/// (exact for cubics; the error is `(b − a)⁵/720 max |f''''|`).
pub(crate) fn corrected_trapezoid(length: f64, a: &Squares, b: &Squares) -> [f64; INTEGRALS] {
    std::array::from_fn(|i| {
        0.5 * length * (a.value[i] + b.value[i]) - length * length / 12.0 * (b.rate[i] - a.rate[i])
    })
}

fn add(a: [f64; INTEGRALS], b: [f64; INTEGRALS]) -> [f64; INTEGRALS] {
    std::array::from_fn(|i| a[i] + b[i])
}

/// The closed part of `∫_{t_0} y² dt` and the anchor of the open run of
/// grid nodes whose `Σ y²` the whole-step loop keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SquareIntegral {
    /// `∫_{t_0}^{anchor_time} f dt` for BA², SDD², TDD², a_w², a_w⁴.
    pub closed: [f64; INTEGRALS],
    /// Grid index of the step that holds the anchor (the anchor is node
    /// `anchor_index` itself whenever the run holds nodes).
    pub anchor_index: u64,
    /// Time of the anchor (s).
    pub anchor_time: f64,
    /// `y²` and its rate at the anchor, taken from the right.
    pub anchor: Squares,
}

impl SquareIntegral {
    /// Starts at `t_0` with the squares there.
    pub fn new(start_time: f64, at_start: Squares) -> SquareIntegral {
        SquareIntegral {
            closed: [0.0; INTEGRALS],
            anchor_index: 0,
            anchor_time: start_time,
            anchor: at_start,
        }
    }

    /// `∫_{t_0}^{t_n} f` where node `t_n` ends the run (`run` holds
    /// `Σ f` of BA, SDD, TDD over the nodes after the anchor up to n,
    /// `weighted` those of a_w², a_w⁴, `last` the squares at `t_n` from the
    /// left). Without nodes in the run it is `closed`.
    pub fn through_run(
        &self,
        h: f64,
        run: &RunningRms,
        weighted: &[f64; 2],
        last: &Squares,
    ) -> [f64; INTEGRALS] {
        if run.samples == 0 {
            return self.closed;
        }
        std::array::from_fn(|i| {
            let sums = if i < 3 {
                run.sums_of_squares[i]
            } else {
                weighted[i - 3]
            };
            let sum = 0.5 * self.anchor.value[i] + sums - 0.5 * last.value[i];
            self.closed[i] + h * sum - h * h / 12.0 * (last.rate[i] - self.anchor.rate[i])
        })
    }
}

/// What has accumulated from `t_0` to the current time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Accumulated {
    /// `∫ f` of BA², SDD², TDD², a_w², a_w⁴.
    pub integral: [f64; INTEGRALS],
    /// Road holding and working space (the largest |SDD| over the
    /// committed points; the outputs add the current one).
    pub holding: Holding,
    /// The W_k filter state now (zero without the filter).
    pub filter: Filter,
}

/// RMS values from `∫ y²` over a duration (0 for a zero duration; a
/// rounding-negative integral counts as 0).
/// `integral` holds at least those of BA², SDD², TDD², in that order.
pub(crate) fn rms_from_integral(integral: &[f64], duration: f64) -> RmsValues {
    if duration <= 0.0 {
        return RmsValues::default();
    }
    let rms = |i: usize| (integral[i].max(0.0) / duration).sqrt();
    RmsValues {
        body_acceleration: rms(0),
        suspension_deflection: rms(1),
        tire_deflection: rms(2),
    }
}

impl Simulator {
    /// The integrands and their rates at time `t` of step k with state `x`
    /// and filter state `w`, the road given by `piece` (which side of a
    /// breakpoint is the caller's choice).
    pub(super) fn squares_at(
        &mut self,
        k: u64,
        t: f64,
        x: &State,
        w: &Filter,
        from: (f64, State),
        piece: &RoadPiece,
    ) -> Squares {
        let (y, rate) = self.performance_and_rates_at(k, t, x, from, piece);
        let weighted = match &self.modes.coupling {
            Some(coupling) => [coupling.weighted(w), coupling.weighted_rate(w, y[0])],
            None => [0.0; 2],
        };
        Squares::of(y, rate, weighted)
    }

    /// BA, SDD, TDD and their rates at time `t` of step k with state `x`,
    /// the road given by `piece` (see [`Self::squares_at`]).
    fn performance_and_rates_at(
        &mut self,
        k: u64,
        t: f64,
        x: &State,
        from: (f64, State),
        piece: &RoadPiece,
    ) -> ([f64; 3], [f64; 3]) {
        let p = stepping!(self).delayed_vector_at(k, t, from, x);
        let [road, road_rate] = self.inputs.road_at(piece, t);
        let forcing = stepping!(self).forcing(piece);
        let [drive, drive_rate] = self.inputs.road_at(&forcing, t);
        let b = self.modes.input_column;
        let dx = self.modes.solver_matrix * x + b * p[0] + self.plant.e * drive;
        let acceleration_rate = (self.modes.solver_matrix.row(V_S) * dx)[0]
            + b[V_S] * p[1]
            + self.plant.e[V_S] * drive_rate;
        let y = [
            self.plant.body_acceleration(x),
            x[X_S] - x[X_T],
            x[X_T] - road,
        ];
        let rate = [acceleration_rate, dx[X_S] - dx[X_T], dx[X_T] - road_rate];
        (y, rate)
    }

    /// The contact margin `[g, g']` ([`super::holding::margin`]) at time `t`
    /// with state `x`, the road given by `piece`.
    pub(super) fn margin_at(&self, t: f64, x: &State, piece: &RoadPiece) -> [f64; 2] {
        let x: [f64; 6] = (*x).into();
        margin(
            self.modes.grid_step.contact.limit,
            &x,
            piece.value(t),
            piece.slope(t),
        )
    }

    /// [`Self::margin_at`], the harmonic road's `sin` and `cos` from the
    /// kept `sin_cos` (the same bits).
    pub(super) fn margin_kept(&mut self, t: f64, x: &State, piece: &RoadPiece) -> [f64; 2] {
        let [road, road_rate] = self.inputs.road_at(piece, t);
        let x: [f64; 6] = (*x).into();
        margin(self.modes.grid_step.contact.limit, &x, road, road_rate)
    }

    /// `∫ f` over `[from.0, to]` inside grid step k (state `to_state` at
    /// `to`: plant and filter), split at road breakpoints, and the squares
    /// at `to` from the left with the road piece they used; `w_from`: the
    /// filter state at the start, `at_from`: the squares there from the
    /// right. The time without contact over the stretch is added to
    /// `holding`. A `to` before the start (by a snapped time drift) is one
    /// piece with a negative length (and no contact time).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn integral_within_step(
        &mut self,
        k: u64,
        from: (f64, State),
        w_from: &Filter,
        at_from: Squares,
        to: f64,
        to_state: (&State, &Filter),
        holding: &mut Holding,
    ) -> ([f64; INTEGRALS], Squares, RoadPiece) {
        let (x_to, w_to) = to_state;
        let filter = Some((w_from, w_to));
        self.stretch_integral(k, from, filter, at_from, (to, x_to), Some(holding))
    }

    /// [`Self::integral_within_step`] with the filter states optional:
    /// without them (`filter` `None`) the squares leave the W_k filter's
    /// out, so only `∫` BA², SDD², TDD² are meaningful (the same bits as
    /// with them), and without `holding` the road-holding accumulators are
    /// not carried.
    fn stretch_integral(
        &mut self,
        k: u64,
        from: (f64, State),
        filter: Option<(&Filter, &Filter)>,
        at_from: Squares,
        to: (f64, &State),
        mut holding: Option<&mut Holding>,
    ) -> ([f64; INTEGRALS], Squares, RoadPiece) {
        let (to, x_to) = to;
        let w_to = filter.map(|(_, w)| *w);
        let (mut start, mut at_start, mut x_start) = (from.0, at_from, from.1);
        if to <= start {
            let piece = self.inputs.road.piece(to);
            let at_to = self.squares_with(k, to, x_to, w_to.as_ref(), from, &piece);
            return (
                corrected_trapezoid(to - start, &at_start, &at_to),
                at_to,
                piece,
            );
        }
        let mut total = [0.0; INTEGRALS];
        loop {
            let super::pieces::Stretch { piece, end, .. } = self.inputs.stretch(start, to, None);
            let (x_end, w_end) = if end == to {
                (*x_to, w_to)
            } else {
                (
                    stepping!(self).integrate_within_step(k, from.0, from.1, end),
                    filter.map(|(w_from, _)| {
                        stepping!(self).filter_within_step(k, from, w_from, end)
                    }),
                )
            };
            let at_end = self.squares_with(k, end, &x_end, w_end.as_ref(), from, &piece);
            total = add(total, corrected_trapezoid(end - start, &at_start, &at_end));
            if let Some(holding) = holding.as_deref_mut()
                && self.config.metrics.road_holding()
            {
                let (a, b) = (
                    self.margin_at(start, &x_start, &piece),
                    self.margin_at(end, &x_end, &piece),
                );
                if !self.config.tire_contact.is_unilateral() {
                    holding.add_interval(start, end - start, a, b);
                }
                holding.add_deflection(
                    end - start,
                    deflection(&x_start.into()),
                    deflection(&x_end.into()),
                );
            }
            if end == to {
                return (total, at_end, piece);
            }
            let next = self.inputs.piece_from(end);
            at_start = self.squares_with(k, end, &x_end, w_end.as_ref(), from, &next);
            (start, x_start) = (end, x_end);
        }
    }

    /// [`Self::squares_at`] with filter state `w`, or without one the
    /// squares of BA, SDD and TDD alone (the W_k filter's left at 0).
    fn squares_with(
        &mut self,
        k: u64,
        t: f64,
        x: &State,
        w: Option<&Filter>,
        from: (f64, State),
        piece: &RoadPiece,
    ) -> Squares {
        match w {
            Some(w) => self.squares_at(k, t, x, w, from, piece),
            None => {
                let (y, rate) = self.performance_and_rates_at(k, t, x, from, piece);
                Squares::of(y, rate, [0.0; 2])
            }
        }
    }

    /// Grid step k from node `t` (state x, filter state w, squares
    /// `at_start` from the right) to node `to`, split inside by road
    /// breakpoints: the end state and filter state, `∫ f` over the step
    /// piece by piece, and the squares at `to` from the left with the last
    /// piece; the time without contact is added to `holding`. The pieces
    /// are integrated one after the other, each from the state the one
    /// before reached (the same operations as one
    /// [`Self::integrate_within_step`] over the step, so the end state is
    /// the same to the bit).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn integrate_split_step(
        &mut self,
        k: u64,
        t: f64,
        x: State,
        w: Filter,
        at_start: Squares,
        to: f64,
        holding: &mut Holding,
    ) -> (State, Filter, [f64; INTEGRALS], Squares, RoadPiece) {
        if self.grid.delay_inside_step() {
            // The end node enters the delayed input of the whole step.
            let x_to = stepping!(self).integrate_within_step(k, t, x, to);
            let w_to = stepping!(self).filter_within_step(k, (t, x), &w, to);
            let (integral, at_end, piece) =
                self.integral_within_step(k, (t, x), &w, at_start, to, (&x_to, &w_to), holding);
            return (x_to, w_to, integral, at_end, piece);
        }
        let mut total = [0.0; INTEGRALS];
        let (mut start, mut x_start, mut w_start, mut at) = (t, x, w, at_start);
        loop {
            let super::pieces::Stretch { piece, end, .. } = self.inputs.stretch(start, to, None);
            let x_end = stepping!(self).integrate_within_step(k, start, x_start, end);
            let w_end = stepping!(self).filter_within_step(k, (start, x_start), &w_start, end);
            let at_end = self.squares_at(k, end, &x_end, &w_end, (start, x_start), &piece);
            total = add(total, corrected_trapezoid(end - start, &at, &at_end));
            if self.config.metrics.road_holding() {
                let (a, b) = (
                    self.margin_at(start, &x_start, &piece),
                    self.margin_at(end, &x_end, &piece),
                );
                if !self.config.tire_contact.is_unilateral() {
                    holding.add_interval(start, end - start, a, b);
                }
                holding.add_deflection(
                    end - start,
                    deflection(&x_start.into()),
                    deflection(&x_end.into()),
                );
            }
            if end == to {
                return (x_end, w_end, total, at_end, piece);
            }
            let next = self.inputs.piece_from(end);
            at = self.across_breakpoint(at_end, end, &x_end, &piece, &next);
            (start, x_start, w_start) = (end, x_end, w_end);
        }
    }

    /// The squares at a road breakpoint `t` (state x) on the side of the
    /// piece `after`, from those on the side of `before`: x_g is continuous
    /// there, so only the rates move, by the jump of the road slope
    /// (`d TDD/dt` by its negative, `d BA/dt` through `e`; a_w and its rate
    /// are continuous).
    fn across_breakpoint(
        &self,
        before_side: Squares,
        t: f64,
        x: &State,
        before: &RoadPiece,
        after: &RoadPiece,
    ) -> Squares {
        let jump = after.slope(t) - before.slope(t);
        let mut squares = before_side;
        let tire = x[X_T] - after.value(t);
        squares.rate[2] -= 2.0 * tire * jump;
        let acceleration_gain = self.plant.e[V_S];
        if acceleration_gain != 0.0 {
            squares.rate[0] += 2.0 * self.plant.body_acceleration(x) * acceleration_gain * jump;
        }
        squares
    }

    /// `∫_{t_0} f` up to the committed point (the end of the open run).
    fn integral_to_committed(&mut self) -> ([f64; INTEGRALS], Squares) {
        if self.observers.rms.samples == 0 {
            return (
                self.observers.integral.closed,
                self.observers.integral.anchor,
            );
        }
        let (k, t, x) = (
            self.trajectory.grid_index,
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let w = self.trajectory.committed_filter;
        let piece = self.inputs.piece_from(t);
        let at_node = self.squares_at(k, t, &x, &w, (t, x), &piece);
        (
            self.observers.integral.through_run(
                self.grid.step,
                &self.observers.rms,
                &self.observers.weighted,
                &at_node,
            ),
            at_node,
        )
    }

    /// Everything accumulated from `t_0` to the current time t: `∫ f`, the
    /// road-holding accumulators (with the stretch from the committed
    /// point to t) and the filter state at t.
    pub(super) fn accumulated_now(&mut self) -> Accumulated {
        self.settle();
        let (base, at_committed) = self.integral_to_committed();
        let (tc, xc, wc) = (
            self.trajectory.committed_time,
            self.trajectory.committed_state,
            self.trajectory.committed_filter,
        );
        let (t, x) = (self.trajectory.current_time, self.trajectory.current_state);
        let mut holding = self.observers.holding;
        if t == tc {
            return Accumulated {
                integral: base,
                holding,
                filter: wc,
            };
        }
        if self.snaps(t, tc) {
            // A drift away from the committed point: its Taylor series,
            // `δ f + δ²/2 f'` (the next term, δ³/6 f'', is below 1e-30 of
            // the integral).
            let delta = t - tc;
            let piece = self.inputs.piece_from(tc);
            if self.config.metrics.road_holding()
                && !self.config.tire_contact.is_unilateral()
                && self.margin_at(tc, &xc, &piece)[0] < 0.0
            {
                holding.lost_time += delta;
            }
            return Accumulated {
                integral: std::array::from_fn(|i| {
                    base[i] + delta * (at_committed.value[i] + 0.5 * delta * at_committed.rate[i])
                }),
                holding,
                filter: self.filter_near_committed(delta),
            };
        }
        let k = self.trajectory.grid_index;
        let w = stepping!(self).filter_within_step(k, (tc, xc), &wc, t);
        let (stretch, _, _) =
            self.integral_within_step(k, (tc, xc), &wc, at_committed, t, (&x, &w), &mut holding);
        Accumulated {
            integral: add(base, stretch),
            holding,
            filter: w,
        }
    }

    /// `∫_{t_0}^{t} y² dt` of BA, SDD and TDD at the current time t, the
    /// first three of [`Self::accumulated_now`]'s integral to the bit. The
    /// squares, at the committed point and at t, are taken without the W_k
    /// filter's, which these three do not need, and neither the
    /// road-holding accumulators nor the filter state are carried to t.
    pub(super) fn rms_integral_now(&mut self) -> [f64; 3] {
        let (t, tc) = (self.trajectory.current_time, self.trajectory.committed_time);
        let inside = t != tc && !self.snaps(t, tc);
        if inside {
            self.settle();
        }
        let (base, at) = if self.observers.rms.samples == 0 {
            (
                self.observers.integral.closed,
                self.observers.integral.anchor,
            )
        } else {
            let (k, x) = (self.trajectory.grid_index, self.trajectory.committed_state);
            let piece = self.inputs.piece_from(tc);
            let at_node = self.squares_with(k, tc, &x, None, (tc, x), &piece);
            let base = self.observers.integral.through_run(
                self.grid.step,
                &self.observers.rms,
                &self.observers.weighted,
                &at_node,
            );
            (base, at_node)
        };
        if inside {
            // As in `accumulated_now`: the stretch from the committed point.
            let (k, xc, x) = (
                self.trajectory.grid_index,
                self.trajectory.committed_state,
                self.trajectory.current_state,
            );
            let (stretch, _, _) = self.stretch_integral(k, (tc, xc), None, at, (t, &x), None);
            return std::array::from_fn(|i| base[i] + stretch[i]);
        }
        // As in `accumulated_now`: the committed point's integral, or its
        // Taylor series over a drift away from it.
        let delta = t - tc;
        std::array::from_fn(|i| {
            if t == tc {
                base[i]
            } else {
                base[i] + delta * (at.value[i] + 0.5 * delta * at.rate[i])
            }
        })
    }

    /// The running RMS values at the current time.
    pub(super) fn rms_now(&mut self) -> RmsValues {
        let integral = self.rms_integral_now();
        rms_from_integral(
            &integral,
            self.trajectory.current_time - self.config.start_time,
        )
    }

    /// Closes the open run at node k (time t, state x, filter state w;
    /// `run` and `weighted`: its sums, node k included) and starts a new
    /// one there: `left` and `right` are the road pieces on either side of
    /// the node.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn close_run_at_node(
        &mut self,
        k: u64,
        t: f64,
        x: &State,
        w: &Filter,
        run: &mut RunningRms,
        weighted: &mut [f64; 2],
        left: &RoadPiece,
        right: &RoadPiece,
    ) {
        let at_left = if run.samples > 0 || left == right {
            Some(self.squares_at(k, t, x, w, (t, *x), left))
        } else {
            None
        };
        if let (true, Some(at_left)) = (run.samples > 0, at_left) {
            self.observers.integral.closed =
                self.observers
                    .integral
                    .through_run(self.grid.step, run, weighted, &at_left);
        }
        let at_right = match at_left {
            Some(at) if left == right => at,
            _ => self.squares_at(k, t, x, w, (t, *x), right),
        };
        self.observers.integral.anchor_index = k;
        self.observers.integral.anchor_time = t;
        self.observers.integral.anchor = at_right;
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
        k: u64,
        (t, x, w): (f64, &State, &Filter),
        step_integral: [f64; INTEGRALS],
        arrival: (Squares, RoadPiece),
    ) {
        self.observers.integral.closed = add(self.observers.integral.closed, step_integral);
        let piece = self.inputs.piece_from(t);
        let at_node = if piece == arrival.1 {
            arrival.0
        } else {
            self.squares_at(k, t, x, w, (t, *x), &piece)
        };
        self.observers.integral.anchor_index = k;
        self.observers.integral.anchor_time = t;
        self.observers.integral.anchor = at_node;
        self.observers.rms = RunningRms::default();
        self.observers.weighted = [0.0; 2];
    }

    /// Before the external road input changes at the current time: closes
    /// the run there. Returns the time from which the new input applies:
    /// the committed point when the current time snaps to it (a time drift
    /// is not a different time), else the current time, which then becomes
    /// the committed point (its filter state and road-holding accumulators
    /// with it).
    pub(super) fn close_run_for_input(&mut self) -> f64 {
        let (tc, t) = (self.trajectory.committed_time, self.trajectory.current_time);
        if self.snaps(t, tc) {
            let (closed, _) = self.integral_to_committed();
            self.observers.integral.closed = closed;
            self.observers.rms = RunningRms::default();
            self.observers.weighted = [0.0; 2];
            self.observers.integral.anchor_index = self.trajectory.grid_index;
            self.observers.integral.anchor_time = self.trajectory.committed_time;
        } else {
            self.close_run_here();
        }
        self.trajectory.committed_time
    }

    /// Closes the run at the current time, which becomes the committed
    /// point (its filter state and road-holding accumulators with it),
    /// however close to the committed point it is (a switch of the tire's
    /// contact, `solver::contact`).
    pub(super) fn close_run_here(&mut self) {
        self.settle();
        if self.trajectory.current_time == self.trajectory.committed_time {
            let (closed, _) = self.integral_to_committed();
            self.observers.integral.closed = closed;
        } else {
            let now = self.accumulated_now();
            self.observers.integral.closed = now.integral;
            self.observers.holding = now.holding;
            if self.config.metrics.road_holding() {
                self.observers
                    .holding
                    .add_node(&self.trajectory.current_state.into());
            }
            self.trajectory.committed_filter = now.filter;
            self.trajectory.committed_time = self.trajectory.current_time;
            self.trajectory.committed_state = self.trajectory.current_state;
        }
        self.observers.rms = RunningRms::default();
        self.observers.weighted = [0.0; 2];
        self.observers.integral.anchor_index = self.trajectory.grid_index;
        self.observers.integral.anchor_time = self.trajectory.committed_time;
    }

    /// After the external road input changed at the anchor: the anchor's
    /// squares from the right, with the new input.
    pub(super) fn reanchor_after_input(&mut self) {
        let (k, t, x) = (
            self.trajectory.grid_index,
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let w = self.trajectory.committed_filter;
        let piece = self.inputs.piece_from(t);
        self.observers.integral.anchor = self.squares_at(k, t, &x, &w, (t, x), &piece);
    }

    /// The state at `committed_time + delta` for a `delta` within the snap
    /// tolerance, by the Taylor series of the exact solution,
    /// `X^{(j+1)} = A X^{(j)} + b u^{(j)} + e x_g^{(j)}`, with the delayed
    /// input's derivatives from its cubic interpolant and the road's own.
    /// The order p (1 to 4) is the smallest whose truncation,
    /// `(ν |delta|)^{p+1} / (p+1)!` relative with `ν = ‖A‖_∞`, stays below
    /// 1e-17 (a drift of 1e-13 s needs p = 1; `h/1024` at the default step
    /// needs 4, for a truncation below 1e-17). Before a node (negative
    /// `delta`) the interpolant after the node is used; the delayed input
    /// is C¹ there, so that costs `delta² |Δu''| / 2`.
    pub(super) fn state_near_committed(&mut self, delta: f64) -> State {
        let (k, t, x) = (
            self.trajectory.grid_index,
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        if delta == 0.0 {
            return x;
        }
        let order = series_order(self.modes.solver_matrix_norm * delta.abs());
        let p = stepping!(self).delayed_vector_at(k, t, (t, x), &x);
        let road_piece = self.inputs.piece_from(t + delta);
        let piece = stepping!(self).forcing(&road_piece);
        let road = if order == 1 {
            [piece.value(t), 0.0, 0.0, 0.0]
        } else {
            piece.derivatives(t)
        };
        let b = self.modes.input_column;
        let (m, e) = (self.modes.solver_matrix, self.plant.e);
        let mut derivative = m * x + b * p[0] + e * road[0];
        let mut result = x + derivative * delta;
        let mut factor = delta;
        for j in 1..order {
            derivative = m * derivative + b * p[j] + e * road[j];
            factor *= delta / (j + 1) as f64;
            result += derivative * factor;
        }
        result
    }
}

/// The order of [`Simulator::state_near_committed`]'s series for `reach =
/// ‖A‖_∞ |delta|`: the smallest whose truncation stays below 1e-17.
pub(super) fn series_order(reach: f64) -> usize {
    match reach {
        r if r <= 4.4e-9 => 1,
        r if r <= 3.9e-6 => 2,
        r if r <= 1.2e-4 => 3,
        _ => 4,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::model::{Params, Performance, Variant};
    use crate::road::{RandomRoad, RoadSpec};
    use crate::solver::{DelayRegime, SimulationConfig, simulate};

    /// Gauss–Legendre nodes on [0, 1] and weights (5 points: exact for
    /// degree 9).
    const GAUSS_LEGENDRE: [(f64, f64); 5] = [
        (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
        (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
        (0.5, 0.284_444_444_444_444_44),
        (0.769_234_655_052_841_6, 0.239_314_335_249_683_23),
        (0.953_089_922_969_332, 0.118_463_442_528_094_54),
    ];

    /// `∫_{t_0}^{t_end} y²` by 5-point Gauss–Legendre on every grid step,
    /// split at the road breakpoints inside it, from the dense output of a
    /// separate simulator (an independent quadrature of the same solution).
    fn reference_integral(cfg: &SimulationConfig, t_end: f64) -> [f64; 3] {
        let mut probe = Simulator::new(cfg.clone()).unwrap();
        let mut breaks = Simulator::new(cfg.clone()).unwrap();
        let h = probe.grid.step;
        let mut total = [0.0; 3];
        let mut k = 0u64;
        let mut a = cfg.start_time;
        while a < t_end {
            let b = probe.grid_time(k + 1).min(t_end);
            let mut start = a;
            while start < b {
                let piece = breaks.inputs.piece_from(start);
                let end = if piece.end() < b && !breaks.coincide(piece.end(), b) {
                    piece.end()
                } else {
                    b
                };
                for (x, w) in GAUSS_LEGENDRE {
                    let t = start + x * (end - start);
                    probe.advance_to(t).unwrap();
                    let y = Performance::at(&probe.plant, &probe.state(), piece.value(t));
                    let y = [
                        y.body_acceleration,
                        y.suspension_deflection,
                        y.tire_deflection,
                    ];
                    for i in 0..3 {
                        total[i] += w * (end - start) * y[i] * y[i];
                    }
                }
                start = end;
            }
            assert!(b - a <= h * (1.0 + 1e-9));
            a = b;
            k += 1;
        }
        total
    }

    /// Configurations that reach the delay regimes, roads and states of
    /// the tests of this file (and of `deferred`).
    pub(in crate::solver) fn configs() -> Vec<(&'static str, SimulationConfig)> {
        let base = SimulationConfig::default();
        let iso = RoadSpec::Iso8608(RandomRoad {
            seed: 7,
            ..RandomRoad::default()
        });
        vec![
            ("TDVASS harmonic", base.clone()),
            (
                "CS ISO 8608 C seed 7",
                SimulationConfig {
                    variant: Variant::Cs,
                    road: iso.clone(),
                    ..base.clone()
                },
            ),
            (
                "TDVASS paper road (kinks on grid nodes)",
                SimulationConfig {
                    params: Params::with_controller(2528.0, 1.28e-4),
                    road: RoadSpec::PaperCompatible {
                        road: RandomRoad::default(),
                        sample_interval: 0.1,
                    },
                    ..base.clone()
                },
            ),
            (
                "TDVASS tau = 0.03, g = 20000, from a displaced state",
                SimulationConfig {
                    params: Params::with_controller(20000.0, 0.03),
                    initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
                    ..base.clone()
                },
            ),
            (
                "TDVASS delay inside the step, ISO road",
                SimulationConfig {
                    params: Params::with_controller(6000.0, 3.7e-5),
                    road: iso,
                    ..base
                },
            ),
        ]
    }

    #[test]
    fn time_average_matches_an_independent_quadrature() {
        for (name, cfg) in configs() {
            // An end time off the grid: the partial last step counts too.
            // The quadrature's own accuracy: a tolerance well below the
            // bound asked here.
            let cfg = SimulationConfig {
                tolerance: 1e-11,
                ..cfg
            };
            let t_end = 1.234_567;
            let mut sim = Simulator::new(cfg.clone()).unwrap();
            sim.advance_to(t_end).unwrap();
            let ours = sim.accumulated_now().integral;
            let reference = reference_integral(&cfg, t_end);
            for i in 0..3 {
                let error = (ours[i] - reference[i]).abs() / reference[i];
                eprintln!("{name}, output {i}: relative difference {error:.1e}");
                assert!(
                    error < 1e-9,
                    "{name}, output {i}: {} against {} ({error:e})",
                    ours[i],
                    reference[i]
                );
            }
            let rms = sim.rms();
            let expected = (reference[0] / t_end).sqrt();
            assert!((rms.body_acceleration - expected).abs() < 1e-9 * expected);
        }
    }

    #[test]
    fn rms_is_zero_at_the_start_and_continuous_in_time() {
        let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
        assert_eq!(sim.rms(), RmsValues::default());
        sim.advance_to(0.5).unwrap();
        let h = sim.grid.step;
        // Across a grid node, from inside the step before to inside the next.
        let node = sim.grid_time(sim.trajectory.grid_index + 1);
        let mut previous = None;
        for offset in [-0.3, -1e-6, 0.0, 1e-6, 0.3] {
            sim.advance_to(node + offset * h).unwrap();
            let now = sim.rms().body_acceleration;
            if let Some(before) = previous {
                let change: f64 = now - before;
                assert!(change.abs() < 1e-4 * now, "{offset}: {before} -> {now}");
            }
            previous = Some(now);
        }
    }

    #[test]
    fn objective_is_continuous_across_a_change_of_the_internal_grid() {
        // With the step bound 1e-3 s: tau just below 1e-3 lies inside the
        // step, 1e-3 is one whole step, 2e-3 two, and a hair more needs
        // three steps of 6.67e-4 s.
        let at = |tau: f64| {
            let cfg = SimulationConfig {
                params: Params::with_controller(5386.0, tau),
                max_internal_step: 1e-3,
                ..SimulationConfig::default()
            };
            let regime = Simulator::new(cfg.clone()).unwrap().grid().regime;
            (simulate(cfg, 15.0).unwrap().objective, regime)
        };
        let (j_inside, inside) = at(1e-3 * (1.0 - 1e-9));
        let (j_one, one) = at(1e-3);
        let (j_two, two) = at(2e-3);
        let (j_three, three) = at(2e-3 * (1.0 + 1e-9));
        assert!(
            matches!(inside, DelayRegime::InsideStep { .. }),
            "{inside:?}"
        );
        assert_eq!(one, DelayRegime::WholeSteps { m: 1 });
        assert_eq!(two, DelayRegime::WholeSteps { m: 2 });
        assert_eq!(three, DelayRegime::WholeSteps { m: 3 });
        for (a, b) in [(j_inside, j_one), (j_two, j_three)] {
            assert!((a - b).abs() < 1e-9 * a, "{a} against {b}");
        }
    }

    #[test]
    fn taylor_dense_output_near_a_node_matches_the_exact_step() {
        for (name, cfg) in configs() {
            let mut sim = Simulator::new(cfg).unwrap();
            sim.advance_to(0.7).unwrap();
            let k = sim.trajectory.grid_index;
            let (t, x) = (
                sim.trajectory.committed_time,
                sim.trajectory.committed_state,
            );
            assert_eq!(t, sim.grid_time(k));
            let h = sim.grid.step;
            for delta in [1e-13, 3e-11, h / 1024.0] {
                let series = sim.state_near_committed(delta);
                let exact = stepping!(sim).integrate_within_step(k, t, x, t + delta);
                let scale = exact.amax();
                let error = (series - exact).amax();
                assert!(
                    error < 1e-13 * scale,
                    "{name}, offset {delta}: {error:e} of {scale:e}"
                );
            }
        }
    }

    #[test]
    fn accumulated_communication_times_commit_the_same_nodes() {
        for (name, cfg) in configs() {
            for step in [1e-3, 1e-3 / 3.0, 7.3e-3] {
                let mut exact = Simulator::new(cfg.clone()).unwrap();
                let mut drifting = Simulator::new(cfg.clone()).unwrap();
                let mut t = 0.0;
                let mut worst_drift: f64 = 0.0;
                for i in 1..=(3.0 / step) as u64 {
                    t += step;
                    let t_exact = i as f64 * step;
                    worst_drift = worst_drift.max((t - t_exact).abs());
                    exact.advance_to(t_exact).unwrap();
                    drifting.advance_to(t).unwrap();
                    assert_eq!(
                        exact.trajectory.grid_index, drifting.trajectory.grid_index,
                        "{name}, step {step}, t = {t}"
                    );
                    let (a, b) = (exact.rms(), drifting.rms());
                    let rates = exact.output_derivatives();
                    for (u, v) in [
                        (a.body_acceleration, b.body_acceleration),
                        (a.suspension_deflection, b.suspension_deflection),
                        (a.tire_deflection, b.tire_deflection),
                    ] {
                        assert!((u - v).abs() <= 1e-12 * u, "{name}, {step}, {t}: {u} {v}");
                    }
                    let drift = (t - t_exact).abs();
                    let (x, y) = (exact.state(), drifting.state());
                    for j in 0..6 {
                        let allowed = 1e-12 * x.amax() + 2.0 * drift * rates.state[j].abs();
                        assert!((x[j] - y[j]).abs() <= allowed, "{name}, {step}, {t}, {j}");
                    }
                }
                assert!(worst_drift > 0.0 || step == 7.3e-3);
            }
        }
    }
}
