//! The version-neutral co-simulation slave of the tdvass FMUs.
//!
//! Everything FMI 2.0 and FMI 3.0 share at run time lives here, once:
//!
//! - [`variables`]: the **one table** of FMU variables. Value references,
//!   types, causality, variability, start values, units, admissible ranges,
//!   descriptions and how each variable is read or written; get/set
//!   dispatch, the GUID and the instantiation token, the CLI's defaults
//!   (checked by tests) and, at build time, the model descriptions and
//!   documentation of every FMI version (`tdvass-describe`) are derived
//!   from it.
//! - [`settings`]: the values of an instance, built on the library's
//!   [`Params`](tdvass::model::Params) and [`Weights`](tdvass::metrics::Weights),
//!   and the [`SimulationConfig`](tdvass::solver::SimulationConfig) they
//!   describe.
//! - [`outputs`]: values, time derivatives and partial derivatives of the
//!   outputs.
//! - [`guards`]: the guards of every slave call: the library's value and
//!   rate limits applied to the FMU's variables, work per step, time
//!   resolution, finite outputs; the value and rate limits themselves are the
//!   library's ([`tdvass::limits`]).
//! - [`snapshot`]: the versioned, checksummed byte format of serialized FMU
//!   states, written with the library's one codec ([`tdvass::bytes`]).
//! - [`slave`]: the [`slave::Slave`]: settings, simulator, phase,
//!   logging and the FMU states it handed out, with a version-neutral API
//!   (set/get by value reference, `do_step(t, h)`, input value and slope,
//!   snapshots, partials). Every method returns `Result<_, FmiError>`.
//! - [`phase`]: the life-cycle phase each front-end's state table checks.
//! - [`pointers`]: instance handles, array and string arguments of the C
//!   interfaces, checked (NULL, alignment, length, the handle's tag).
//! - [`instantiation`]: what the instantiation function of every FMI
//!   version checks and logs alike (instance name, token, the new slave);
//!   the slave logs the instance's release ([`Slave::log_freed`]).
//! - [`entry`]: what the C entry points of every FMI version do around an
//!   instance: the call under the front-end's state table with panics
//!   caught ([`entry::with_instance`], [`entry::call`]), `FreeInstance`,
//!   `SetDebugLogging` and the FMU-state functions; a front-end's instance
//!   implements [`entry::FrontEnd`].
//!
//! **What this crate owns and must never import.** It owns the behaviour of
//! an FMU instance that does not depend on the FMI version, and the C glue
//! every version shares. Where the versions differ it holds data, not
//! code: which variables exist in which version ([`variables::FmiVersion`],
//! [`Variable::fmi3_only`]) and how a front-end names its functions
//! ([`slave::Dialect`]). It imports the physics from `tdvass` and nothing
//! else of the workspace: no front-end's C types, exported functions or
//! state table, no command line. It holds runtime code only: the writers
//! of the model descriptions and documentation are `tdvass-describe`'s, at
//! build time, so no FMU library links them. Its `unsafe` is in
//! [`pointers`] and [`entry`] only (denied everywhere else), each block
//! with its `SAFETY` comment.

#![deny(unsafe_code)]

pub mod entry;
pub mod guards;
pub mod instantiation;
pub mod outputs;
pub mod phase;
pub mod pointers;
pub mod settings;
pub mod slave;
pub mod snapshot;
pub mod variables;

pub use phase::Phase;
pub use settings::Settings;
pub use slave::Slave;
pub use variables::{COMMON_VARIABLES, Variable, guid};

/// The `modelIdentifier` (shared library base name) of the FMUs.
pub const MODEL_IDENTIFIER: &str = "tdvass";
/// The `modelName` of the FMUs.
pub const MODEL_NAME: &str = "TDVASS";
/// `DefaultExperiment` start time (s).
pub const DEFAULT_START_TIME: f64 = 0.0;
/// `DefaultExperiment` stop time (s).
pub const DEFAULT_STOP_TIME: f64 = 15.0;
/// `DefaultExperiment` step size (s).
pub const DEFAULT_STEP_SIZE: f64 = 0.001;
/// Relative tolerance for comparing communication points with the FMU time
/// and step ends with the stop time.
pub const TIME_TOLERANCE: f64 = 1e-9;

/// The status of a call, with the codes FMI 2.0 and FMI 3.0 share
/// (`OK` 0 .. `Fatal` 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

impl Status {
    /// The status name without the version prefix (`OK`, `Warning`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::Warning => "Warning",
            Status::Discard => "Discard",
            Status::Error => "Error",
            Status::Fatal => "Fatal",
        }
    }
}

/// A call that did not (fully) succeed: the status to return and the
/// message to log (without the function-name prefix, which the front-end's
/// dispatcher adds).
#[derive(Debug, Clone, PartialEq)]
pub struct FmiError {
    /// Status returned to the master (Discard, Error or Fatal).
    pub status: Status,
    /// What went wrong, naming the variable and value where there is one.
    pub message: String,
}

impl FmiError {
    /// An Error with `message`.
    pub fn error(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Error,
            message: message.into(),
        }
    }

    /// A Discard with `message`.
    pub fn discard(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Discard,
            message: message.into(),
        }
    }
}

impl From<tdvass::Error> for FmiError {
    /// Library errors (invalid parameter, invalid state bytes, a limit...)
    /// are Errors with the library's message, which names the variable and
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
