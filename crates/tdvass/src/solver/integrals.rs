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
//!
//! This file holds the integrands ([`Squares`]), the kept integral
//! ([`SquareIntegral`]) and the integrals over a stretch inside a step,
//! which stepping computes from the exact partial steps
//! ([`Stepping::integral_within_step`], [`Stepping::integrate_split_step`]);
//! the observers (`observers`) close and read the runs.
//!
//! Layer: stepping (docs/architecture.md); it imports the solver's
//! `holding`, `stepping`, `system` and the crate's `metrics`, `model`,
//! `road`.

use super::holding::{Holding, deflection};
use super::stepping::Stepping;
use super::system::Filter;
use crate::metrics::RunningRms;
use crate::model::dynamics::Switch;
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

pub(super) fn add(a: [f64; INTEGRALS], b: [f64; INTEGRALS]) -> [f64; INTEGRALS] {
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

impl Stepping<'_> {
    /// Adds the stretch from `start` (state `x_start`) to `end` (state
    /// `x_end`) on `piece` to the road-holding accumulators, when they run:
    /// the time without contact of the bilateral tire (the margin's cubic,
    /// `Holding::add_interval`) and the largest |SDD| on it.
    fn hold_stretch(
        &mut self,
        holding: &mut Holding,
        (start, x_start): (f64, &State),
        (end, x_end): (f64, &State),
        piece: &RoadPiece,
    ) {
        if !self.config.metrics.road_holding() {
            return;
        }
        let (a, b) = (
            self.margin_at(start, x_start, piece),
            self.margin_at(end, x_end, piece),
        );
        if !self.config.tire_contact.is_unilateral() {
            holding.add_interval(start, end - start, a, b);
        }
        holding.add_deflection(
            end - start,
            deflection(&(*x_start).into()),
            deflection(&(*x_end).into()),
        );
    }

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
        let p = self.delayed_vector_at(k, t, from, x);
        let [road, road_rate] = self.inputs.road_at(piece, t);
        let forcing = self.forcing(piece);
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

    /// The contact margin `[g, g']` (the tire's side,
    /// [`Switching::side`](crate::model::dynamics::Switching::side)) at
    /// time `t` with state `x`, the road given by `piece`.
    pub(super) fn margin_at(&self, t: f64, x: &State, piece: &RoadPiece) -> [f64; 2] {
        self.modes.grid_step.switching.side(
            Switch::Tire,
            x.as_slice(),
            piece.value(t),
            piece.slope(t),
        )
    }

    /// [`Self::margin_at`], the harmonic road's `sin` and `cos` from the
    /// kept `sin_cos` (the same bits).
    pub(super) fn margin_kept(&mut self, t: f64, x: &State, piece: &RoadPiece) -> [f64; 2] {
        let [road, road_rate] = self.inputs.road_at(piece, t);
        let switching = &self.modes.grid_step.switching;
        switching.side(Switch::Tire, x.as_slice(), road, road_rate)
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
    pub(super) fn stretch_integral(
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
        let (start, at_start, x_start) = (from.0, at_from, from.1);
        if to <= start {
            let piece = self.inputs.road.piece(to);
            let at_to = self.squares_with(k, to, x_to, w_to.as_ref(), from, &piece);
            return (
                corrected_trapezoid(to - start, &at_start, &at_to),
                at_to,
                piece,
            );
        }
        let first = (at_start, x_start, [0.0; INTEGRALS], None);
        let (at_end, _, total, piece) = self.through_stretches(
            start,
            to,
            None,
            first,
            |s, start, stretch, (at_start, x_start, total, _)| {
                let (piece, end) = (stretch.piece, stretch.end);
                let (x_end, w_end) = if end == to {
                    (*x_to, w_to)
                } else {
                    (
                        s.integrate_within_step(k, from.0, from.1, end),
                        filter.map(|(w_from, _)| s.filter_within_step(k, from, w_from, end)),
                    )
                };
                let at_end = s.squares_with(k, end, &x_end, w_end.as_ref(), from, &piece);
                let total = add(total, corrected_trapezoid(end - start, &at_start, &at_end));
                if let Some(holding) = holding.as_deref_mut() {
                    s.hold_stretch(holding, (start, &x_start), (end, &x_end), &piece);
                }
                // The squares where the next stretch starts, on its piece.
                let at_next = if end == to {
                    at_end
                } else {
                    let next = s.inputs.piece_from(end);
                    s.squares_with(k, end, &x_end, w_end.as_ref(), from, &next)
                };
                (at_next, x_end, total, Some(piece))
            },
        );
        let piece = piece.expect("a stretch reaches `to`");
        (total, at_end, piece)
    }

    /// [`Self::squares_at`] with filter state `w`, or without one the
    /// squares of BA, SDD and TDD alone (the W_k filter's left at 0).
    pub(super) fn squares_with(
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
            let x_to = self.integrate_within_step(k, t, x, to);
            let w_to = self.filter_within_step(k, (t, x), &w, to);
            let (integral, at_end, piece) =
                self.integral_within_step(k, (t, x), &w, at_start, to, (&x_to, &w_to), holding);
            return (x_to, w_to, integral, at_end, piece);
        }
        let first = (x, w, at_start, [0.0; INTEGRALS], None);
        let (x_end, w_end, at_end, total, piece) = self.through_stretches(
            t,
            to,
            None,
            first,
            |s, start, stretch, (x_start, w_start, at, total, _)| {
                let (piece, end) = (stretch.piece, stretch.end);
                let x_end = s.integrate_within_step(k, start, x_start, end);
                let w_end = s.filter_within_step(k, (start, x_start), &w_start, end);
                let at_end = s.squares_at(k, end, &x_end, &w_end, (start, x_start), &piece);
                let total = add(total, corrected_trapezoid(end - start, &at, &at_end));
                s.hold_stretch(holding, (start, &x_start), (end, &x_end), &piece);
                // The squares where the next stretch starts: across the
                // breakpoint that ends this one.
                let at_next = if end == to {
                    at_end
                } else {
                    let next = s.inputs.piece_from(end);
                    s.across_breakpoint(at_end, end, &x_end, &piece, &next)
                };
                (x_end, w_end, at_next, total, Some(piece))
            },
        );
        let piece = piece.expect("a stretch reaches `to`");
        (x_end, w_end, total, at_end, piece)
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
}
