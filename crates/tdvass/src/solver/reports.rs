//! What the simulator reports: the outputs at an instant, their time
//! derivatives, the time averages and the summary of a run (the values;
//! `outputs` computes them). Plain data; it imports the model and the
//! metrics.

use crate::metrics::RmsValues;
use crate::model::{Performance, State};

pub use crate::model::dynamics::{
    CONTINUOUS_STATES, FILTER_STATES_AT, INTEGRAL_NAMES, INTEGRAL_STATES, INTEGRALS_AT,
};

/// Ride comfort by ISO 2631-1:1997 (vertical whole-body vibration, W_k
/// weighting of the body acceleration BA; see [`crate::comfort`]), present
/// when [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ComfortValues {
    /// The frequency-weighted body acceleration a_w(t) (m/s²): BA through
    /// W_k, the filter starting from rest at t_0.
    pub weighted_body_acceleration: f64,
    /// Its running RMS, the time average
    /// `sqrt((1/(t − t_0)) ∫_{t_0}^{t} a_w² ds)` (m/s²; 0 at the start),
    /// the a_w of ISO 2631-1 section 6.1 and of its comfort scale
    /// ([`crate::comfort::comfort_reaction`]).
    pub rms_weighted_body_acceleration: f64,
    /// The vibration dose value `VDV = (∫_{t_0}^{t} a_w⁴ ds)^{1/4}`
    /// (m/s^1.75), ISO 2631-1 section 6.3.2.
    pub vibration_dose_value: f64,
}

/// Road holding and working space so far, kept with
/// [`super::Metrics::RoadHolding`] (and [`super::Metrics::Comfort`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RoadHolding {
    /// The time without tire contact so far (s): the measure of the times
    /// at which the dynamic tire load was below −W, crossings located
    /// inside the steps (see `solver::holding`); with the unilateral tire
    /// the flight time, between located switches (see `solver::contact`).
    pub contact_loss_time: f64,
    /// The largest |SDD| so far (m), located inside the steps (see
    /// `solver::holding`), and now: the suspension working space used.
    pub max_suspension_deflection: f64,
    /// The first loss of tire contact, if any so far.
    pub first_contact_loss: Option<ContactLoss>,
    /// The number of lift-offs so far: with the unilateral tire, the
    /// switches from contact to flight; with the bilateral tire, the
    /// number of times the dynamic tire load went below −W (a run that
    /// starts without contact counts one at the start).
    pub lift_off_count: u64,
}

/// The first loss of tire contact: the first time at which the dynamic
/// tire load `k_t (x_g − x_t)` fell below minus the static load
/// ([`crate::model::Params::static_load`]). With the bilateral tire the
/// linear model does not hold while the contact is lost; the simulation
/// goes on, and front-ends warn once. With the unilateral tire it is the
/// first lift-off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLoss {
    /// When (s).
    pub time: f64,
    /// The dynamic tire load then (N): minus the static load at a crossing
    /// inside the run, the initial value when the run starts without
    /// contact.
    pub dynamic_tire_load: f64,
    /// The static load W (N).
    pub static_load: f64,
}

/// Every output of the model at one instant (the FMU's outputs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outputs {
    /// Time (s).
    pub time: f64,
    /// Reported state `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: x_h, v_h mirror the wheel).
    pub state: State,
    /// BA, SDD, TDD.
    pub performance: Performance,
    /// The road displacement x_g actually applied (m).
    pub road_displacement: f64,
    /// Control force `u = g x_t(t − tau)` (N).
    pub control_force: f64,
    /// The suspension's force on the body at its attachment (N), positive
    /// up, zero at the static equilibrium
    /// ([`crate::model::Plant::body_force`]; with the sprung mass it is
    /// `m_s BA`).
    pub body_force: f64,
    /// Running RMS values from the start to now, as time averages
    /// `sqrt((1/(t − t_0)) ∫_{t_0}^{t} y² ds)` (0 at the start).
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
    /// ISO 2631-1 ride comfort (`None` unless
    /// [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`]).
    pub comfort: Option<ComfortValues>,
    /// The dynamic tire load `k_t (x_g − x_t)` (N; `−k_t TDD`, positive
    /// when the tire is compressed beyond its static load; there is no tire
    /// damping); with the unilateral tire at least −W (0 N of total load
    /// in flight).
    pub dynamic_tire_load: f64,
    /// `RMS(dynamic tire load) / W` (dimensionless): `k_t RMS(TDD) / W`
    /// with the static load W ([`crate::model::Params::static_load`]).
    /// At most 1/3 keeps the contact with 3σ confidence for a Gaussian
    /// load. It is the tire deflection's, also with the unilateral tire
    /// (whose load does not fall below −W in flight).
    pub rms_dynamic_tire_load_ratio: f64,
    /// Road holding and working space (`None` below
    /// [`super::Metrics::RoadHolding`]).
    pub road_holding: Option<RoadHolding>,
}

