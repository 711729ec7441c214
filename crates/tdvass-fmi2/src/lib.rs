//! The FMI 2.0 Co-Simulation FMU (`modelIdentifier="tdvass"`).
//!
//! The physics stays in the safe library ([`tdvass::solver`] and friends);
//! this module only adapts it to the FMI 2.0 calling convention:
//!
//! - [`variables`]: the **one table** of FMU variables. Value references,
//!   types, causality, variability, start values, units, admissible ranges,
//!   descriptions and how each variable is read or written all live there;
//!   get/set dispatch, `modelDescription.xml`, `documentation/index.html` and
//!   the GUID are derived from it.
//! - [`states`]: the FMI state machine as one declarative table of which
//!   function is allowed in which state.
//! - [`instance`]: the safe [`Instance`](instance::Instance): settings, the
//!   [`Simulator`](tdvass::solver::Simulator), the machine state, the logger
//!   and the FMU states handed out to the master. Every method returns
//!   `Result<_, FmiError>`.
//! - [`snapshot`]: the versioned, checksummed, position-independent byte
//!   format of serialized FMU states.
//! - [`uri`]: parsing of `fmuResourceLocation`.
//! - [`limits`]: the numerical limits (values, rates, work per step).
//! - [`description`]: `modelDescription.xml` and `documentation/index.html`
//!   (quick-xml, never written by hand).
//! - [`ffi`]: the thin `extern "C"` layer: null checks, pointer-to-slice
//!   conversion, `catch_unwind` around every entry point. Nothing else.
//!
//! Behaviour decisions (also in the generated documentation):
//! - A diverging run (unstable g, tau) makes `fmi2DoStep` return
//!   `fmi2Discard`; the instance stays at the last good internal grid node,
//!   `fmi2GetRealStatus(fmi2LastSuccessfulTime)` tells where, and
//!   `fmi2GetBooleanStatus(fmi2Terminated)` is true. Outputs stay finite.
//! - A refused call (wrong state, bad argument, bad value) returns
//!   `fmi2Error`, logs why and changes nothing: the instance stays in its
//!   state, so the master may correct the value and go on.
//! - `fmi2GetFMUstate` hands out states owned by the instance; `fmi2SetFMUstate`
//!   and `fmi2FreeFMUstate` accept only states of the same instance (others
//!   are refused with `fmi2Error`, so double frees are harmless). To move a
//!   state between instances (or processes) serialize it: a deserialized
//!   state carries every parameter value and replaces the target's.
//! - Beyond the declared ranges, [`limits`] keeps every output finite and
//!   every call short: initial states and the road within the divergence
//!   bounds, rates (stiffness, damping, gain over mass) up to 1e12 1/s²,
//!   weights up to 1e12, and at most 2^22 internal steps (plus road
//!   breakpoints) per `fmi2DoStep`; beyond them the call is refused with
//!   `fmi2Error` naming the variable and value. A non-finite output is never
//!   handed out.
//! - `fmi2SetReal` on `x_g` resets its slope to 0; `fmi2SetRealInputDerivatives`
//!   (order 1) sets the slope used from the current communication point on.
//!   Higher orders are ignored with `fmi2Warning`.
//!
//! **What this crate owns and must never import.** It owns the FMI 2.0
//! layer: the C ABI, the state machine, the variable table, logging and the
//! generated description; it builds the FMU's shared library. It imports the
//! physics from `tdvass` and nothing from the command line (`tdvass-cli`).
//! `unsafe` lives in [`ffi`] only (denied everywhere else).

#![deny(unsafe_code)]

pub mod description;
pub mod ffi;
pub mod instance;
pub mod limits;
pub mod markdown;
pub mod snapshot;
pub mod states;
pub mod uri;
pub mod variables;

pub use instance::Instance;
pub use states::{Function, MachineState};
pub use variables::{VARIABLES, Variable, guid};

/// The `modelIdentifier` (shared library base name) of the FMU.
pub const MODEL_IDENTIFIER: &str = "tdvass";
/// The `modelName` of the FMU.
pub const MODEL_NAME: &str = "TDVASS";
/// `fmi2GetVersion`.
pub const FMI_VERSION: &str = "2.0";
/// `fmi2GetTypesPlatform`.
pub const TYPES_PLATFORM: &str = "default";
/// `DefaultExperiment` start time (s).
pub const DEFAULT_START_TIME: f64 = 0.0;
/// `DefaultExperiment` stop time (s).
pub const DEFAULT_STOP_TIME: f64 = 15.0;
/// `DefaultExperiment` step size (s).
pub const DEFAULT_STEP_SIZE: f64 = 0.001;
/// Relative tolerance for comparing communication points with the FMU time
/// and step ends with the stop time.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// `fmi2Status`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
    Pending = 5,
}

impl Status {
    /// The `fmi2Status` name (`fmi2OK`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "fmi2OK",
            Status::Warning => "fmi2Warning",
            Status::Discard => "fmi2Discard",
            Status::Error => "fmi2Error",
            Status::Fatal => "fmi2Fatal",
            Status::Pending => "fmi2Pending",
        }
    }
}

/// A call that did not (fully) succeed: the status to return and the
/// message to log (without the function-name prefix, which the dispatcher
/// adds).
#[derive(Debug, Clone, PartialEq)]
pub struct FmiError {
    /// Status returned to the master (`fmi2Discard`, `fmi2Error` or `fmi2Fatal`).
    pub status: Status,
    /// What went wrong, naming the variable and value where there is one.
    pub message: String,
}

impl FmiError {
    /// An `fmi2Error` with `message`.
    pub fn error(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Error,
            message: message.into(),
        }
    }

    /// An `fmi2Discard` with `message`.
    pub fn discard(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Discard,
            message: message.into(),
        }
    }
}

impl From<tdvass::Error> for FmiError {
    /// Library errors (invalid parameter, invalid state bytes...) are
    /// `fmi2Error` with the library's message, which names the variable and
    /// value.
    fn from(e: tdvass::Error) -> FmiError {
        FmiError::error(e.to_string())
    }
}

impl std::fmt::Display for FmiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.status.name(), self.message)
    }
}

/// Log categories declared in `modelDescription.xml`, with their descriptions.
/// `logAll` switches every category at once.
pub const LOG_CATEGORIES: [(&str, &str); 6] = [
    (
        "logEvents",
        "Life-cycle events: instantiation, initialization, reset, FMU states",
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
