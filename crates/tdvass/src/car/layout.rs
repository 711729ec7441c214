//! The full car as one linear system: the state's layout and the matrices
//! of `Ẋ = A_m X + Σ_c (e_c r_c + b_c u_c)`.
//!
//! **The state** ([`STATES`]): the chassis `[z, θ, φ, ż, θ̇, φ̇]`
//! (`crate::chassis`), each corner's `[x_h, v_h, x_t, v_t]` in the order
//! fl, fr, rl, rr (the paper's suspension of `crate::model` under
//! `Body::Attached`: its body coordinates `x_s`, `v_s` are the chassis's
//! attachment point `z + x θ + y φ`), the 8 states of the ISO 2631-1 W_k
//! filter at the seat point (`crate::comfort`), and the harmonic road's
//! exosystem `[sin ω t, cos ω t]`. The CS has no absorber: its `x_h`, `v_h`
//! stay 0.
//!
//! **The inputs** of a corner c: the road column `e_c` with its input
//! `r_c` (a straight piece of a random road in contact, the constant
//! `−W_c/k_t` in flight, 0 on the harmonic road in contact, whose road
//! comes from the exosystem), and the delayed feedback column `b_c` with
//! `u_c = x_t,c(t − tau)` (zero when the delay is folded into A, as
//! `model::dynamics::folded_feedback` folds it).
//!
//! **Every row comes from the one model:** a corner's rows are its
//! [`Plant`]'s (Eq. (2) from Eq. (1)), its force on the body is the plant's
//! `body_force_row`, the chassis's accelerations are
//! [`ChassisParams::accelerations`] of those forces, the flight matrix is
//! `model::dynamics::flight_matrix`'s rule (the road column moved onto
//! the wheel's column), and the filter is `comfort::wk_state_space`.
//!
//! Layer: the car's system; it imports the crate's `chassis`, `comfort`,
//! `error`, `limits` and `model`.

use crate::chassis::{ChassisParams, Corner};
use crate::comfort::{WK_STATES, wk_state_space};
use crate::error::{Error, Result};
use crate::limits::{DIVERGENCE_DISPLACEMENT, DIVERGENCE_VELOCITY};
use crate::model::dynamics::folded_feedback;
use crate::model::{Body, Params, Plant, STANDARD_GRAVITY, V_H, V_S, V_T, Variant, X_H, X_S, X_T};
use nalgebra::{DMatrix, DVector, RowDVector};

/// The corners, in the order fl, fr, rl, rr.
pub const CORNERS: usize = 4;
/// The chassis's states `[z, θ, φ, ż, θ̇, φ̇]`.
const CHASSIS_STATES: usize = 6;
/// Each corner's states `[x_h, v_h, x_t, v_t]`.
const CORNER_STATES: usize = 4;
/// Index of the first W_k filter state.
const FILTER_AT: usize = CHASSIS_STATES + CORNERS * CORNER_STATES;
/// Index of the exosystem's `sin ω t` (and `cos ω t` after it).
const OSCILLATOR_AT: usize = FILTER_AT + WK_STATES;
/// Number of states of the full car.
pub const STATES: usize = OSCILLATOR_AT + 2;
/// The road input's Taylor coefficients kept: value and slope.
pub(super) const ROAD_ORDER: usize = 2;
/// The delayed input's Taylor coefficients kept: a cubic's four.
pub(super) const DELAY_ORDER: usize = 4;
/// Number of input coefficients of a stretch of a step.
pub(super) const INPUTS: usize = CORNERS * (ROAD_ORDER + DELAY_ORDER);

/// The state index of a corner's local plant coordinate (`X_H` … `V_T`).
pub(super) fn slot(corner: usize, local: usize) -> usize {
    CHASSIS_STATES + CORNER_STATES * corner + local - X_H
}

/// Where a corner's road input coefficients start among the inputs.
pub(super) fn road_input(corner: usize) -> usize {
    corner * ROAD_ORDER
}

/// Where a corner's delayed input coefficients start among the inputs.
pub(super) fn delay_input(corner: usize) -> usize {
    CORNERS * ROAD_ORDER + corner * DELAY_ORDER
}

/// The harmonic road of every corner: `x_g,c = A sin(ω t + φ_c)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HarmonicRoads {
    /// A (m).
    pub amplitude: f64,
    /// ω (rad/s).
    pub angular_frequency: f64,
    /// φ_c (rad), each corner's with its delay and phase in it.
    pub phases: [f64; CORNERS],
}

