//! The chassis of a vehicle on four corners: a rigid body in heave, pitch
//! and roll (small angles, displacements from the static equilibrium,
//! positive up), driven by the four corners' forces on it and giving the
//! motion of their attachment points, with the ride-comfort measures at a
//! seat point.
//!
//! **Geometry.** The corners sit at `x` ahead of the centre of gravity
//! (`a` for the front axle, `−b` for the rear) and `y` to its left (half
//! the track, `+` left, `−` right). A point `(x, y)` of the body is at
//! `z + x θ + y φ` (heave z, pitch θ positive nose up, roll φ positive
//! left side up).
//!
//! **Dynamics.** With the corners' forces `f_i` (N, positive up):
//!
//! ```text
//! m z'' = Σ f_i,   I_θ θ'' = Σ x_i f_i,   I_φ φ'' = Σ y_i f_i
//! ```
//!
//! The forces are linear in time between their changes
//! ([`Chassis::set_forces`]: a value and a rate; a rate of 0 holds it), so
//! the accelerations are too and the step is exact: for the generalized
//! accelerations `α_0 + α_1 s`, `q(t + δ) = q + q' δ + α_0 δ²/2 + α_1 δ³/6`.
//! With `I_θ = m a b` (the default) a force at one axle moves the other
//! axle's middle not at all (heave and pitch together; roll still moves
//! the other axle's sides): front and rear decouple, and each corner of a
//! car whose two tracks see the same road carries `m b / (a + b) / 2` (the
//! front) as a quarter car's body would. A rigid body cannot decouple left
//! from right (four corners, three degrees of freedom).
//!
//! **Comfort** at the seat point `(seat_x, seat_y)`: its vertical
//! acceleration `a_s = z'' + seat_x θ'' + seat_y φ''`, weighted by ISO
//! 2631-1 W_k (`crate::comfort`, 8 states) exactly over each step (the
//! exponential of the filter with the linear input), the running RMS of
//! a_w and the vibration dose value `(∫ a_w⁴)^{1/4}`; and the running RMS
//! of the heave, pitch and roll accelerations (exact: their squares are
//! quadratics in time). The integrals of `a_w²` and `a_w⁴` are taken by
//! 5-point Gauss–Legendre quadrature on the exact filter states inside
//! each step: exact for polynomials of degree 9; for `a_w` a sine of
//! frequency f, the error bound `δ^11 (5!)^4 / (11 (10!)^3) |(a_w²)^(10)|`
//! is about 4e-12 of the step's integral at f = 100 Hz and δ = 1 ms
//! (4e-9 for `a_w⁴`, whose frequency is twice as high), and 1e-10 of
//! those at 10 Hz.
//!
//! Layer: engines (docs/architecture.md), beside Model Exchange; it
//! imports the crate's `comfort`, `error`, `metrics` and the solver's
//! `expm`.

use crate::bytes::{ByteReader, ByteWriter};
use crate::comfort::{WK_STATES, WkStateSpace, wk_state_space};
use crate::error::{Error, Result};
use crate::metrics::weighted_averages;
use crate::solver::expm::precise_exp;
use nalgebra::{SMatrix, SVector};

mod params;
pub use params::{ChassisParams, Corner};

/// Where the integrals of the chassis's time averages are kept.
const HEAVE: usize = 0;
const PITCH: usize = 1;
const ROLL: usize = 2;
const WEIGHTED_SQUARE: usize = 3;
const WEIGHTED_FOURTH: usize = 4;

