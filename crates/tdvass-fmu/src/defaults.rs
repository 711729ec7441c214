//! The FMUs' names, default experiment, time tolerance and log
//! categories: what the model descriptions declare and the slave assumes.

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
