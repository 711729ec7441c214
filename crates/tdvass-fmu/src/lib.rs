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
//! - [`state`]: what an FMU state copies ([`state::SlaveState`]), with the
//!   [`state::Engine`] that integrates the instance: the kind it was made
//!   for and its model.
//! - [`snapshot`]: the versioned, checksummed byte format of serialized FMU
//!   states, written with the library's one codec ([`tdvass::bytes`]).
//! - [`slave`]: the [`slave::Slave`]: settings, simulator, phase,
//!   logging and the FMU states it handed out, with a version-neutral API
//!   (set/get by value reference, `do_step(t, h)`, input value and slope,
//!   snapshots, partials). Every method returns `Result<_, FmiError>`.
//! - [`phase`]: the life-cycle phase each front-end's state table checks.
//! - [`error`]: the status of a call and the error a refused call returns
//!   ([`FmiError`]); [`defaults`]: the names, the default experiment and
//!   the log categories the descriptions declare. Both are below every
//!   other module, so that none imports upwards from this root.
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

pub mod chassis_outputs;
pub mod defaults;
pub mod entry;
pub mod error;
pub mod guards;
pub mod instantiation;
pub mod outputs;
pub mod phase;
pub mod pointers;
pub mod settings;
pub mod slave;
pub mod snapshot;
pub mod state;
pub mod variables;

pub use defaults::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, LOG_CATEGORIES, MODEL_IDENTIFIER,
    MODEL_NAME, Model, TIME_TOLERANCE,
};
pub use error::{FmiError, Status};
pub use phase::Phase;
pub use settings::Settings;
pub use slave::Slave;
pub use variables::{COMMON_VARIABLES, Variable, guid};