/// The 5-point Gauss–Legendre nodes on `[0, 1]` and their weights.
const GAUSS: [(f64, f64); 5] = [
    (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
    (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
    (0.5, 0.284_444_444_444_444_45),
    (0.769_234_655_052_841_6, 0.239_314_335_249_683_23),
    (0.953_089_922_969_332, 0.118_463_442_528_094_54),
];

/// Model Exchange: how many continuous states the chassis has
/// ([`Chassis::states`]).
pub const CHASSIS_STATES: usize = 6 + WK_STATES + 5;
/// Where the W_k filter's states start among the chassis's continuous
/// states.
pub const CHASSIS_FILTER_AT: usize = 6;
/// Where the integrals start among the chassis's continuous states.
pub const CHASSIS_INTEGRALS_AT: usize = CHASSIS_FILTER_AT + WK_STATES;
const FILTER_AT: usize = CHASSIS_FILTER_AT;
const INTEGRALS_AT: usize = CHASSIS_INTEGRALS_AT;

/// The names of the chassis's continuous states, in order (the FMU's
/// variables of the same names).
pub const CHASSIS_STATE_NAMES: [&str; CHASSIS_STATES] = [
    "heave",
    "pitch",
    "roll",
    "heave_velocity",
    "pitch_rate",
    "roll_rate",
    "seat_wk_filter_1",
    "seat_wk_filter_2",
    "seat_wk_filter_3",
    "seat_wk_filter_4",
    "seat_wk_filter_5",
    "seat_wk_filter_6",
    "seat_wk_filter_7",
    "seat_wk_filter_8",
    "integral_heave_acceleration_squared",
    "integral_pitch_acceleration_squared",
    "integral_roll_acceleration_squared",
    "integral_weighted_seat_acceleration_squared",
    "integral_weighted_seat_acceleration_fourth",
];

/// The nominal values of the chassis's continuous states (their typical
/// magnitudes; a master scales its absolute tolerances by them):
/// displacements 1e-3 m or rad, rates 1e-2, the W_k filter 1e-2 m/s²,
/// the integrals 1e-3.
pub fn chassis_nominals() -> [f64; CHASSIS_STATES] {
    std::array::from_fn(|i| match i {
        0..3 => 1e-3,
        3..INTEGRALS_AT => 1e-2,
        _ => 1e-3,
    })
}

/// How many step lengths the chassis keeps the filter's maps of.
const FILTER_STEPS: usize = 4;

/// The W_k filter with a linear input: `[w; u; u']`.
type FilterInput = SMatrix<f64, { WK_STATES + 2 }, { WK_STATES + 2 }>;

/// The filter's exact maps over a step of one length: at the Gauss nodes
/// and at its end.
#[derive(Debug, Clone)]
struct FilterStep {
    length: f64,
    nodes: [FilterInput; 5],
    end: FilterInput,
}

/// The exact maps of the filter `wk` with a linear input over a step of
/// `delta`.
fn filter_maps(wk: &WkStateSpace, delta: f64) -> FilterStep {
    let mut m = FilterInput::zeros();
    m.fixed_view_mut::<WK_STATES, WK_STATES>(0, 0)
        .copy_from(&wk.state_matrix);
    m.fixed_view_mut::<WK_STATES, 1>(0, WK_STATES)
        .copy_from(&wk.input_vector);
    m[(WK_STATES, WK_STATES + 1)] = 1.0;
    FilterStep {
        length: delta,
        nodes: GAUSS.map(|(node, _)| precise_exp(&(m * (node * delta)))),
        end: precise_exp(&(m * delta)),
    }
}

/// The chassis's outputs at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChassisOutputs {
    /// Time (s).
    pub time: f64,
    /// `[z (m), θ (rad), φ (rad)]`.
    pub position: [f64; 3],
    /// Their rates (m/s, rad/s).
    pub rate: [f64; 3],
    /// Their accelerations (m/s², rad/s²).
    pub acceleration: [f64; 3],
    /// The seat point's vertical acceleration (m/s²).
    pub seat_acceleration: f64,
    /// The running RMS of `[z'', θ'', φ'']` from the start.
    pub rms_acceleration: [f64; 3],
    /// The W_k-weighted seat acceleration a_w now (m/s²).
    pub weighted_seat_acceleration: f64,
    /// The running RMS of a_w (m/s²).
    pub rms_weighted_seat_acceleration: f64,
    /// The seat's vibration dose value `(∫ a_w⁴)^{1/4}` (m/s^1.75).
    pub seat_vibration_dose_value: f64,
}

/// A chassis in motion (module documentation).
#[derive(Debug, Clone)]
pub struct Chassis {
    params: ChassisParams,
    wk: WkStateSpace,
    start_time: f64,
    time: f64,
    /// `[z, θ, φ]` and their rates.
    position: [f64; 3],
    rate: [f64; 3],
    /// The corners' forces now (N) and their rates (N/s).
    forces: [f64; 4],
    force_rates: [f64; 4],
    /// The W_k filter's state at the seat.
    filter: SVector<f64, WK_STATES>,
    /// `∫ z''², ∫ θ''², ∫ φ''², ∫ a_w², ∫ a_w⁴` from the start.
    integrals: [f64; 5],
    /// The filter's maps over the last [`FILTER_STEPS`] step lengths taken
    /// (a master whose clock counts nanoseconds alternates between two
    /// lengths a rounding apart), the oldest replaced first. In place, not
    /// on the heap: a new length (a step of its own, a state restored)
    /// makes its maps without allocating.
    steps: [Option<FilterStep>; FILTER_STEPS],
    /// Where the next new length goes in `steps`.
    next_step: usize,
}

impl Chassis {
    /// A chassis at rest at its static equilibrium at `start_time`, the
    /// forces 0.
    pub fn new(params: ChassisParams, start_time: f64) -> Result<Chassis> {
        params.validate()?;
        if !start_time.is_finite() {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: start_time,
                reason: "must be finite",
            });
        }
        Ok(Chassis {
            params,
            wk: wk_state_space(),
            start_time,
            time: start_time,
            position: [0.0; 3],
            rate: [0.0; 3],
            forces: [0.0; 4],
            force_rates: [0.0; 4],
            filter: SVector::zeros(),
            integrals: [0.0; 5],
            steps: [const { None }; FILTER_STEPS],
            next_step: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &ChassisParams {
        &self.params
    }

    /// The time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the corners' forces on the body from now on (N, positive up,
    /// in the order of [`Corner::ALL`]): `forces + rates (t − now)`. A
    /// value or rate that is not finite is refused by name and changes
    /// nothing.
    pub fn set_forces(&mut self, forces: [f64; 4], rates: [f64; 4]) -> Result<()> {
        for (corner, (&force, &rate)) in Corner::ALL.iter().zip(forces.iter().zip(&rates)) {
            for (value, reason) in [
                (force, "a corner's force must be finite"),
                (rate, "the rate of a corner's force must be finite"),
            ] {
                if !value.is_finite() {
                    return Err(Error::InvalidParameter {
                        name: corner.force_name(),
                        value,
                        reason,
                    });
                }
            }
        }
        self.forces = forces;
        self.force_rates = rates;
        Ok(())
    }

    /// Advances exactly to `t` (s, not before the current time) under the
    /// forces set.
    pub fn advance_to(&mut self, t: f64) -> Result<()> {
        if !(t.is_finite() && t >= self.time) {
            return Err(Error::InvalidTime {
                name: "t_end",
                value: t,
                reason: "must be finite and not before the current time",
            });
        }
        let delta = t - self.time;
        if delta == 0.0 {
            return Ok(());
        }
        let p = &self.params;
        let alpha0 = p.accelerations(&self.forces);
        let alpha1 = p.accelerations(&self.force_rates);
        let (d2, d3) = (delta * delta / 2.0, delta * delta * delta / 6.0);
        for k in 0..3 {
            self.position[k] += self.rate[k] * delta + alpha0[k] * d2 + alpha1[k] * d3;
            self.rate[k] += alpha0[k] * delta + alpha1[k] * d2;
            // ∫ (α0 + α1 s)² ds over [0, δ].
            self.integrals[HEAVE + k] += alpha0[k] * alpha0[k] * delta
                + alpha0[k] * alpha1[k] * delta * delta
                + alpha1[k] * alpha1[k] * delta * delta * delta / 3.0;
        }
        let seat = [1.0, p.seat_x, p.seat_y];
        let dot = |v: &[f64; 3]| v[0] * seat[0] + v[1] * seat[1] + v[2] * seat[2];
        let (u0, u1) = (dot(&alpha0), dot(&alpha1));
        self.filter_step(delta, u0, u1);
        for (force, rate) in self.forces.iter_mut().zip(&self.force_rates) {
            *force += rate * delta;
        }
        self.time = t;
        Ok(())
    }

    /// The W_k filter over `delta` with the input `u0 + u1 s`, and the
    /// integrals of a_w² and a_w⁴ over it.
    fn filter_step(&mut self, delta: f64, u0: f64, u1: f64) {
        let found = self
            .steps
            .iter()
            .position(|step| step.as_ref().is_some_and(|step| step.length == delta));
        let at = match found {
            Some(at) => at,
            None => {
                let at = self.next_step;
                self.next_step = (at + 1) % FILTER_STEPS;
                self.steps[at] = Some(filter_maps(&self.wk, delta));
                at
            }
        };
        let Some(step) = &self.steps[at] else {
            unreachable!("the maps of a step length just found or made")
        };
        let mut z = SVector::<f64, { WK_STATES + 2 }>::zeros();
        z.fixed_rows_mut::<WK_STATES>(0).copy_from(&self.filter);
        z[WK_STATES] = u0;
        z[WK_STATES + 1] = u1;
        let (mut square, mut fourth) = (0.0, 0.0);
        for (map, (_, weight)) in step.nodes.iter().zip(GAUSS) {
            let y = map * z;
            let w = y.fixed_rows::<WK_STATES>(0).into_owned();
            let a_w = self.wk.weighted_acceleration(&w, y[WK_STATES]);
            square += weight * a_w * a_w;
            fourth += weight * a_w * a_w * a_w * a_w;
        }
        self.integrals[WEIGHTED_SQUARE] += square * delta;
        self.integrals[WEIGHTED_FOURTH] += fourth * delta;
        let end = step.end * z;
        self.filter = end.fixed_rows::<WK_STATES>(0).into_owned();
    }

    /// The corners' forces now (N) and their rates (N/s), in the order of
    /// [`Corner::ALL`].
    pub fn forces(&self) -> ([f64; 4], [f64; 4]) {
        (self.forces, self.force_rates)
    }

    /// Appends the motion (time, states, forces, filter, integrals; the
    /// parameters are the caller's) to `w`: [`Chassis::read_motion`]
    /// restores it bit for bit.
    pub fn write_motion(&self, w: &mut ByteWriter) {
        w.f64(self.start_time);
        w.f64(self.time);
        let filter: [f64; WK_STATES] = self.filter.into();
        for values in [
            &self.position[..],
            &self.rate,
            &self.forces,
            &self.force_rates,
            &filter,
            &self.integrals,
        ] {
            values.iter().for_each(|&v| w.f64(v));
        }
    }

    /// A chassis of `params` in the motion [`Chassis::write_motion`] wrote,
    /// read from `r`. Every value must be finite and the time not before
    /// the start. The integrals may be below 0: in Model Exchange the
    /// master's solver sets them ([`Chassis::set_states`]), and the
    /// outputs take a negative one as 0.
    pub fn read_motion(params: ChassisParams, r: &mut ByteReader) -> Result<Chassis> {
        let mut chassis = Chassis::new(params, r.f64()?)?;
        chassis.time = r.f64()?;
        let mut filter = [0.0; WK_STATES];
        for values in [
            &mut chassis.position[..],
            &mut chassis.rate,
            &mut chassis.forces,
            &mut chassis.force_rates,
            &mut filter,
            &mut chassis.integrals,
        ] {
            for v in values.iter_mut() {
                *v = r.f64()?;
            }
        }
        chassis.filter = SVector::from(filter);
        let finite = [chassis.time]
            .iter()
            .chain(&chassis.position)
            .chain(&chassis.rate)
            .chain(&chassis.forces)
            .chain(&chassis.force_rates)
            .chain(&filter)
            .chain(&chassis.integrals)
            .all(|v| v.is_finite());
        if !finite || chassis.time < chassis.start_time {
            return Err(Error::InvalidState(
                "the chassis's motion is not finite or runs backwards".into(),
            ));
        }
        Ok(chassis)
    }

    /// Model Exchange: the continuous states, in the order of
    /// [`CHASSIS_STATE_NAMES`] (`[z, θ, φ]`, their rates, the W_k filter at
    /// the seat, then the integrals of `z''²`, `θ''²`, `φ''²`, `a_w²` and
    /// `a_w⁴` from the start).
    pub fn states(&self) -> [f64; CHASSIS_STATES] {
        let mut x = [0.0; CHASSIS_STATES];
        x[..3].copy_from_slice(&self.position);
        x[3..6].copy_from_slice(&self.rate);
        x[FILTER_AT..INTEGRALS_AT].copy_from_slice(self.filter.as_slice());
        x[INTEGRALS_AT..].copy_from_slice(&self.integrals);
        x
    }

    /// Model Exchange: sets the continuous states ([`Chassis::states`]),
    /// exactly [`CHASSIS_STATES`] finite values (the error names the first
    /// that is not; a refused call changes nothing).
    pub fn set_states(&mut self, values: &[f64]) -> Result<()> {
        if values.len() != CHASSIS_STATES {
            return Err(Error::Refused(format!(
                "{} continuous states given, the chassis has {CHASSIS_STATES}",
                values.len()
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::Refused(format!(
                "continuous state {i} (`{}`) = {} is not finite",
                CHASSIS_STATE_NAMES[i], values[i]
            )));
        }
        self.position.copy_from_slice(&values[..3]);
        self.rate.copy_from_slice(&values[3..6]);
        self.filter
            .as_mut_slice()
            .copy_from_slice(&values[FILTER_AT..INTEGRALS_AT]);
        self.integrals.copy_from_slice(&values[INTEGRALS_AT..]);
        Ok(())
    }

    /// Model Exchange: sets the time (s; finite and not before the start
    /// time). The states and the forces keep their values: the master's
    /// solver integrates the states and sets the forces at each time.
    pub fn set_time(&mut self, time: f64) -> Result<()> {
        if !(time.is_finite() && time >= self.start_time) {
            return Err(Error::InvalidTime {
                name: "time",
                value: time,
                reason: "must be finite and not before the start time",
            });
        }
        self.time = time;
        Ok(())
    }

    /// Model Exchange: the time derivatives of [`Chassis::states`] under
    /// the forces now (their rates play no part: the master sets the
    /// forces at every point it evaluates).
    pub fn rates(&self) -> [f64; CHASSIS_STATES] {
        let p = &self.params;
        let acceleration = p.accelerations(&self.forces);
        let seat = acceleration[0] + p.seat_x * acceleration[1] + p.seat_y * acceleration[2];
        let mut dx = [0.0; CHASSIS_STATES];
        dx[..3].copy_from_slice(&self.rate);
        dx[3..6].copy_from_slice(&acceleration);
        dx[FILTER_AT..INTEGRALS_AT]
            .copy_from_slice(self.wk.derivative(&self.filter, seat).as_slice());
        let a_w = self.wk.weighted_acceleration(&self.filter, seat);
        for k in [HEAVE, PITCH, ROLL] {
            dx[INTEGRALS_AT + k] = acceleration[k] * acceleration[k];
        }
        dx[INTEGRALS_AT + WEIGHTED_SQUARE] = a_w * a_w;
        dx[INTEGRALS_AT + WEIGHTED_FOURTH] = a_w * a_w * a_w * a_w;
        dx
    }

    /// Model Exchange: [`Chassis::rates`], refused naming the first that
    /// is not finite (forces or states too large for the chassis).
    pub fn derivatives(&self) -> Result<[f64; CHASSIS_STATES]> {
        let dx = self.rates();
        if let Some(i) = dx.iter().position(|v| !v.is_finite()) {
            return Err(Error::Refused(format!(
                "the derivative of `{}` is {} at t = {} s; the forces or the states are too large for the chassis",
                CHASSIS_STATE_NAMES[i], dx[i], self.time
            )));
        }
        Ok(dx)
    }

    /// The attachment point of `corner`: displacement (m) and velocity
    /// (m/s), from the states alone.
    pub fn attachment(&self, corner: Corner) -> (f64, f64) {
        let (x, y) = self.params.position(corner);
        let p = ChassisParams::point(x, y);
        let along = |v: &[f64; 3]| p[0] * v[0] + p[1] * v[1] + p[2] * v[2];
        (along(&self.position), along(&self.rate))
    }

    /// The outputs now.
    pub fn outputs(&self) -> ChassisOutputs {
        let p = &self.params;
        let acceleration = p.accelerations(&self.forces);
        let seat_acceleration =
            acceleration[0] + p.seat_x * acceleration[1] + p.seat_y * acceleration[2];
        let duration = self.time - self.start_time;
        let rms = |integral: f64| {
            if duration > 0.0 {
                (integral.max(0.0) / duration).sqrt()
            } else {
                0.0
            }
        };
        let (rms_weighted, dose) = weighted_averages(
            self.integrals[WEIGHTED_SQUARE],
            self.integrals[WEIGHTED_FOURTH],
            duration,
        );
        ChassisOutputs {
            time: self.time,
            position: self.position,
            rate: self.rate,
            acceleration,
            seat_acceleration,
            rms_acceleration: [HEAVE, PITCH, ROLL].map(|k| rms(self.integrals[k])),
            weighted_seat_acceleration: self
                .wk
                .weighted_acceleration(&self.filter, seat_acceleration),
            rms_weighted_seat_acceleration: rms_weighted,
            seat_vibration_dose_value: dose,
        }
    }
}

mod partials;
pub use partials::{ChassisGradient, ChassisOutputPartials};

#[cfg(test)]
mod tests;
