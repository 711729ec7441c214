//! The configuration of a simulation ([`SimulationConfig`]) and what a run
//! accumulates ([`Metrics`]): values, checked by `Simulator::new`, that
//! the solver reads and never changes (but for the tunable gain and
//! weights), the checks of the solver's own settings, and how the
//! internal step came from the tolerance ([`StepChoice`]). It imports the
//! model, the road and the metrics, nothing of the solver.

use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::metrics::Weights;
use crate::model::{Body, Params, State, TireContact, Variant};
use crate::road::{RoadShift, RoadSpec};

/// Default relative tolerance of every reported metric.
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// Everything that defines a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Physical and controller parameters.
    pub params: Params,
    /// CS, PVASS or TDVASS.
    pub variant: Variant,
    /// The road.
    pub road: RoadSpec,
    /// How the wheel sees the road ([`RoadShift`]: a delay, and on the
    /// harmonic road a phase; none by default): a corner of a vehicle
    /// behind another, or on the other track.
    pub road_shift: RoadShift,
    /// Relative accuracy of every reported metric: it sets the internal
    /// step (see the `accuracy` module; [`DEFAULT_TOLERANCE`] by default).
    pub tolerance: f64,
    /// Optional upper bound of the internal step (s); 0 = none, the
    /// tolerance alone sets the step.
    pub max_internal_step: f64,
    /// A communication step the internal step should divide (s; 0 =
    /// none): the ladder of steps becomes `communication_step / n`, so that
    /// a caller advancing by it (or a multiple) meets internal nodes only
    /// and never pays for a point inside a step. The FMU passes its
    /// DefaultExperiment stepSize (see the `accuracy` module).
    pub communication_step: f64,
    /// The tire's contact law ([`TireContact`]; the paper's bilateral
    /// tire by default).
    pub tire_contact: TireContact,
    /// What carries the suspension ([`Body`]: the paper's sprung mass by
    /// default, or a body outside the model whose attachment point's
    /// motion is an input, the corner of a vehicle).
    pub body: Body,
    /// Start time t_0 (s).
    pub start_time: f64,
    /// X(t_0) = [x_s, v_s, x_h, v_h, x_t, v_t]; also the history for t < t_0.
    pub initial_state: State,
    /// Weights of the objective J.
    pub weights: Weights,
    /// Which outputs beyond the RMS values of Eq. (6) the run accumulates
    /// ([`Metrics`]; [`Metrics::Paper`] by default, at the cost a step
    /// always had). The outputs they share are the same to the bit at every
    /// level.
    pub metrics: Metrics,
}

/// What a run accumulates besides the RMS values of BA, SDD, TDD and J.
/// The levels are ordered: each includes the one before.
///
/// The instantaneous dynamic tire load `k_t (x_g − x_t)` and the RMS
/// dynamic tire load ratio `k_t RMS(TDD) / W` need nothing more and are
/// given at every level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub enum Metrics {
    /// The paper's evaluation only: a step costs what it always did (the
    /// PSO on J, the floor-ratio loop).
    #[default]
    Paper,
    /// Also road holding and working space (the outputs' `RoadHolding`): the time
    /// without tire contact with its first occurrence, and the largest
    /// |SDD|; a test of every internal step.
    RoadHolding,
    /// Also ISO 2631-1 ride comfort (the outputs' `ComfortValues`): the W_k weighting
    /// of BA integrated as 8 more states in the exact step (see
    /// `solver::system`), for a_w, RMS a_w and VDV.
    Comfort,
}

impl Metrics {
    /// All levels, in order.
    pub const ALL: [Metrics; 3] = [Metrics::Paper, Metrics::RoadHolding, Metrics::Comfort];

    /// Whether the road-holding and working-space accumulators run.
    pub fn road_holding(self) -> bool {
        self >= Metrics::RoadHolding
    }

    /// Whether the W_k filter runs.
    pub fn comfort(self) -> bool {
        self >= Metrics::Comfort
    }

    /// Integer code (0 = paper, 1 = road holding, 2 = comfort), as saved.
    pub fn code(self) -> u64 {
        self as u64
    }

    /// Inverse of [`Metrics::code`].
    pub fn from_code(code: u64) -> Result<Metrics> {
        Metrics::ALL
            .get(usize::try_from(code).unwrap_or(usize::MAX))
            .copied()
            .ok_or(Error::InvalidSetting {
                name: "metrics",
                value: i64::try_from(code).unwrap_or(i64::MAX),
                reason: "must be 0 (paper), 1 (road holding) or 2 (comfort)",
            })
    }
}

impl SimulationConfig {
    /// Writes the configuration: the parameters, the variant, the road,
    /// the solver's settings, the start, the weights, the metrics level,
    /// the tire's contact law, the body and the road's shift.
    pub(super) fn write(&self, w: &mut ByteWriter) {
        self.params.write(w);
        w.u64(self.variant.code() as u64);
        self.road.write(w);
        w.f64(self.tolerance);
        w.f64(self.max_internal_step);
        w.f64(self.communication_step);
        w.f64(self.start_time);
        self.initial_state.iter().for_each(|&v| w.f64(v));
        w.f64(self.weights.body_acceleration);
        w.f64(self.weights.suspension_deflection);
        w.f64(self.weights.tire_deflection);
        w.u64(self.metrics.code());
        w.u64(self.tire_contact.code() as u64);
        w.u64(self.body.code() as u64);
        w.f64(self.road_shift.delay);
        w.f64(self.road_shift.phase);
    }

