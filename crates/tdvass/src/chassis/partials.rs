//! The chassis's exact partials in Model Exchange: of the derivatives
//! ([`Chassis::rates`]) and of the outputs ([`Chassis::outputs`], the
//! attachment points) with respect to the continuous states and the four
//! corners' forces.
//!
//! The rigid body is linear: `z' = z'`, `q'' = G f` (`G` the generalized
//! accelerations per unit force, [`ChassisParams::accelerations`]), the
//! seat acceleration `s = S f` with `S = G_z + seat_x G_θ + seat_y G_φ`,
//! the W_k filter `w' = A_w w + b_w s`, `a_w = c_w w + d_w s`. The
//! integrands are squares and a fourth power of these: `∂(a²) = 2 a ∂a`,
//! `∂(a_w⁴) = 4 a_w³ ∂a_w`. A running RMS `sqrt(I / (t − t_0))` has the
//! partial `1 / (2 sqrt(I (t − t_0)))` with respect to its integral, and
//! the vibration dose value `I^{1/4}` the partial `I^{−3/4} / 4`, each
//! taken as 0 where the integral is 0 (their slope is unbounded there), as
//! the quarter car's.

use super::{
    CHASSIS_STATES, Chassis, ChassisParams, Corner, FILTER_AT, HEAVE, INTEGRALS_AT, PITCH, ROLL,
    WEIGHTED_FOURTH, WEIGHTED_SQUARE,
};
use crate::comfort::WK_STATES;
use crate::metrics::{dose_slope, rms_slope};

/// The partials of one value with respect to the chassis's continuous
/// states and the corners' forces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChassisGradient {
    /// `∂y/∂x_j`, in the order of [`Chassis::states`].
    pub states: [f64; CHASSIS_STATES],
    /// `∂y/∂f_c` (1/N), in the order of [`Corner::ALL`].
    pub forces: [f64; 4],
}

impl ChassisGradient {
    /// No dependence on anything.
    pub const ZERO: ChassisGradient = ChassisGradient {
        states: [0.0; CHASSIS_STATES],
        forces: [0.0; 4],
    };

    /// The gradient of the continuous state `j` itself.
    pub fn of_state(j: usize) -> ChassisGradient {
        let mut g = ChassisGradient::ZERO;
        g.states[j] = 1.0;
        g
    }

    fn scaled(mut self, factor: f64) -> ChassisGradient {
        self.states.iter_mut().for_each(|v| *v *= factor);
        self.forces.iter_mut().for_each(|v| *v *= factor);
        self
    }
}

/// The partials of the chassis's outputs (the attachment points by corner,
/// `[z, θ, φ]`, their rates are the states' own: [`ChassisGradient::of_state`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ChassisOutputPartials {
    /// Of each corner's attachment displacement, in [`Corner::ALL`] order.
    pub displacement: [ChassisGradient; 4],
    /// Of each corner's attachment velocity.
    pub velocity: [ChassisGradient; 4],
    /// Of `[z'', θ'', φ'']`.
    pub acceleration: [ChassisGradient; 3],
    pub seat_acceleration: ChassisGradient,
    /// Of the running RMS of `[z'', θ'', φ'']`.
    pub rms_acceleration: [ChassisGradient; 3],
    pub weighted_seat_acceleration: ChassisGradient,
    pub rms_weighted_seat_acceleration: ChassisGradient,
    pub seat_vibration_dose_value: ChassisGradient,
}

impl ChassisParams {
    /// `G`: `∂[z'', θ'', φ'']/∂f_c` by corner (the accelerations are
    /// linear in the forces).
    fn acceleration_per_force(&self) -> [[f64; 4]; 3] {
        let mut g = [[0.0; 4]; 3];
        for (c, _) in Corner::ALL.iter().enumerate() {
            let mut unit = [0.0; 4];
            unit[c] = 1.0;
            for (k, a) in self.accelerations(&unit).into_iter().enumerate() {
                g[k][c] = a;
            }
        }
        g
    }
}

impl Chassis {
    /// `∂[z'', θ'', φ'']`, `∂s` (the seat acceleration) and `∂a_w`.
    fn acceleration_gradients(&self) -> ([ChassisGradient; 3], ChassisGradient, ChassisGradient) {
        let p = &self.params;
        let g = p.acceleration_per_force();
        let acceleration = g.map(|forces| ChassisGradient {
            forces,
            ..ChassisGradient::ZERO
        });
        let seat = ChassisGradient {
            forces: std::array::from_fn(|c| {
                g[HEAVE][c] + p.seat_x * g[PITCH][c] + p.seat_y * g[ROLL][c]
            }),
            ..ChassisGradient::ZERO
        };
        let mut weighted = seat.scaled(self.wk.feedthrough);
        for k in 0..WK_STATES {
            weighted.states[FILTER_AT + k] = self.wk.output_vector[k];
        }
        (acceleration, seat, weighted)
    }

    /// The exact partials of [`Chassis::rates`] at the current states and
    /// forces: `[i]` is the gradient of the derivative of state i.
    pub fn jacobian(&self) -> [ChassisGradient; CHASSIS_STATES] {
        let (acceleration, seat, weighted) = self.acceleration_gradients();
        let values = self.params.accelerations(&self.forces);
        let seat_value =
            values[HEAVE] + self.params.seat_x * values[PITCH] + self.params.seat_y * values[ROLL];
        let a_w = self.wk.weighted_acceleration(&self.filter, seat_value);
        let mut rows = [ChassisGradient::ZERO; CHASSIS_STATES];
        for k in 0..3 {
            rows[k] = ChassisGradient::of_state(3 + k);
            rows[3 + k] = acceleration[k];
            rows[INTEGRALS_AT + k] = acceleration[k].scaled(2.0 * values[k]);
        }
        for i in 0..WK_STATES {
            let row = &mut rows[FILTER_AT + i];
            for k in 0..WK_STATES {
                row.states[FILTER_AT + k] = self.wk.state_matrix[(i, k)];
            }
            row.forces = seat.forces.map(|s| self.wk.input_vector[i] * s);
        }
        rows[INTEGRALS_AT + WEIGHTED_SQUARE] = weighted.scaled(2.0 * a_w);
        rows[INTEGRALS_AT + WEIGHTED_FOURTH] = weighted.scaled(4.0 * a_w * a_w * a_w);
        rows
    }

    /// The exact partials of the outputs at the current states and forces.
    pub fn output_partials(&self) -> ChassisOutputPartials {
        let (acceleration, seat, weighted) = self.acceleration_gradients();
        let duration = self.time - self.start_time;
        let rms = |k: usize| {
            let slope = rms_slope(self.integrals[k], duration);
            ChassisGradient::of_state(INTEGRALS_AT + k).scaled(slope)
        };
        let along = |corner: Corner, at: usize| {
            let (x, y) = self.params.position(corner);
            let mut g = ChassisGradient::ZERO;
            g.states[at..at + 3].copy_from_slice(&ChassisParams::point(x, y));
            g
        };
        ChassisOutputPartials {
            displacement: Corner::ALL.map(|c| along(c, 0)),
            velocity: Corner::ALL.map(|c| along(c, 3)),
            acceleration,
            seat_acceleration: seat,
            rms_acceleration: [HEAVE, PITCH, ROLL].map(rms),
            weighted_seat_acceleration: weighted,
            rms_weighted_seat_acceleration: rms(WEIGHTED_SQUARE),
            seat_vibration_dose_value: ChassisGradient::of_state(INTEGRALS_AT + WEIGHTED_FOURTH)
                .scaled(dose_slope(self.integrals[WEIGHTED_FOURTH])),
        }
    }
}