/// The full car's matrices and output rows (module documentation).
#[derive(Debug, Clone)]
pub(super) struct CarSystem {
    /// A with every tire in contact, the delay folded where it is, without
    /// the harmonic road's coupling.
    a_base: DMatrix<f64>,
    /// `e_c`: each corner's road column (1/s²).
    pub road_columns: [DVector<f64>; CORNERS],
    /// `b_c`: each corner's delayed-feedback column (1/s²; zero when
    /// folded).
    pub delay_columns: [DVector<f64>; CORNERS],
    /// The harmonic road, if that is the road.
    harmonic: Option<HarmonicRoads>,
    /// `x_s − x_t` of each corner (SDD, m).
    pub deflection_rows: [RowDVector<f64>; CORNERS],
    /// `[z'', θ'', φ'']` (m/s², rad/s²).
    pub acceleration_rows: [RowDVector<f64>; 3],
    /// The seat point's vertical acceleration (m/s²).
    pub seat_row: RowDVector<f64>,
    /// a_w at the seat (m/s²).
    pub weighted_row: RowDVector<f64>,
    /// Each corner's static tire load W_c over k_t (m): its contact
    /// margin's limit.
    pub limits: [f64; CORNERS],
    /// Each corner's static tire load W_c (N).
    pub tire_loads: [f64; CORNERS],
    /// Each corner's share of the body's weight (N).
    pub static_loads: [f64; CORNERS],
}

impl CarSystem {
    /// The car of `variant` with the corner parameters `params` (their
    /// `m_s` is not used: each corner carries its share of the chassis),
    /// the chassis `chassis`, the feedback folded with `folded_delay` when
    /// the grid does not resolve the delay, and the harmonic road if any.
    pub fn new(
        params: &Params,
        variant: Variant,
        chassis: &ChassisParams,
        folded_delay: Option<f64>,
        harmonic: Option<HarmonicRoads>,
    ) -> Result<CarSystem> {
        chassis.validate()?;
        let mut a = DMatrix::<f64>::zeros(STATES, STATES);
        let zero_column = DVector::<f64>::zeros(STATES);
        let mut road_columns = std::array::from_fn(|_| zero_column.clone());
        let mut delay_columns = std::array::from_fn(|_| zero_column.clone());
        let zero_row = RowDVector::<f64>::zeros(STATES);
        let mut deflection_rows = std::array::from_fn(|_| zero_row.clone());
        let mut force_rows: [RowDVector<f64>; CORNERS] = std::array::from_fn(|_| zero_row.clone());
        let (mut limits, mut tire_loads, mut static_loads) = ([0.0; CORNERS], [0.0; 4], [0.0; 4]);
        for (c, corner) in Corner::ALL.iter().enumerate() {
            let share = corner_share(chassis, *corner);
            let corner_params = Params {
                m_s: share,
                ..*params
            };
            let plant = Plant::new(corner_params, variant)?.with_body(Body::Attached);
            let (a_local, b_local) = match folded_delay {
                Some(tau) => folded_feedback(&plant, tau),
                None => (plant.a, plant.b),
            };
            // Row l of the corner's local state as a row of the car's state.
            let (x, y) = chassis.position(*corner);
            let point = ChassisParams::point(x, y);
            let local = |l: usize| -> RowDVector<f64> {
                let mut row = zero_row.clone();
                match l {
                    X_S => (0..3).for_each(|i| row[i] = point[i]),
                    V_S => (0..3).for_each(|i| row[3 + i] = point[i]),
                    _ => row[slot(c, l)] = 1.0,
                }
                row
            };
            let over_state = |coefficients: &[f64]| {
                (0..6).fold(zero_row.clone(), |sum, l| sum + local(l) * coefficients[l])
            };
            for l in X_H..=V_T {
                let coefficients: Vec<f64> = (0..6).map(|j| a_local[(l, j)]).collect();
                a.set_row(slot(c, l), &over_state(&coefficients));
                road_columns[c][slot(c, l)] = plant.e[l];
                delay_columns[c][slot(c, l)] = b_local[l];
            }
            force_rows[c] = over_state(plant.body_force_row.as_slice());
            deflection_rows[c] = local(X_S) - local(X_T);
            tire_loads[c] = corner_params.static_load(variant);
            limits[c] = tire_loads[c] / params.k_t;
            static_loads[c] = share * STANDARD_GRAVITY;
        }
        // The chassis: ż = ż … and the accelerations of the corners' forces.
        for i in 0..3 {
            a[(i, 3 + i)] = 1.0;
        }
        for (c, force_row) in force_rows.iter().enumerate() {
            let mut unit = [0.0; CORNERS];
            unit[c] = 1.0;
            let per_newton = chassis.accelerations(&unit);
            for (i, gain) in per_newton.iter().enumerate() {
                let row = a.row(3 + i) + force_row * *gain;
                a.set_row(3 + i, &row);
            }
        }
        let acceleration_rows: [RowDVector<f64>; 3] = std::array::from_fn(|i| a.row(3 + i).into());
        let seat_row = &acceleration_rows[0]
            + &acceleration_rows[1] * chassis.seat_x
            + &acceleration_rows[2] * chassis.seat_y;
        // The W_k filter driven by the seat's acceleration.
        let wk = wk_state_space();
        let mut weighted_row = &seat_row * wk.feedthrough;
        for r in 0..WK_STATES {
            let mut row = &seat_row * wk.input_vector[r];
            for j in 0..WK_STATES {
                row[FILTER_AT + j] += wk.state_matrix[(r, j)];
            }
            a.set_row(FILTER_AT + r, &row);
            weighted_row[FILTER_AT + r] += wk.output_vector[r];
        }
        if let Some(road) = harmonic {
            a[(OSCILLATOR_AT, OSCILLATOR_AT + 1)] = road.angular_frequency;
            a[(OSCILLATOR_AT + 1, OSCILLATOR_AT)] = -road.angular_frequency;
        }
        Ok(CarSystem {
            a_base: a,
            road_columns,
            delay_columns,
            harmonic,
            deflection_rows,
            acceleration_rows,
            seat_row,
            weighted_row,
            limits,
            tire_loads,
            static_loads,
        })
    }

