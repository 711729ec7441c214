//! A current state found when first asked for.
//!
//! `Simulator::advance_to` ends at a time `t` that is either a grid node
//! (its state comes with the step), within the snap tolerance of the
//! committed node (the state by [`Stepping::state_near`](super::stepping::Stepping::state_near)), or
//! inside a step (the state by the exact partial steps of
//! [`super::dense`]). The last two cost more than the whole step itself,
//! and a master often does not ask for the state at every communication
//! point (a getter of the time averages does not need it). So the
//! simulator may defer it: `current_state` then holds the committed state
//! and `Simulator::settle` computes the state at `t` when it is first
//! needed (the state, the outputs, a change of the operators or of the
//! road), by the same function of the same values (the committed point,
//! the step, the history and the road do not change before it), so the
//! result is the same to the bit. The saved bytes keep it deferred: they
//! hold what finds it (format 7), and a restored simulator finds it
//! when first asked, from the same values again.
//!
//! **The divergence check.** `advance_to` checks the state at `t`. A
//! deferred state is shown to pass it by bounds of `|x_i(t) − x_c,i|`
//! (`x_c` the committed state): `|x_c,i|` plus the bound at most half of
//! the divergence bound. Where a bound is not available or too large, the
//! state is computed at once and checked, as before.
//!
//! - Near the node ([`Stepping::drift_bounds`]): the terms of the Taylor
//!   series.
//! - Inside a step ([`Stepping::inside_bounds`]): with `y = x − x_c`,
//!   `y' = A y + f`, `f = A x_c + b u + e x_g`, `y(0) = 0`, and a diagonal
//!   `D` of powers of two balancing A (`ν = ‖D⁻¹ A D‖_∞`),
//!
//!   ```text
//!   ‖D⁻¹ y(s)‖_∞ ≤ ∫_0^s e^{ν (s − r)} dr · max ‖D⁻¹ f‖_∞
//!               ≤ s (1 + ν s + (ν s)²) (‖D⁻¹ A x_c‖_∞ + U ‖D⁻¹ b‖_∞ + G ‖D⁻¹ e‖_∞)
//!   ```
//!
//!   for `ν s ≤ 1` (`e^θ ≤ 1 + θ + θ²` there), U and G bounds of `|u|` and
//!   `|x_g|` over the stretch: [`hermite_bound`] of the cubics of the
//!   delayed input it uses, `|A|` on the harmonic road, the larger end
//!   value on a linear piece (a stretch across a road breakpoint is not
//!   deferred). The factor 1.01 and an absolute `1e-9` of the values
//!   involved cover the rounding of the exact partial steps (1.5e-14 of
//!   the largest value in the tests of `dense`).
//!
//! **The contact-loss test** of the stretch from the committed point
//! (`Simulator::first_contact_loss`) runs on the same bounds: its
//! evaluation is monotone in the end point's `x_t` and `|v_t|`, so a
//! stretch that passes with the bounds passes with the state; otherwise
//! the state is computed and the exact test runs.
//!
//! Layer: stepping (docs/architecture.md); it imports the solver's
//! `linalg`, `stepping` and the crate's `road`.

use super::linalg::{hermite_bound, scaled_norm};
use super::stepping::{Stepping, series_order};
use crate::model::State;
use crate::road::RoadPiece;

/// What finds a deferred state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// [`Stepping::state_near`](super::stepping::Stepping::state_near).
    NearNode,
    /// [`Stepping::integrate_within_step`](super::stepping::Stepping::integrate_within_step)
    /// from the committed point.
    InsideStep,
}

impl Kind {
    /// The byte a saved state holds for `deferral` (0: the state is
    /// computed).
    pub(super) fn code(deferral: Option<Kind>) -> u8 {
        match deferral {
            None => 0,
            Some(Kind::NearNode) => 1,
            Some(Kind::InsideStep) => 2,
        }
    }

    /// The deferral of [`Kind::code`]'s byte (`None` for an unknown one).
    pub(super) fn from_code(code: u8) -> Option<Option<Kind>> {
        match code {
            0 => Some(None),
            1 => Some(Some(Kind::NearNode)),
            2 => Some(Some(Kind::InsideStep)),
            _ => None,
        }
    }
}