    /// Reads what [`SimulationConfig::write`] wrote; the codes are
    /// checked here, the values by `Simulator::new`. `version` is the
    /// saved-state format the bytes are of: before 6 the body is the
    /// sprung mass and the road is not shifted.
    pub(super) fn read(r: &mut ByteReader, version: u64) -> Result<SimulationConfig> {
        let params = Params::read(r, version)?;
        let variant = Variant::from_code(r.u64()? as i64)?;
        let road = RoadSpec::read(r)?;
        let tolerance = r.f64()?;
        let max_internal_step = r.f64()?;
        let communication_step = r.f64()?;
        let start_time = r.f64()?;
        let mut initial_state = State::zeros();
        for v in initial_state.iter_mut() {
            *v = r.f64()?;
        }
        let weights = Weights {
            body_acceleration: r.f64()?,
            suspension_deflection: r.f64()?,
            tire_deflection: r.f64()?,
        };
        let metrics = Metrics::from_code(r.u64()?)
            .map_err(|e| Error::InvalidState(format!("metrics level: {e}")))?;
        let tire_contact = TireContact::from_code(i64::try_from(r.u64()?).unwrap_or(i64::MAX))
            .map_err(|e| Error::InvalidState(format!("tire contact: {e}")))?;
        let (body, road_shift) = if version >= 6 {
            let body = Body::from_code(i64::try_from(r.u64()?).unwrap_or(i64::MAX))
                .map_err(|e| Error::InvalidState(format!("body: {e}")))?;
            let (delay, phase) = (r.f64()?, r.f64()?);
            (body, RoadShift { delay, phase })
        } else {
            (Body::Mass, RoadShift::NONE)
        };
        Ok(SimulationConfig {
            params,
            variant,
            road,
            road_shift,
            tolerance,
            max_internal_step,
            communication_step,
            tire_contact,
            body,
            start_time,
            initial_state,
            weights,
            metrics,
        })
    }
}

impl Default for SimulationConfig {
    /// TDVASS, Table 1, (g1, tau1), the harmonic road 0.05 sin 5t, from rest.
    fn default() -> Self {
        SimulationConfig {
            params: Params::default(),
            variant: Variant::Tdvass,
            road: RoadSpec::paper_harmonic(),
            road_shift: RoadShift::NONE,
            tolerance: DEFAULT_TOLERANCE,
            max_internal_step: 0.0,
            communication_step: 0.0,
            tire_contact: TireContact::Bilateral,
            body: Body::Mass,
            start_time: 0.0,
            initial_state: State::zeros(),
            weights: Weights::default(),
            metrics: Metrics::Paper,
        }
    }
}

/// Tightest tolerance accepted: below it rounding, not the step, sets the
/// error of a 15 s run.
pub const MIN_TOLERANCE: f64 = 1e-12;

/// Loosest tolerance accepted: beyond it the numbers would mean little.
pub const MAX_TOLERANCE: f64 = 0.1;

/// Checks a tolerance: finite, within [`MIN_TOLERANCE`], [`MAX_TOLERANCE`].
pub fn check_tolerance(tolerance: f64) -> Result<()> {
    if !tolerance.is_finite() || tolerance <= 0.0 {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: tolerance,
            reason: "the relative tolerance must be finite and > 0",
        });
    }
    if tolerance > MAX_TOLERANCE {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: tolerance,
            reason: "the relative tolerance must be at most 0.1 to mean anything",
        });
    }
    if tolerance < MIN_TOLERANCE {
        return Err(Error::InvalidParameter {
            name: "tolerance",
            value: tolerance,
            reason: "the relative tolerance must be at least 1e-12: below it rounding, not the step, sets the error",
        });
    }
    Ok(())
}

/// Checks `max_internal_step`: 0 (no bound) or finite and > 0.
pub fn check_max_internal_step(bound: f64) -> Result<()> {
    check_optional_step(
        "max_internal_step",
        bound,
        "must be finite and >= 0 (0 = no bound: the tolerance sets the step)",
    )
}

/// Checks `communication_step`: 0 (none) or finite and > 0.
pub fn check_communication_step(step: f64) -> Result<()> {
    check_optional_step(
        "communication_step",
        step,
        "must be finite and >= 0 (0 = none)",
    )
}

/// An optional time (s): 0 or finite and > 0.
fn check_optional_step(name: &'static str, value: f64, reason: &'static str) -> Result<()> {
    crate::model::check(name, value, value >= 0.0, reason)
}

/// What the step choice found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepChoice {
    /// The bound of the internal step handed to the delay grid (s).
    pub step_bound: f64,
    /// The model's first step `h_0` (s), before the ladder.
    pub model_step: f64,
    /// The estimated relative error of the accepted step, from the last
    /// probe that ran at it (NaN when none did).
    pub probe_error: f64,
    /// Probe rounds run.
    pub probe_rounds: usize,
}