    /// A in the mode `flight` (bit c set: corner c in flight): a corner in
    /// contact takes its harmonic road from the exosystem, one in flight
    /// has its road column moved onto its wheel's column (the tire's force
    /// held at −W_c by the road input `−W_c/k_t`).
    pub fn mode_matrix(&self, flight: u8) -> DMatrix<f64> {
        let mut a = self.a_base.clone();
        for c in 0..CORNERS {
            let column = &self.road_columns[c];
            if flight & (1 << c) != 0 {
                let wheel = slot(c, X_T);
                let moved = a.column(wheel) + column;
                a.set_column(wheel, &moved);
            } else if let Some(road) = self.harmonic {
                let (sin, cos) = crate::math::sin_cos(road.phases[c]);
                let on_sin = a.column(OSCILLATOR_AT) + column * (road.amplitude * cos);
                let on_cos = a.column(OSCILLATOR_AT + 1) + column * (road.amplitude * sin);
                a.set_column(OSCILLATOR_AT, &on_sin);
                a.set_column(OSCILLATOR_AT + 1, &on_cos);
            }
        }
        a
    }

    /// The exosystem's states at t: `[sin ω t, cos ω t]` (zeros without
    /// the harmonic road).
    pub fn oscillator_at(&self, t: f64) -> [f64; 2] {
        self.harmonic.map_or([0.0; 2], |road| {
            let (sin, cos) = crate::math::sin_cos(road.angular_frequency * t);
            [sin, cos]
        })
    }

    /// Sets the exosystem's states of `x` to their values at t (exact at
    /// every node, so that no rounding accumulates over a run).
    pub fn set_oscillator(&self, x: &mut DVector<f64>, t: f64) {
        let [sin, cos] = self.oscillator_at(t);
        x[OSCILLATOR_AT] = sin;
        x[OSCILLATOR_AT + 1] = cos;
    }
}

/// A corner's share of the body's mass (kg): half of the axle's load,
/// `m b / (a + b) / 2` at the front, `m a / (a + b) / 2` at the rear.
pub fn corner_share(chassis: &ChassisParams, corner: Corner) -> f64 {
    let axle = match corner {
        Corner::FrontLeft | Corner::FrontRight => chassis.b,
        Corner::RearLeft | Corner::RearRight => chassis.a,
    };
    chassis.mass * axle / (chassis.a + chassis.b) / 2.0
}

/// The names of the car's states, for a divergence's message.
const STATE_NAMES: [&str; 22] = [
    "heave",
    "pitch",
    "roll",
    "heave_velocity",
    "pitch_rate",
    "roll_rate",
    "x_h_fl",
    "v_h_fl",
    "x_t_fl",
    "v_t_fl",
    "x_h_fr",
    "v_h_fr",
    "x_t_fr",
    "v_t_fr",
    "x_h_rl",
    "v_h_rl",
    "x_t_rl",
    "v_t_rl",
    "x_h_rr",
    "v_h_rr",
    "x_t_rr",
    "v_t_rr",
];

/// Fails where a displacement (or angle) passes
/// [`DIVERGENCE_DISPLACEMENT`] or a rate [`DIVERGENCE_VELOCITY`], or a
/// state is not finite.
pub(super) fn check_divergence(x: &DVector<f64>, time: f64) -> Result<()> {
    for (i, name) in STATE_NAMES.iter().enumerate() {
        let is_rate = if i < 6 {
            i >= 3
        } else {
            matches!((i - 6) % 4 + X_H, V_H | V_T)
        };
        let bound = if is_rate {
            DIVERGENCE_VELOCITY
        } else {
            DIVERGENCE_DISPLACEMENT
        };
        let value = x[i];
        if !value.is_finite() || value.abs() > bound {
            return Err(Error::Diverged {
                time,
                variable: name,
                value,
                bound,
            });
        }
    }
    Ok(())
}
