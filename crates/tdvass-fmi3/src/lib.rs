//! The FMI 3.0 Co-Simulation FMU (`modelIdentifier="tdvass"`).
//!
//! The physics stays in the safe library ([`tdvass`]) and the behaviour of
//! an instance in the version-neutral slave ([`tdvass_fmu`]); this crate
//! adapts them to the FMI 3.0 calling convention:
//!
//! - [`types`]: the FMI 3.0 type of each variable of the one table.
//! - [`states`]: the FMI 3.0 state machine as one declarative table of
//!   which function is allowed in which phase
//!   ([`states::Fmi3Phase`], the standard's state).
//! - [`instance`]: the FMI 3.0 [`instance::Instance`]: the FMI 3.0
//!   instantiation checks, the state table, the FMI 3.0 types,
//!   Configuration Mode and intermediate updates, around a
//!   [`Slave`](tdvass_fmu::Slave).
//! - [`ffi`]: every fmi3 function with C linkage: null checks, pointers to
//!   slices (through [`tdvass_fmu::pointers`]), `catch_unwind` around every
//!   entry point, and the intermediate-update loop of `fmi3DoStep`, which
//!   holds no reference to the instance while the master's callback runs.
//!
//! **What this crate owns and must never import.** It owns the FMI 3.0
//! layer: the C ABI, the FMI 3.0 state table and the FMI 3.0 types; it
//! builds the FMU's shared library, which holds runtime code only (the
//! model description and documentation are written at build time by
//! `tdvass-describe`). It imports the slave from `tdvass-fmu` and the
//! physics from `tdvass`, and nothing from the command line or the FMI 2.0
//! front-end.

#![deny(unsafe_code)]

pub mod ffi;
pub mod instance;
pub mod states;
pub mod types;

pub use instance::Instance;

pub use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, FmiError, LOG_CATEGORIES,
    MODEL_IDENTIFIER, MODEL_NAME, Status, TIME_TOLERANCE,
};

/// `fmi3GetVersion`.
pub const FMI_VERSION: &str = "3.0";

/// The `instantiationToken` of `model`'s FMU.
pub fn instantiation_token(model: tdvass_fmu::Model) -> String {
    tdvass_fmu::variables::instantiation_token(model)
}
