//! The FMUs' names, default experiment, time tolerance and log
//! categories: what the model descriptions declare and the slave assumes.

use tdvass::chassis::CHASSIS_STATES;
use tdvass::exchange::EVENT_INDICATORS;
use tdvass::model::{V_H, V_T, X_H, X_T};
use tdvass::solver::{CONTINUOUS_STATES, INTEGRALS_AT};

/// The `modelIdentifier` (shared library base name) of the FMUs.
pub const MODEL_IDENTIFIER: &str = "tdvass";
/// The `modelName` of the quarter car's FMUs ([`Model::name`] names
/// each model).
pub const MODEL_NAME: &str = "TDVASS";

/// A model the library serves. Every FMU carries the same library; the
/// token of its model description (the GUID, the instantiation token)
/// picks the model at instantiation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    /// The paper's quarter car: the suspension under its sprung mass m_s,
    /// on its own road (`tdvass.fmu`).
    QuarterCar,
    /// The suspension of one corner of a vehicle: the quarter car without
    /// its body, whose attachment point's motion is an input and which
    /// returns the force on the body (`tdvass-corner.fmu`).
    Corner,
    /// The body of a vehicle on four corners: a rigid body in heave, pitch
    /// and roll whose inputs are the corners' forces and whose outputs are
    /// their attachment points' motion (`tdvass-chassis.fmu`).
    Chassis,
}

impl Model {
    /// Every model, the quarter car first.
    pub const ALL: [Model; 3] = [Model::QuarterCar, Model::Corner, Model::Chassis];

    /// The `modelName`.
    pub fn name(self) -> &'static str {
        match self {
            Model::QuarterCar => MODEL_NAME,
            Model::Corner => "TDVASS corner",
            Model::Chassis => "TDVASS chassis",
        }
    }

    /// The FMU's file name without the FMI version's suffix and `.fmu`.
    pub fn fmu_stem(self) -> &'static str {
        match self {
            Model::QuarterCar => "tdvass",
            Model::Corner => "tdvass-corner",
            Model::Chassis => "tdvass-chassis",
        }
    }

    /// Whether the model offers Model Exchange (every model does: the
    /// quarter car and the corner with the states of
    /// [`tdvass::exchange::ModelExchange`], the chassis with its own,
    /// [`tdvass::chassis::Chassis::states`]).
    pub fn offers_model_exchange(self) -> bool {
        true
    }

    /// Model Exchange: the model's continuous states, in the order the
    /// master sees them, as indices into its engine's states (the
    /// quarter car's and the corner's into
    /// [`tdvass::solver::CONTINUOUS_STATES`], the chassis's into
    /// [`tdvass::chassis::CHASSIS_STATES`]). The corner leaves out the
    /// body's coordinates (its input), the W_k filter of the body
    /// acceleration and the integrals of outputs it does not have.
    pub fn continuous_states(self) -> &'static [usize] {
        const QUARTER_CAR: [usize; CONTINUOUS_STATES] = indices();
        const CHASSIS: [usize; CHASSIS_STATES] = indices();
        const CORNER: [usize; 7] = [
            X_H,
            V_H,
            X_T,
            V_T,
            INTEGRALS_AT + 1,
            INTEGRALS_AT + 2,
            CONTINUOUS_STATES - 1,
        ];
        match self {
            Model::QuarterCar => &QUARTER_CAR,
            Model::Corner => &CORNER,
            Model::Chassis => &CHASSIS,
        }
    }

    /// Model Exchange: how many event indicators the model has (the
    /// suspension's switching elements; the chassis has none).
    pub fn event_indicators(self) -> usize {
        if self.is_suspension() {
            EVENT_INDICATORS
        } else {
            0
        }
    }

    /// Whether the model is the suspension (the quarter car or the
    /// corner: the simulator of `tdvass::solver`), not the chassis.
    pub fn is_suspension(self) -> bool {
        self != Model::Chassis
    }
}

/// `[0, 1, .., N - 1]`.
const fn indices<const N: usize>() -> [usize; N] {
    let mut all = [0; N];
    let mut i = 0;
    while i < N {
        all[i] = i;
        i += 1;
    }
    all
}

/// `DefaultExperiment` start time (s).
pub const DEFAULT_START_TIME: f64 = 0.0;
/// `DefaultExperiment` stop time (s).
pub const DEFAULT_STOP_TIME: f64 = 15.0;
/// `DefaultExperiment` step size (s).
pub const DEFAULT_STEP_SIZE: f64 = 0.001;
/// Relative tolerance for comparing communication points with the FMU time
/// and step ends with the stop time.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// Log categories declared in the model descriptions, with their
/// descriptions. `logAll` switches every category at once.
pub const LOG_CATEGORIES: [(&str, &str); 6] = [
    (
        "logEvents",
        "Life-cycle events: instantiation, initialization, reset, FMU states; the lift-offs of the unilateral tire",
    ),
    ("logStatusWarning", "Warnings, e.g. an unstable (g, tau)"),
    (
        "logStatusDiscard",
        "Discarded steps (divergence); always reported",
    ),
    (
        "logStatusError",
        "Errors (refused calls and values); always reported",
    ),
    (
        "logStatusFatal",
        "Fatal errors (an internal panic); always reported",
    ),
    ("logAll", "All of the above"),
];
