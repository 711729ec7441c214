//! # tdvass
//!
//! A time-delay feedback controlled quarter-car suspension with an annular
//! vibration-absorbing structure (the "TDVASS" of the source paper), with the
//! conventional suspension (CS) and the uncontrolled absorber suspension
//! (PVASS) for comparison.
//!
//! The physics is a plain, safe library:
//! - [`model`]: parameters (Table 1), the three variants, the state-space
//!   matrices of Eq. (2) and the outputs BA, SDD, TDD;
//! - [`solver`]: the precise (fine) integration method for the delay
//!   differential equation, Eq. (22)-(24);
//! - [`road`]: harmonic, ISO 8608 and paper-compatible random roads, roads
//!   from files and from an external input;
//! - [`metrics`]: running RMS values and the objective J of Eq. (6);
//! - [`analysis`]: stability (section 3), frequency response (section 2.2)
//!   and particle swarm optimisation (sections 2.3.2 and 4.2).
//!
//! The [`fmi2`] module is the only place with FFI: it wraps the simulator as
//! an FMI 2.0 Co-Simulation FMU.

pub mod analysis;
pub mod cli;
pub mod error;
pub mod fmi2;
pub mod metrics;
pub mod model;
mod monotone;
pub mod road;
pub mod solver;

pub use error::{Error, Result};
pub use model::{Params, Variant};