/// A deferred current state: what finds it and bounds of `|x_i − x_c,i|`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Deferred {
    pub(super) kind: Kind,
    pub(super) drift: [f64; 6],
}

impl Stepping<'_> {
    /// Bounds of `|x_i − x_c,i|` for the state x that
    /// [`Stepping::state_near`](super::stepping::Stepping::state_near) gives at `delta` from the committed
    /// point `x_c` when that point is grid node k (`None` elsewhere).
    ///
    /// Its series of order p is `x = x_c + Σ_{j=1..p} delta^j/j! d_j`,
    /// `d_j = A d_{j−1} + b u^{(j−1)} + e x_g^{(j−1)}`, `d_0 = x_c`, so
    /// `|d_j,i| ≤ ν D_{j−1} + |b_i| U_{j−1} + |e_i| R_{j−1}` with `ν =
    /// ‖A‖_∞`, `D_j` the bound of `‖d_j‖_∞` that follows, `R_j` bounds of
    /// the road's derivatives (`|A| ω^j` on the harmonic road; the value
    /// and the slope on a linear piece) and `U_j` bounds of the delayed
    /// input's over the whole Hermite cubic of the nodes `(x_0, v_0)`,
    /// `(x_1, v_1)` (s = offset/h in [0, 1], from the ranges of the basis
    /// functions and their derivatives):
    ///
    /// ```text
    /// U_0 = max(|x_0|, |x_1|) + 4/27 h (|v_0| + |v_1|)
    /// U_1 = 3/2 |x_1 − x_0|/h + |v_0| + |v_1|
    /// U_2 = (6 |x_1 − x_0|/h + 4 (|v_0| + |v_1|)) / h
    /// U_3 = (12 |x_1 − x_0|/h + 6 (|v_0| + |v_1|)) / h²
    /// ```
    ///
    /// The sum is bounded with `|delta|^j` for `|delta|^j/j!`; the
    /// factor 1.001 and `4 ε |x_c,i|` cover the rounding of the series.
    #[inline]
    pub(super) fn drift_bounds(
        &mut self,
        (k, t, x): (u64, f64, &State),
        delta: f64,
    ) -> Option<[f64; 6]> {
        if t != self.inputs.node_time(k) {
            return None;
        }
        let norm = self.modes.solver_matrix_norm;
        let order = series_order(norm * delta.abs());
        let h = self.grid.step;
        let nodes = self.inputs.delayed_nodes(k);
        let [x0, v0, x1, v1] = nodes;
        let mut input = [hermite_bound(nodes, h), 0.0, 0.0, 0.0];
        if order > 1 {
            let (rise, slopes) = ((x1 - x0).abs() / h, v0.abs() + v1.abs());
            input[1] = 1.5 * rise + slopes;
            input[2] = (6.0 * rise + 4.0 * slopes) / h;
            input[3] = (12.0 * rise + 6.0 * slopes) / (h * h);
        }
        let road_piece = self.inputs.piece_from(t + delta);
        let road = self.forcing(&road_piece).derivative_bounds(t);
        let (b, e) = (self.modes.input_column, self.plant.e);
        let (b_max, e_max) = (b.amax(), e.amax());
        let mut previous = x.amax();
        let mut bounds = [0.0; 6];
        let mut factor = 1.0;
        for j in 0..order {
            factor *= delta.abs();
            for (i, bound) in bounds.iter_mut().enumerate() {
                *bound += factor * (norm * previous + b[i].abs() * input[j] + e[i].abs() * road[j]);
            }
            previous = norm * previous + b_max * input[j] + e_max * road[j];
        }
        Some(std::array::from_fn(|i| {
            1.001 * bounds[i] + 4.0 * f64::EPSILON * x[i].abs()
        }))
    }

    /// Bounds of `|x_i − x_c,i|` over the stretch from the committed point
    /// to `t` inside its step (see the module docs); `None` where the
    /// stretch crosses a road breakpoint or `ν (t − t_c) > 1`.
    #[inline]
    pub(super) fn inside_bounds(
        &mut self,
        (k, tc, xc): (u64, f64, &State),
        t: f64,
    ) -> Option<[f64; 6]> {
        let length = t - tc;
        let road_piece = self.inputs.piece_from(tc);
        if length.is_nan() || length <= 0.0 || road_piece.end() < t {
            return None;
        }
        let road = match self.forcing(&road_piece) {
            RoadPiece::Harmonic { amplitude, .. } => amplitude.abs(),
            piece @ RoadPiece::Linear { .. } => piece.value(tc).abs().max(piece.value(t).abs()),
        };
        let scaling = self.dense_output().scaling;
        let theta = scaling.norm * length;
        if theta.is_nan() || theta > 1.0 {
            return None;
        }
        let h = self.grid.step;
        let input = if scaling.input == 0.0 {
            0.0
        } else {
            let mut bound = hermite_bound(self.inputs.delayed_nodes(k), h);
            if self.grid.delay_inside_step()
                && t > self.inputs.node_time(k) + self.grid.inner_delay()
            {
                // The piece after t_k + tau interpolates node k and the
                // step's end node.
                let (_, [end_x, end_v]) = self.inner_delay_next_node(k, tc, *xc);
                let [node_x, node_v] = self.inputs.node_tire(k);
                bound = bound.max(hermite_bound([node_x, node_v, end_x, end_v], h));
            }
            bound
        };
        let pull = self.modes.solver_matrix * xc;
        let forcing =
            scaled_norm(&scaling.diagonal, &pull) + input * scaling.input + road * scaling.road;
        let growth = length * (1.0 + theta + theta * theta) * forcing;
        let bounds: [f64; 6] = std::array::from_fn(|i| 1.01 * scaling.diagonal[i] * growth);
        let cushion =
            1e-9 * (xc.amax() + bounds.iter().fold(0.0f64, |m, b| m.max(*b)) + input + road);
        Some(bounds.map(|b| b + cushion))
    }
}

