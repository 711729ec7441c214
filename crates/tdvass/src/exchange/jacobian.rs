//! Exact partial derivatives of Model Exchange: the derivatives and the
//! outputs with respect to the continuous states and the road input `x_g`
//! (directional and adjoint derivatives of the FMUs).
//!
//! In each tire mode the plant and the W_k filter are linear, and the
//! integrands are polynomials of the outputs:
//!
//! ```text
//! ∂Ẋ/∂X   = M + b [∂d/∂x_t, ∂d/∂v_t] (columns x_t, v_t),   ∂Ẋ/∂x_g = e (contact)
//! ∂ẇ/∂X   = b_w a_vs,  ∂ẇ/∂w = A_w,                       a_w = c_w w + d_w BA
//! ∂(y²)'/∂· = 2 y ∂y,  ∂(a_w⁴)'/∂· = 4 a_w³ ∂a_w,          ∂(t_lost)'/∂· = 0
//! ```
//!
//! with `M = A` in contact and `A + e c_tᵀ` in flight, `a_vs` the row of A
//! that gives BA, and `d = x_t(t − tau)` the delayed input: its partials
//! ([`super::Delayed`]) are not zero only where the history interpolates
//! towards the current state (a delay shorter than the master's step), or
//! `(1, −tau)` where the delay is folded. The outputs' partials follow the
//! formulas of [`ModelExchange::outputs`]; a time average
//! `sqrt(I/(t − t_0))` has the partial `1/(2 sqrt(I (t − t_0)))` with
//! respect to its integral I, taken as 0 where I is 0 (its slope there is
//! unbounded) and at the start.

use super::instance::ModelExchange;
use crate::metrics::{dose_slope, rms_slope};
use crate::model::dynamics::Switch;
use crate::model::inputs::{PRESCRIBED, PrescribedValues};
use crate::model::{V_S, V_T, Variant, X_H, X_S, X_T};
use crate::solver::{CONTINUOUS_STATES, FILTER_STATES_AT, INTEGRALS_AT};

/// The partials of the derivatives at the current point.
#[derive(Debug, Clone, PartialEq)]
pub struct Jacobian {
    /// `∂ẋ_i/∂x_j` at `[i][j]`.
    pub states: [[f64; CONTINUOUS_STATES]; CONTINUOUS_STATES],
    /// `∂ẋ_i/∂x_g` (0 unless the road is the input `x_g`).
    pub road_input: [f64; CONTINUOUS_STATES],
    /// `∂ẋ_i/∂[position, velocity]` of each input that prescribes
    /// coordinates ([`PRESCRIBED`]: a corner's body attachment `[x_s,
    /// v_s]`), 0 for one the configuration does not have (the sprung
    /// mass's `x_s`, `v_s` are states).
    pub prescribed: [[[f64; 2]; PRESCRIBED.len()]; CONTINUOUS_STATES],
}

/// The partials of one output with respect to the continuous states and
/// the road input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gradient {
    /// `∂y/∂x_j`.
    pub states: [f64; CONTINUOUS_STATES],
    /// `∂y/∂x_g`.
    pub road_input: f64,
    /// `∂y/∂[position, velocity]` of each input that prescribes
    /// coordinates ([`PRESCRIBED`]: a corner's body attachment).
    pub prescribed: [[f64; 2]; PRESCRIBED.len()],
}

impl Gradient {
    /// No dependence on anything.
    pub const ZERO: Gradient = Gradient {
        states: [0.0; CONTINUOUS_STATES],
        road_input: 0.0,
        prescribed: [[0.0; 2]; PRESCRIBED.len()],
    };

    /// The gradient of the continuous state `j` itself.
    pub fn of_state(j: usize) -> Gradient {
        let mut g = Gradient::ZERO;
        g.states[j] = 1.0;
        g
    }

    fn scaled(mut self, factor: f64) -> Gradient {
        self.states.iter_mut().for_each(|v| *v *= factor);
        self.road_input *= factor;
        self.prescribed
            .iter_mut()
            .flatten()
            .for_each(|v| *v *= factor);
        self
    }

    /// The partials with respect to the coordinates that the inputs in
    /// `values` prescribe (a corner's `x_s`, `v_s`) moved from the states
    /// to the inputs they are read from.
    fn prescribed_by(mut self, values: &PrescribedValues) -> Gradient {
        move_to_inputs(&mut self.states, &mut self.prescribed, values);
        self
    }

    fn plus(mut self, other: &Gradient) -> Gradient {
        for (v, o) in self.states.iter_mut().zip(other.states) {
            *v += o;
        }
        self.road_input += other.road_input;
        for (v, o) in self.prescribed.iter_mut().zip(other.prescribed) {
            v[0] += o[0];
            v[1] += o[1];
        }
        self
    }
}

