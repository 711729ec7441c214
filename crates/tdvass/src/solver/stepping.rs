//! Stepping: the integration of the plant (and of the W_k filter) from a
//! point inside a grid step to another point of the same step, by the
//! exact partial steps of [`super::dense`] over the stretches of
//! [`super::pieces`], and the node at the end of a step when the delay lies
//! inside it (a 2×2 solve).
//!
//! [`Stepping`] is a view of the simulator's configuration, plant, grid,
//! modes and inputs, taken for one call by [`stepping!`]: it reads the
//! committed point's grid index and the tire's mode, and changes only
//! caches (the dense table, the next node, the road's window and the
//! phases). It knows nothing of the trajectory's commits or of the
//! accumulators; the whole-step loop is `kernel`'s and
//! `whole_steps`'.
//!
//! Layer: stepping (docs/architecture.md); it imports the solver's
//! `config`, `dense`, `grid`, `inputs`, `linalg`, `modes`, `pieces`,
//! `system` and the crate's `model`, `road`.

use super::config::SimulationConfig;
use super::dense;
use super::grid::DelayGrid;
use super::inputs::Inputs;
use super::linalg::{self, hermite, hermite_matrix};
use super::modes::{Modes, NextNode};
use super::pieces::{self, Stretch};
use super::system::{DELAY_INPUT, Filter, tire_pick};
use crate::model::dynamics::{Mode, Switch, flight_input, folded_delay};
use crate::model::{Plant, State, V_T, X_T};
use crate::road::RoadPiece;
use nalgebra::{Matrix2, SMatrix, Vector2, Vector4};

/// A view of a simulator for stepping (see the module docs); `$sim` is the
/// simulator, borrowed field by field so that its trajectory and
/// observers stay free.
macro_rules! stepping {
    ($sim:expr) => {
        $crate::solver::stepping::Stepping {
            config: &$sim.config,
            plant: &$sim.plant,
            grid: $sim.grid,
            modes: &mut $sim.modes,
            inputs: &mut $sim.inputs,
            grid_index: $sim.trajectory.grid_index,
            mode: $sim.trajectory.mode,
        }
    };
}
pub(super) use stepping;

/// A committed point: its grid index, time (s), state and W_k filter
/// state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Committed {
    pub(super) k: u64,
    pub(super) time: f64,
    pub(super) state: State,
    pub(super) filter: Filter,
}

/// The order of [`Stepping::state_near`]'s series for `reach =
/// ‖A‖_∞ |delta|`: the smallest whose truncation stays below 1e-17.
pub(super) fn series_order(reach: f64) -> usize {
    match reach {
        r if r <= 4.4e-9 => 1,
        r if r <= 3.9e-6 => 2,
        r if r <= 1.2e-4 => 3,
        _ => 4,
    }
}

/// The parts of a simulator that stepping uses (see the module docs).
pub(super) struct Stepping<'a> {
    pub(super) config: &'a SimulationConfig,
    pub(super) plant: &'a Plant,
    pub(super) grid: DelayGrid,
    pub(super) modes: &'a mut Modes,
    pub(super) inputs: &'a mut Inputs,
    /// The grid index of the committed point.
    pub(super) grid_index: u64,
    /// The mode in force (the tire in contact or in flight).
    pub(super) mode: Mode,
}

