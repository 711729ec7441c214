//! The ISO 2631-1 W_k weighting of the body acceleration inside the precise
//! integration (only when [`super::Metrics::comfort`] is on).
//!
//! The realization of [`crate::comfort::wk_state_space`],
//! `ẇ = A_w w + b_w BA`, `a_w = c_w w` (8 states, m/s²), is driven by
//! `BA = c X + β_u u + β_g x_g` (row V_S of the solver's A, and the V_S
//! entries of b and e, which are zero in every variant). The plant and the
//! filter together form the block lower-triangular system
//!
//! ```text
//! d/dt [X]   [ A        0  ] [X]   [ b      ]       [ e      ]
//!      [w] = [ b_w c    A_w] [w] + [ b_w β_u] u  +  [ b_w β_g] x_g
//! ```
//!
//! with the same inputs as the plant alone (the delayed tire displacement
//! as a cubic, the road as a line or a sine), so one exponential of the
//! 22-dimensional augmented matrix (plant 6, delayed input 4, linear road
//! 2, harmonic road 2, filter 8) gives the filter's exact step
//! `w(a+δ) = Φ_ww w(a) + Φ_wx X(a) + Γ_wu p + Γ_wl q + Γ_wh z`
//! ([`super::operators::FilterRows`]). The plant keeps the matrices of its own
//! 14-dimensional exponential: turning the filter on changes no bit of the
//! plant's states or of the BA, SDD, TDD values.
//!
//! The filter starts from rest (`w(t_0) = 0`).

use super::Simulator;
use super::stepping::stepping;
use super::system::Filter;
use crate::model::State;

impl Simulator {
    /// The filter state at `committed_time + delta` for a `delta` within
    /// the snap tolerance: the fourth-order Taylor series of
    /// `ẇ = A_w w + b_w c X` with the plant's derivatives from
    /// [`Self::committed_derivatives`] (truncation below
    /// `(ν |delta|)^5 / 120` relative, ν the larger norm of A and A_w).
    pub(super) fn filter_near_committed(&mut self, delta: f64) -> Filter {
        let w = self.trajectory.committed_filter;
        let Some(coupling) = self.modes.coupling.clone() else {
            return Filter::zeros();
        };
        if delta == 0.0 {
            return w;
        }
        let plant = self.committed_derivatives(delta);
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

    /// `X, X', X'', X'''` at the committed point (the recursion of
    /// [`Self::state_near_committed`] at its highest order), for the
    /// filter's Taylor series; the road derivatives are those of the piece
    /// in force at `committed_time + delta`.
    fn committed_derivatives(&mut self, delta: f64) -> [State; 4] {
        let (k, t, x) = (
            self.trajectory.grid_index,
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let p = stepping!(self).delayed_vector_at(k, t, (t, x), &x);
        let road_piece = self.inputs.piece_from(t + delta);
        let piece = stepping!(self).forcing(&road_piece);
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