/// Moves the partials in `states` with respect to the coordinates that the
/// inputs in `values` prescribe to `inputs` (by input: position, velocity),
/// leaving 0 in `states`.
fn move_to_inputs(
    states: &mut [f64; CONTINUOUS_STATES],
    inputs: &mut [[f64; 2]; PRESCRIBED.len()],
    values: &PrescribedValues,
) {
    for ((p, value), partials) in PRESCRIBED.iter().zip(values).zip(inputs) {
        if value.is_some() {
            for (k, &c) in p.coordinates.iter().enumerate() {
                partials[k] = states[c];
                states[c] = 0.0;
            }
        }
    }
}

/// The partials of the Real outputs of [`ModelExchange::outputs`] (the
/// state outputs are the states themselves: [`Gradient::of_state`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OutputPartials {
    pub body_acceleration: Gradient,
    pub suspension_deflection: Gradient,
    pub tire_deflection: Gradient,
    pub road_displacement: Gradient,
    pub control_force: Gradient,
    pub rms_body_acceleration: Gradient,
    pub rms_suspension_deflection: Gradient,
    pub rms_tire_deflection: Gradient,
    pub objective: Gradient,
    pub weighted_body_acceleration: Gradient,
    pub rms_weighted_body_acceleration: Gradient,
    pub vibration_dose_value: Gradient,
    pub dynamic_tire_load: Gradient,
    pub rms_dynamic_tire_load_ratio: Gradient,
    pub contact_loss_time: Gradient,
    pub max_suspension_deflection: Gradient,
    /// The suspension's force on the body
    /// ([`crate::model::Plant::body_force`]): a corner's partials with
    /// respect to its body attachment are in [`Gradient::prescribed`].
    pub body_force: Gradient,
}

/// What the partials at the current point are built from.
struct Point {
    /// `∂BA/∂X`: the row of A that gives BA.
    acceleration_row: [f64; 6],
    /// BA, SDD, TDD, a_w now.
    body_acceleration: f64,
    suspension_deflection: f64,
    tire_deflection: f64,
    weighted: f64,
    /// The road is the input `x_g`.
    road_is_input: bool,
}

impl ModelExchange {
    /// The values the partials at the current point need.
    fn point(&mut self) -> Point {
        let x = self.plant_state();
        let road = self.road.value(self.time);
        let body_acceleration = self.plant.body_acceleration(&x);
        let w = self.filter_state();
        Point {
            acceleration_row: std::array::from_fn(|j| self.plant.a[(V_S, j)]),
            body_acceleration,
            suspension_deflection: x[X_S] - x[X_T],
            tire_deflection: x[X_T] - road,
            weighted: self.wk.weighted_acceleration(&w, body_acceleration),
            road_is_input: self.road.is_input(),
        }
    }

    /// `∂BA`, `∂SDD`, `∂TDD`, `∂a_w` and the body force's partials at `p`.
    fn performance_gradients(&self, p: &Point) -> [Gradient; 5] {
        let mut acceleration = Gradient::ZERO;
        acceleration.states[..6].copy_from_slice(&p.acceleration_row);
        let mut deflection = Gradient::ZERO;
        deflection.states[X_S] = 1.0;
        deflection.states[X_T] = -1.0;
        let mut tire = Gradient::of_state(X_T);
        tire.road_input = if p.road_is_input { -1.0 } else { 0.0 };
        let mut weighted = acceleration.scaled(self.wk.feedthrough);
        for k in 0..crate::comfort::WK_STATES {
            weighted.states[FILTER_STATES_AT + k] = self.wk.output_vector[k];
        }
        let mut body_force = Gradient::ZERO;
        body_force.states[..6].copy_from_slice(self.plant.body_force_row.as_slice());
        let gradients = [acceleration, deflection, tire, weighted, body_force];
        gradients.map(|g| g.prescribed_by(&self.prescribed))
    }

