//! The FMI 2.0 Co-Simulation FMU (`modelIdentifier="tdvass"`).
//!
//! The physics stays in the safe library ([`tdvass`]) and the behaviour of
//! an instance in the version-neutral slave ([`tdvass_fmu`]: the one
//! variable table, settings, the guards of every call, the FMU-state format, the
//! [`Slave`](tdvass_fmu::Slave)); this crate only adapts them to the FMI 2.0
//! calling convention:
//!
//! - [`states`]: the FMI 2.0 state machine as one declarative table of
//!   which function is allowed in which phase ([`Phase`], the standard's
//!   state).
//! - [`instance`]: the FMI 2.0 [`instance::Instance`]: the FMI 2.0
//!   instantiation checks, the state table, the status kinds and a
//!   [`Slave`](tdvass_fmu::Slave) that does the rest, called explicitly
//!   (the instance is a [`tdvass_fmu::entry::FrontEnd`]). Every method
//!   returns `Result<_, FmiError>`.
//! - [`uri`]: parsing of `fmuResourceLocation`.
//! - [`ffi`]: the thin `extern "C"` layer: the C signatures and the
//!   conversions of FMI 2.0's types and statuses. What every FMI version
//!   does alike is [`tdvass_fmu::entry`] (the state table and
//!   `catch_unwind` around every entry point, the FMU-state functions) and
//!   [`tdvass_fmu::pointers`] (null checks, pointer-to-slice conversion).
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
//! - Beyond the declared ranges, [`tdvass_fmu::guards`] keeps every output finite and
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
//! layer: the C ABI, the FMI 2.0 state table and the status kinds; it
//! builds the FMU's shared library, which holds runtime code only (the
//! model description and documentation are written at build time by
//! `tdvass-describe`). It imports the slave from `tdvass-fmu` and the
//! physics from `tdvass`, and nothing from the command line (`tdvass-cli`)
//! or another FMI version.
//! `unsafe` lives in [`ffi`] only (denied everywhere else).

#![deny(unsafe_code)]

pub mod ffi;
pub mod instance;
pub mod states;
pub mod uri;

pub use instance::Instance;
pub use states::Function;
pub use tdvass_fmu::{
    COMMON_VARIABLES, DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, FmiError,
    LOG_CATEGORIES, MODEL_IDENTIFIER, MODEL_NAME, Model, Phase, Status, TIME_TOLERANCE, Variable,
    guards, guid, snapshot, variables,
};

/// `fmi2GetVersion`.
pub const FMI_VERSION: &str = "2.0";
/// `fmi2GetTypesPlatform`.
pub const TYPES_PLATFORM: &str = "default";

/// The `fmi2Status` name of a status (`fmi2OK`, ...).
pub fn status_name(status: Status) -> String {
    format!("fmi2{}", status.name())
}
