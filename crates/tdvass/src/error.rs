//! The one error type of the library. Every message names the offending
//! quantity and its value, so that the FMU can log it verbatim.

use thiserror::Error;

/// Errors of the physics library (model, solver, roads, analyses).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Error {
    /// A parameter is outside its admissible range (or not finite).
    #[error("invalid value {value} for parameter `{name}`: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// An integer-valued setting is outside its admissible set.
    #[error("invalid value {value} for `{name}`: {reason}")]
    InvalidSetting {
        name: &'static str,
        value: i64,
        reason: &'static str,
    },
    /// A requested time is not admissible (before the current time, not finite...).
    #[error("invalid time {value} s for `{name}`: {reason}")]
    InvalidTime {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// The response grew past the divergence bound (an unstable (g, tau)).
    #[error(
        "simulation diverged at t = {time} s: `{variable}` = {value} exceeds the bound {bound}"
    )]
    Diverged {
        time: f64,
        variable: &'static str,
        value: f64,
        bound: f64,
    },
    /// A name (of a variant, a road, a road class, an optimisation target)
    /// is not one of the accepted ones; `given` is the text as typed.
    #[error("invalid {what} `{given}`: expected {expected}")]
    UnknownName {
        what: &'static str,
        given: String,
        expected: &'static str,
    },
    /// A file could not be written (or created).
    #[error("I/O error {action} `{path}`: {reason}")]
    Io {
        action: &'static str,
        path: String,
        reason: String,
    },
    /// A road file could not be read or parsed.
    #[error("road file `{path}`: {reason}")]
    RoadFile { path: String, reason: String },
    /// A value beyond a numerical limit (see [`crate::limits`]).
    #[error("invalid value {value} for `{name}`: its magnitude exceeds {bound:e}, {what}")]
    BeyondLimit {
        name: String,
        value: f64,
        bound: f64,
        what: &'static str,
    },
    /// A coefficient over a mass beyond the numerical limit of rates (see
    /// [`crate::limits`]).
    #[error(
        "invalid combination `{name}` = {value} over `{mass_name}` = {mass}: the rate {rate:e} exceeds the numerical limit {limit:e} (natural frequencies up to 1e6 rad/s)"
    )]
    RateLimit {
        name: &'static str,
        value: f64,
        mass_name: &'static str,
        mass: f64,
        rate: f64,
        limit: f64,
    },
    /// A call's argument that the running model refuses (Model Exchange:
    /// a time before the last accepted point, a state that is not finite,
    /// a wrong count); the message names the argument and its value.
    #[error("{0}")]
    Refused(String),
    /// A saved simulator state could not be restored.
    #[error("invalid saved state: {0}")]
    InvalidState(String),
    /// A numerical procedure did not reach its tolerance.
    #[error("numerical failure in {what}: {reason}")]
    Numerical { what: &'static str, reason: String },
}

/// Result alias of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;
