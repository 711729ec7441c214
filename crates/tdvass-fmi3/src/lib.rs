//! The FMI 3.0 Co-Simulation FMU (`modelIdentifier="tdvass"`).
//!
//! The physics stays in the safe library ([`tdvass`]) and the behaviour of
//! an instance in the version-neutral slave ([`tdvass_fmu`]); this crate
//! adapts them to the FMI 3.0 calling convention:
//!
//! - [`types`]: the FMI 3.0 type of each variable of the one table.
//! - [`description`]: the FMI 3.0 `modelDescription.xml` and
//!   `documentation/index.html`.
//!
//! **What this crate owns and must never import.** It owns the FMI 3.0
//! layer. It imports the slave from `tdvass-fmu` and the physics from
//! `tdvass`, and nothing from the command line or the FMI 2.0 front-end.

#![deny(unsafe_code)]

pub mod description;
pub mod types;

pub use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, FmiError, LOG_CATEGORIES,
    MODEL_IDENTIFIER, MODEL_NAME, Status, TIME_TOLERANCE,
};

/// `fmi3GetVersion`.
pub const FMI_VERSION: &str = "3.0";

/// The `instantiationToken` of this FMU.
pub fn instantiation_token() -> String {
    tdvass_fmu::variables::instantiation_token()
}