impl Stepping<'_> {
    /// Whether times `a` and `b` are the same on this grid
    /// ([`pieces::coincide`]).
    fn coincide(&self, a: f64, b: f64) -> bool {
        pieces::coincide(a, b, self.grid.step)
    }

    /// The dense output of the mode in force, built at its first use.
    pub(super) fn dense_output(&mut self) -> &mut dense::DenseOutput {
        self.modes.dense_output(self.plant, &self.grid)
    }

    /// The augmented vector of a partial step from `at` ([`dense::augmented`]).
    pub(super) fn augmented(
        &mut self,
        x: &State,
        delayed: Option<&Vector4<f64>>,
        road: &RoadPiece,
        at: f64,
    ) -> dense::Augmented<1> {
        let k = self.grid_index;
        dense::augmented(x, delayed, road, at, || {
            self.inputs.harmonic_at(road, at, k)
        })
    }

    /// The exact map of a partial step of length `length` (quantized to
    /// 2^-40 h, see [`dense`]) applied to the augmented vectors `z`: the
    /// first 6 rows of `e^{M length} z`.
    pub(super) fn partial_step<const C: usize>(
        &mut self,
        length: f64,
        z: &dense::Augmented<C>,
    ) -> SMatrix<f64, 6, C> {
        let key = dense::offset_key(length, self.grid.step);
        self.dense_output().plant(key, z)
    }

    /// The one loop that advances inside a step: the stretches from `start`
    /// to `to` ([`Inputs::stretch`]: ending at road breakpoints, and at
    /// `switch` too when given), each handed to `each` with its start and
    /// the value carried so far; the value after the last stretch.
    #[inline(always)]
    pub(super) fn through_stretches<T>(
        &mut self,
        start: f64,
        to: f64,
        switch: Option<f64>,
        value: T,
        mut each: impl FnMut(&mut Self, f64, Stretch, T) -> T,
    ) -> T {
        let (mut start, mut value) = (start, value);
        loop {
            let stretch = self.inputs.stretch(start, to, switch);
            value = each(self, start, stretch, value);
            if stretch.end == to {
                return value;
            }
            start = stretch.end;
        }
    }

    /// Integrates from (a, x) to b, all inside grid step k, splitting at road
    /// breakpoints.
    pub(super) fn integrate_within_step(&mut self, k: u64, from: f64, x: State, to: f64) -> State {
        if self.grid.delay_inside_step() {
            if to == self.inputs.node_time(k + 1) {
                return self.inner_delay_next_node(k, from, x).0;
            }
            return self.integrate_inner_delay_to(k, from, x, to);
        }
        let step_start = self.inputs.node_time(k);
        self.through_stretches(from, to, None, x, |s, start, stretch, state| {
            let delayed = s
                .grid
                .resolves_delay()
                .then(|| s.inputs.delayed_input(k, start - step_start));
            let length = stretch.end - start;
            let drive = s.forcing(&stretch.piece);
            if s.coincide(length, s.grid.step) {
                s.modes
                    .full_step
                    .apply(&state, delayed.as_ref(), &drive, start)
            } else {
                let z = s.augmented(&state, delayed.as_ref(), &drive, start);
                s.partial_step(length, &z)
            }
        })
    }

    /// Delay inside the step ([`DelayRegime::InsideStep`](super::grid::DelayRegime::InsideStep)): the state at grid
    /// node k + 1 reached from (from, x) in step k, and that node's
    /// `(x_t, v_t)`, which the delayed input of `[t_k + tau, t_{k+1})`
    /// interpolates (a 2×2 solve; NaN if it is singular, which the
    /// divergence check reports).
    pub(super) fn inner_delay_next_node(
        &mut self,
        k: u64,
        from: f64,
        x: State,
    ) -> (State, [f64; 2]) {
        let mode = self.mode;
        if let Some(c) = &self.modes.next_node
            && (c.k, c.from.to_bits(), c.mode) == (k, from.to_bits(), mode)
            && c.state
                .iter()
                .zip(x.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        {
            return (c.node, c.end);
        }
        let (node, end) = self.solve_next_node(k, from, x);
        self.modes.next_node = Some(NextNode {
            k,
            from,
            state: x,
            mode,
            node,
            end,
        });
        (node, end)
    }

    /// [`Self::inner_delay_next_node`] without its cache.
    fn solve_next_node(&mut self, k: u64, from: f64, x: State) -> (State, [f64; 2]) {
        if let Some(node) = self.whole_step_from_node(k, from, &x) {
            return (node, [node[X_T], node[V_T]]);
        }
        let next = self.inputs.node_time(k + 1);
        let (state, sensitivity) = self.integrate_inner_delay(k, from, x, next);
        let pick = tire_pick();
        let end = (Matrix2::identity() - pick * sensitivity)
            .lu()
            .solve(&(pick * state))
            .unwrap_or(Vector2::repeat(f64::NAN));
        (state + sensitivity * end, [end[0], end[1]])
    }

    /// Node k + 1 by the whole-step map of the grid (the 2×2 solve folded
    /// in, as the whole-step loop takes it) from node k itself (time
    /// `from`, state `x`), when the step lies in one road piece and every
    /// switching element is in its first law (the wheel on the road; the
    /// grid's maps are that mode's); `None` otherwise.
    fn whole_step_from_node(&mut self, k: u64, from: f64, x: &State) -> Option<State> {
        if from != self.inputs.node_time(k) || self.mode != Mode::CONTACT {
            return None;
        }
        #[cfg(test)]
        if dense::tests::EXACT.get() {
            // The reference of the tests solves for the node as before.
            return None;
        }
        let next = self.inputs.node_time(k + 1);
        let piece = self.inputs.piece_from(from);
        if pieces::ends_before(&piece, next, self.grid.step) {
            return None;
        }
        let nodes = self.inputs.delayed_nodes(k);
        let road = match piece {
            RoadPiece::Harmonic { .. } => {
                let phase = self.inputs.node_phase(k);
                linalg::combine2(&self.modes.grid_step.harmonic, &phase)
            }
            RoadPiece::Linear { .. } => linalg::combine2(
                &self.modes.grid_step.linear,
                &[piece.value(from), piece.slope(from)],
            ),
        };
        let step = &self.modes.grid_step;
        let inputs = linalg::add6(linalg::combine4(&step.nodes, &nodes), road);
        let x: [f64; 6] = (*x).into();
        Some(State::from(linalg::add6(
            linalg::combine6(&step.transition, &x),
            inputs,
        )))
    }

    /// Delay inside the step: integrates from (from, x) to `to` inside grid
    /// step k, splitting at road breakpoints and at `t_k + tau`, with node
    /// k + 1 taken as zero in the delayed input. Returns that state and its
    /// 6×2 sensitivity to node k + 1's `(x_t, v_t)` (the result is affine
    /// in them).
    fn integrate_inner_delay(
        &mut self,
        k: u64,
        from: f64,
        x: State,
        to: f64,
    ) -> (State, SMatrix<f64, 6, 2>) {
        let (h, tau) = (self.grid.step, self.grid.inner_delay());
        let step_start = self.inputs.node_time(k);
        let switch = step_start + tau;
        let [node_x, node_v] = self.inputs.node_tire(k);
        let at_rest = (x, SMatrix::<f64, 6, 2>::zeros());
        self.through_stretches(
            from,
            to,
            Some(switch),
            at_rest,
            |s, start, stretch, (state, sensitivity)| {
                let piece = s.forcing(&stretch.piece);
                // The state and the two columns of its sensitivity, in one
                // application of the partial step.
                let mut z = dense::Augmented::<3>::zeros();
                z.fixed_view_mut::<6, 2>(0, 1).copy_from(&sensitivity);
                let delayed = if stretch.before_switch {
                    s.inputs.delayed_input(k, h - tau + (start - step_start))
                } else {
                    let interpolant = hermite_matrix(h, (start - switch).max(0.0));
                    z.fixed_view_mut::<4, 2>(DELAY_INPUT, 1)
                        .copy_from(&interpolant.fixed_view::<4, 2>(0, 2));
                    interpolant * Vector4::new(node_x, node_v, 0.0, 0.0)
                };
                z.set_column(0, &s.augmented(&state, Some(&delayed), &piece, start));
                let next = s.partial_step(stretch.end - start, &z);
                (
                    next.column(0).into_owned(),
                    next.fixed_columns::<2>(1).into_owned(),
                )
            },
        )
    }

    /// Delay inside the step: the state at `to` in grid step k from
    /// (from, x), split as [`Self::integrate_inner_delay`] (the same value,
    /// with node k + 1's `(x_t, v_t)` from [`Self::inner_delay_next_node`]
    /// in the delayed input instead of through the sensitivity: one vector
    /// per piece instead of three). That node is found only for a piece
    /// after `t_k + tau`: a point before it does not need it.
    fn integrate_inner_delay_to(&mut self, k: u64, from: f64, x: State, to: f64) -> State {
        let (h, tau) = (self.grid.step, self.grid.inner_delay());
        let step_start = self.inputs.node_time(k);
        let switch = step_start + tau;
        let [node_x, node_v] = self.inputs.node_tire(k);
        self.through_stretches(from, to, Some(switch), x, |s, start, stretch, state| {
            let piece = s.forcing(&stretch.piece);
            let delayed = if stretch.before_switch {
                s.inputs.delayed_input(k, h - tau + (start - step_start))
            } else {
                let (_, [end_x, end_v]) = s.inner_delay_next_node(k, from, x);
                hermite([node_x, node_v, end_x, end_v], h, (start - switch).max(0.0))
            };
            let z = s.augmented(&state, Some(&delayed), &piece, start);
            s.partial_step(stretch.end - start, &z)
        })
    }

    /// The W_k filter state at `to` inside grid step k, from the point
    /// `from` (time and plant state) of step k with filter state `w`:
    /// the exact filter step of each piece (split at road breakpoints and,
    /// when the delay lies inside the step, at `t_k + tau`), with the plant
    /// state carried along the same pieces. Zero without the filter.
    pub(super) fn filter_within_step(
        &mut self,
        k: u64,
        from: (f64, State),
        w: &Filter,
        to: f64,
    ) -> Filter {
        if self.modes.coupling.is_none() {
            return Filter::zeros();
        }
        let switch = self
            .grid
            .delay_inside_step()
            .then(|| self.inputs.node_time(k) + self.grid.inner_delay());
        let start_point = (from.1, *w);
        let (_, w) = self.through_stretches(
            from.0,
            to,
            switch,
            start_point,
            |s, start, stretch, (x, w)| {
                let delayed = s
                    .grid
                    .resolves_delay()
                    .then(|| s.delayed_vector_at(k, start, from, &x));
                let length = stretch.end - start;
                let drive = s.forcing(&stretch.piece);
                if s.coincide(length, s.grid.step) {
                    let op = &s.modes.full_step;
                    let rows = op.filter.as_ref().expect("the filter is on");
                    let w = rows.apply(&w, &x, delayed.as_ref(), &drive, start);
                    (op.apply(&x, delayed.as_ref(), &drive, start), w)
                } else {
                    // The plant's state by the same operations as
                    // `integrate_within_step`, the filter's from its own
                    // rows.
                    let z = s.augmented(&x, delayed.as_ref(), &drive, start);
                    let w = s.partial_filter_step(length, &z, &w);
                    (s.partial_step(length, &z), w)
                }
            },
        );
        w
    }

    /// The W_k filter state after a partial step of length `length` from
    /// the plant's augmented vector `z` and the filter state `w`
    /// ([`super::dense`]).
    fn partial_filter_step(
        &mut self,
        length: f64,
        z: &super::dense::Augmented<1>,
        w: &Filter,
    ) -> Filter {
        let key = super::dense::offset_key(length, self.grid.step);
        self.dense_output();
        match (self.modes.dense.as_mut(), self.modes.coupling.as_ref()) {
            (Some(dense), Some(coupling)) => dense.filter(key, z, w, coupling),
            _ => Filter::zeros(),
        }
    }

    /// `[u, u', u'', u''']` of the delayed tire displacement at time `t` in
    /// grid step k, state `x` there; `from` is a point of step k with its
    /// state, from which the step's end node is found when the delay lies
    /// inside the step. With the delay folded into the plant only `[u, u']`
    /// are meaningful (`u = x_t − tau v_t`; the solver has no delayed input).
    pub(super) fn delayed_vector_at(
        &mut self,
        k: u64,
        t: f64,
        from: (f64, State),
        x: &State,
    ) -> Vector4<f64> {
        let offset = t - self.inputs.node_time(k);
        if self.grid.delay_inside_step() {
            let (h, tau) = (self.grid.step, self.grid.inner_delay());
            if offset < tau {
                self.inputs.delayed_input(k, h - tau + offset)
            } else {
                let (_, [end_x, end_v]) = self.inner_delay_next_node(k, from.0, from.1);
                let [node_x, node_v] = self.inputs.node_tire(k);
                hermite([node_x, node_v, end_x, end_v], h, offset - tau)
            }
        } else if self.grid.resolves_delay() {
            self.inputs.delayed_input(k, offset)
        } else {
            let tau = if self.config.variant.has_control() {
                self.config.params.tau
            } else {
                0.0
            };
            let piece = self.inputs.piece_from(t);
            let xg = self.forcing(&piece).value(t);
            let dx = self.modes.solver_matrix * x + self.plant.e * xg;
            Vector4::new(folded_delay(x, tau), folded_delay(&dx, tau), 0.0, 0.0)
        }
    }

    /// What drives the plant through its road column `e` over `piece`: the
    /// road in contact, the constant `−W/k_t` in flight (see the module
    /// docs).
    #[inline]
    pub(super) fn forcing(&self, piece: &RoadPiece) -> RoadPiece {
        if self.mode.is(Switch::Tire) {
            RoadPiece::Linear {
                start: 0.0,
                end: piece.end(),
                value: flight_input(self.modes.grid_step.switching.tire_limit),
                slope: 0.0,
            }
        } else {
            *piece
        }
    }

    /// The state at `t + delta` (grid index k, state x at t: the committed
    /// point) for a `delta` within the snap
    /// tolerance, by the Taylor series of the exact solution,
    /// `X^{(j+1)} = A X^{(j)} + b u^{(j)} + e x_g^{(j)}`, with the delayed
    /// input's derivatives from its cubic interpolant and the road's own.
    /// The order p (1 to 4) is the smallest whose truncation,
    /// `(ν |delta|)^{p+1} / (p+1)!` relative with `ν = ‖A‖_∞`, stays below
    /// 1e-17 (a drift of 1e-13 s needs p = 1; `h/1024` at the default step
    /// needs 4, for a truncation below 1e-17). Before a node (negative
    /// `delta`) the interpolant after the node is used; the delayed input
    /// is C¹ there, so that costs `delta² |Δu''| / 2`.
    #[inline(always)]
    pub(super) fn state_near(&mut self, (k, t, x): (u64, f64, &State), delta: f64) -> State {
        let x = *x;
        if delta == 0.0 {
            return x;
        }
        let order = series_order(self.modes.solver_matrix_norm * delta.abs());
        let p = self.delayed_vector_at(k, t, (t, x), &x);
        let road_piece = self.inputs.piece_from(t + delta);
        let piece = self.forcing(&road_piece);
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

    /// The filter state at `at.time + delta` for a `delta` within
    /// the snap tolerance: the fourth-order Taylor series of
    /// `ẇ = A_w w + b_w c X` with the plant's derivatives from
    /// [`Self::derivatives_at`] (truncation below
    /// `(ν |delta|)^5 / 120` relative, ν the larger norm of A and A_w).
    pub(super) fn filter_near(&mut self, at: &Committed, delta: f64) -> Filter {
        let w = at.filter;
        let Some(coupling) = self.modes.coupling.clone() else {
            return Filter::zeros();
        };
        if delta == 0.0 {
            return w;
        }
        let plant = self.derivatives_at((at.k, at.time, &at.state), delta);
        let (a_w, b_w) = (&coupling.wk.state_matrix, &coupling.wk.input_vector);
        let acceleration = |x: &State| (coupling.acceleration_row * x)[0];
        let mut derivative = a_w * w + b_w * acceleration(&plant[0]);
        let mut result = w + derivative * delta;
        let mut factor = delta;
        for (j, x) in plant.iter().enumerate().skip(1) {
            derivative = a_w * derivative + b_w * acceleration(x);
            factor *= delta / (j + 1) as f64;
            result += derivative * factor;
        }
        result
    }

    /// `X, X', X'', X'''` at the committed point (grid index k, time t,
    /// state x; the recursion of
    /// [`Self::state_near`] at its highest order), for the filter's Taylor
    /// series; the road derivatives are those of the piece in force at
    /// `t + delta`.
    fn derivatives_at(&mut self, (k, t, x): (u64, f64, &State), delta: f64) -> [State; 4] {
        let x = *x;
        let p = self.delayed_vector_at(k, t, (t, x), &x);
        let road_piece = self.inputs.piece_from(t + delta);
        let piece = self.forcing(&road_piece);
        let road = piece.derivatives(t);
        let b = self.modes.input_column;
        let (m, e) = (self.modes.solver_matrix, self.plant.e);
        let mut out = [x; 4];
        for j in 1..4 {
            out[j] = m * out[j - 1] + b * p[j - 1] + e * road[j - 1];
        }
        out
    }
}