#[cfg(test)]
mod tests {

    use crate::model::State;
    use crate::solver::SimulationConfig;
    use crate::solver::Simulator;
    use crate::solver::dense::tests::Lcg;
    use crate::solver::observers::tests::configs;
    use crate::solver::stepping::stepping;

    /// The configurations of the time-average tests and the unilateral
    /// tire in flight (the flight plant and its constant forcing).
    fn cases() -> Vec<(&'static str, SimulationConfig)> {
        let mut cases = configs();
        cases.push((
            "TDVASS unilateral tire, wheel starting 5 cm up",
            SimulationConfig {
                tire_contact: crate::model::TireContact::Unilateral,
                initial_state: State::new(0.0, 0.0, 0.0, 0.0, 0.05, 0.0),
                ..SimulationConfig::default()
            },
        ));
        cases
    }

    #[test]
    fn drift_bounds_hold_for_the_series_near_a_node() {
        let mut random = Lcg(3);
        for (name, cfg) in cases() {
            let mut sim = Simulator::new(cfg).unwrap();
            for end in [0.0, 0.013, 0.7] {
                sim.advance_to(end).unwrap();
                let (k, x) = (sim.trajectory.grid_index, sim.trajectory.committed_state);
                if sim.trajectory.committed_time != sim.grid_time(k) {
                    continue;
                }
                let limit = sim.snap_tolerance(sim.trajectory.committed_time);
                for _ in 0..200 {
                    // Offsets of every order of the series, both signs.
                    let delta = (2.0 * random.next() - 1.0) * limit * 1e-9f64.powf(random.next());
                    let series = stepping!(sim).state_near(sim.trajectory.committed_point(), delta);
                    let bounds = stepping!(sim)
                        .drift_bounds(sim.trajectory.committed_point(), delta)
                        .unwrap();
                    for i in 0..6 {
                        assert!(
                            (series[i] - x[i]).abs() <= bounds[i],
                            "{name}, t = {end}, delta {delta:e}, state {i}: {:e} > {:e}",
                            (series[i] - x[i]).abs(),
                            bounds[i]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn inside_bounds_hold_for_the_exact_partial_steps() {
        let mut random = Lcg(5);
        let mut used = 0;
        for (name, cfg) in cases() {
            let mut sim = Simulator::new(cfg).unwrap();
            for end in [0.0, 0.013, 0.7] {
                sim.advance_to(end).unwrap();
                let (k, tc, xc) = (
                    sim.trajectory.grid_index,
                    sim.trajectory.committed_time,
                    sim.trajectory.committed_state,
                );
                let next = sim.grid_time(k + 1);
                for _ in 0..100 {
                    let t = tc + (next - tc) * random.next();
                    let Some(bounds) =
                        stepping!(sim).inside_bounds(sim.trajectory.committed_point(), t)
                    else {
                        continue;
                    };
                    used += 1;
                    let x = stepping!(sim).integrate_within_step(k, tc, xc, t);
                    for i in 0..6 {
                        assert!(
                            (x[i] - xc[i]).abs() <= bounds[i],
                            "{name}, t = {t}, state {i}: {:e} > {:e}",
                            (x[i] - xc[i]).abs(),
                            bounds[i]
                        );
                    }
                }
            }
        }
        assert!(used > 1000, "{used} bounds");
    }

    #[test]
    fn a_deferred_state_inside_a_step_is_the_state_computed_at_once() {
        for (name, cfg) in cases() {
            let mut sim = Simulator::new(cfg).unwrap();
            let step = 0.37 * sim.grid.step;
            let mut deferred = 0;
            for i in 1..=400 {
                let t = i as f64 * step;
                sim.advance_to(t).unwrap();
                if sim.computed_state().is_none() {
                    deferred += 1;
                    same_as_at_once(name, &sim);
                }
            }
            assert!(deferred > 100, "{name}: {deferred} deferred");
        }
    }

    /// The state, the state restored from the saved bytes, the first loss
    /// of contact and the outputs of `sim` (its state deferred) are those
    /// of its state computed.
    fn same_as_at_once(name: &str, sim: &Simulator) {
        let t = sim.time();
        let mut settled = sim.clone();
        settled.settle();
        let bits = |x: State| x.map(f64::to_bits);
        assert_eq!(
            bits(sim.state()),
            bits(settled.trajectory.current_state),
            "{name}, t = {t}"
        );
        // Saved as it stands, and found after the restore.
        let bytes = sim.to_bytes();
        let restored = Simulator::from_bytes(&bytes).unwrap();
        assert!(restored.computed_state().is_none(), "{name}, t = {t}");
        assert_eq!(restored.to_bytes(), bytes, "{name}, t = {t}");
        assert_eq!(
            bits(restored.state()),
            bits(settled.trajectory.current_state),
            "{name}, t = {t}"
        );
        assert_eq!(
            sim.clone().first_contact_loss(),
            settled.clone().first_contact_loss(),
            "{name}, t = {t}"
        );
        let (a, b) = (sim.clone().outputs(), settled.outputs());
        assert_eq!(
            a.core_values().map(f64::to_bits),
            b.core_values().map(f64::to_bits),
            "{name}, t = {t}"
        );
    }

    #[test]
    fn a_deferred_state_is_the_state_computed_at_once() {
        for (name, cfg) in configs() {
            let mut sim = Simulator::new(cfg).unwrap();
            let mut t = 0.0;
            let (mut deferred, mut drifted) = (0, 0);
            let step = sim.grid.step;
            for _ in 0..400 {
                t += step;
                sim.advance_to(t).unwrap();
                let tc = sim.trajectory.committed_time;
                if t != tc && sim.snaps(t, tc) && tc == sim.grid_time(sim.trajectory.grid_index) {
                    drifted += 1;
                }
                if sim.computed_state().is_some() {
                    continue;
                }
                deferred += 1;
                let delta = t - sim.trajectory.committed_time;
                let at_once = {
                    let mut copy = sim.clone();
                    stepping!(copy).state_near(copy.trajectory.committed_point(), delta)
                };
                let bits = |x: State| x.map(f64::to_bits);
                assert_eq!(bits(sim.state()), bits(at_once), "{name}, t = {t}");
                same_as_at_once(name, &sim);
            }
            // Every time that drifted off a node is deferred.
            assert!(
                deferred == drifted && deferred > 10,
                "{name}: {deferred} deferred of {drifted}"
            );
        }
    }
}