    /// The exact partials of the derivatives at the current time and
    /// states (module documentation). Nothing is recorded.
    pub fn jacobian(&mut self) -> Jacobian {
        let delayed = self.delayed_now();
        let p = self.point();
        let mut states = [[0.0; CONTINUOUS_STATES]; CONTINUOUS_STATES];
        let mut road_input = [0.0; CONTINUOUS_STATES];
        let mode = self.mode();
        let flying = mode.is(Switch::Tire);
        let m = &self.matrices;
        let matrix = m.modes[mode.index()];
        for (i, row) in states.iter_mut().enumerate().take(6) {
            for (j, value) in row.iter_mut().enumerate().take(6) {
                *value = matrix[(i, j)];
            }
            row[X_T] += m.feedback[i] * delayed.by_position;
            row[V_T] += m.feedback[i] * delayed.by_velocity;
            if p.road_is_input && !flying {
                road_input[i] = self.plant.e[i];
            }
        }
        if self.config.variant == Variant::Cs {
            states[X_H] = states[X_T];
            states[X_H + 1] = states[V_T];
            road_input[X_H] = road_input[X_T];
            road_input[X_H + 1] = road_input[V_T];
        }
        let wk = &self.wk;
        for i in 0..crate::comfort::WK_STATES {
            let row = &mut states[FILTER_STATES_AT + i];
            for (j, a) in p.acceleration_row.iter().enumerate() {
                row[j] = wk.input_vector[i] * a;
            }
            for k in 0..crate::comfort::WK_STATES {
                row[FILTER_STATES_AT + k] = wk.state_matrix[(i, k)];
            }
        }
        let [acceleration, deflection, tire, weighted, _] = self.performance_gradients(&p);
        let aw = p.weighted;
        let integrands = [
            acceleration.scaled(2.0 * p.body_acceleration),
            deflection.scaled(2.0 * p.suspension_deflection),
            tire.scaled(2.0 * p.tire_deflection),
            weighted.scaled(2.0 * aw),
            weighted.scaled(4.0 * aw * aw * aw),
        ];
        // The rates read the prescribed coordinates (a corner's body
        // attachment) from their inputs.
        let mut prescribed = [[[0.0; 2]; PRESCRIBED.len()]; CONTINUOUS_STATES];
        for (row, partials) in states.iter_mut().zip(prescribed.iter_mut()) {
            move_to_inputs(row, partials, &self.prescribed);
        }
        for (k, g) in integrands.iter().enumerate() {
            states[INTEGRALS_AT + k] = g.states;
            road_input[INTEGRALS_AT + k] = g.road_input;
            prescribed[INTEGRALS_AT + k] = g.prescribed;
        }
        Jacobian {
            states,
            road_input,
            prescribed,
        }
    }

    /// The exact partials of the outputs at the current time and states
    /// (module documentation). Nothing is recorded.
    pub fn output_partials(&mut self) -> OutputPartials {
        let delayed = self.delayed_now();
        let p = self.point();
        let [acceleration, deflection, tire, weighted, body_force] = self.performance_gradients(&p);
        let duration = self.time - self.config.start_time;
        let integral = |k: usize| self.states[INTEGRALS_AT + k];
        let rms = |k: usize| {
            Gradient::of_state(INTEGRALS_AT + k).scaled(rms_slope(integral(k), duration))
        };
        let weights = self.config.weights;
        let objective = rms(0)
            .scaled(weights.body_acceleration)
            .plus(&rms(1).scaled(weights.suspension_deflection))
            .plus(&rms(2).scaled(weights.tire_deflection));

        let k_t = self.config.params.k_t;
        // The tire law `max(k_t (x_g − x_t), −W)` of a unilateral tire is
        // flat where it holds the load at −W (the kink counts as contact).
        let held = self.config.tire_contact.is_unilateral()
            && k_t * -p.tire_deflection < -self.static_load;
        let tire_load = if held {
            Gradient::ZERO
        } else {
            tire.scaled(-k_t)
        };
        let mut control = Gradient::ZERO;
        let gain = self.config.params.effective_gain(self.config.variant);
        control.states[X_T] = gain * delayed.by_position;
        control.states[V_T] = gain * delayed.by_velocity;
        let mut road = Gradient::ZERO;
        road.road_input = if p.road_is_input { 1.0 } else { 0.0 };
        let sdd = p.suspension_deflection;
        let max_deflection = if sdd.abs() > self.discrete.max_suspension_deflection {
            deflection.scaled(sdd.signum())
        } else {
            Gradient::ZERO
        };
        OutputPartials {
            body_acceleration: acceleration,
            suspension_deflection: deflection,
            tire_deflection: tire,
            road_displacement: road,
            control_force: control,
            rms_body_acceleration: rms(0),
            rms_suspension_deflection: rms(1),
            rms_tire_deflection: rms(2),
            objective,
            weighted_body_acceleration: weighted,
            rms_weighted_body_acceleration: rms(3),
            vibration_dose_value: Gradient::of_state(INTEGRALS_AT + 4)
                .scaled(dose_slope(integral(4))),
            dynamic_tire_load: tire_load,
            rms_dynamic_tire_load_ratio: rms(2).scaled(k_t / self.static_load),
            contact_loss_time: Gradient::of_state(CONTINUOUS_STATES - 1),
            max_suspension_deflection: max_deflection,
            body_force,
        }
    }
}