impl Outputs {
    /// The time averages among them.
    pub fn time_averages(&self) -> TimeAverages {
        TimeAverages {
            rms: self.rms,
            objective: self.objective,
            rms_dynamic_tire_load_ratio: self.rms_dynamic_tire_load_ratio,
        }
    }

    /// The outputs every metrics level has, as numbers in a fixed order:
    /// the reported state `[x_s, v_s, x_h, v_h, x_t, v_t]`, BA, SDD, TDD,
    /// x_g, the control force, RMS of BA, SDD, TDD, and J.
    pub fn core_values(&self) -> [f64; 15] {
        let s = &self.state;
        [
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5],
            self.performance.body_acceleration,
            self.performance.suspension_deflection,
            self.performance.tire_deflection,
            self.road_displacement,
            self.control_force,
            self.rms.body_acceleration,
            self.rms.suspension_deflection,
            self.rms.tire_deflection,
            self.objective,
        ]
    }
}

/// The outputs that are time averages from the start (see [`Outputs`]),
/// for a reader that needs only them (`Simulator::time_averages`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TimeAverages {
    /// Running RMS values of BA, SDD and TDD.
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
    /// `RMS(dynamic tire load) / W`.
    pub rms_dynamic_tire_load_ratio: f64,
}

/// The outputs that are values at the current instant (see [`Outputs`]),
/// for a reader that needs only them (`Simulator::instantaneous`): no
/// integral from the start is closed for them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instantaneous {
    /// Time (s).
    pub time: f64,
    /// Reported state `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: x_h, v_h mirror the wheel).
    pub state: State,
    /// BA, SDD, TDD.
    pub performance: Performance,
    /// The road displacement x_g actually applied (m).
    pub road_displacement: f64,
    /// Control force `u = g x_t(t − tau)` (N).
    pub control_force: f64,
    /// The suspension's force on the body (N), as in [`Outputs`].
    pub body_force: f64,
    /// The dynamic tire load `k_t (x_g − x_t)` (N; at least −W with the
    /// unilateral tire).
    pub dynamic_tire_load: f64,
}

/// First time derivatives of the outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OutputDerivatives {
    /// dX/dt (reported state).
    pub state: State,
    /// d/dt of BA, SDD, TDD.
    pub performance: Performance,
    /// dx_g/dt.
    pub road_displacement: f64,
    /// du/dt.
    pub control_force: f64,
    /// d/dt of the force on the body (N/s).
    pub body_force: f64,
    /// d/dt of the running RMS values: `(y² − RMS²) / (2 RMS (t − t_0))`
    /// (0 at the start and where an RMS value is 0).
    pub rms: RmsValues,
    /// dJ/dt.
    pub objective: f64,
    /// d/dt of the comfort outputs: `da_w/dt = c_w (A_w w + b_w BA)`, the
    /// RMS rate as above, `dVDV/dt = a_w⁴ / (4 VDV³)` (0 where VDV = 0).
    pub comfort: Option<ComfortValues>,
    /// d/dt of the dynamic tire load, `k_t (dx_g/dt − v_t)` (N/s).
    pub dynamic_tire_load: f64,
    /// d/dt of the RMS dynamic tire load ratio (1/s).
    pub rms_dynamic_tire_load_ratio: f64,
    /// d/dt of road holding and working space: of the contact loss time 1
    /// while the contact is lost, else 0; of the largest |SDD| (m/s)
    /// `d|SDD|/dt` while |SDD| now is the largest and growing, else 0;
    /// `first_contact_loss` is `None`.
    pub road_holding: Option<RoadHolding>,
}

/// Summary of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// RMS values over the run.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
    /// ISO 2631-1 ride comfort at the end (`None` unless
    /// [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`]).
    pub comfort: Option<ComfortValues>,
    /// `RMS(dynamic tire load) / W` over the run (see [`Outputs`]).
    pub rms_dynamic_tire_load_ratio: f64,
    /// Road holding and working space over the run (`None` below
    /// [`super::Metrics::RoadHolding`]).
    pub road_holding: Option<RoadHolding>,
}
