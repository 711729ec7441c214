//! # tdvass
//!
//! A time-delay feedback controlled quarter-car suspension with an annular
//! vibration-absorbing structure (the "TDVASS" of the source paper), with the
//! conventional suspension (CS) and the uncontrolled absorber suspension
//! (PVASS) for comparison.
//!
//! The physics is a plain, safe library:
//! - [`model`]: parameters (Table 1), the three variants, the state-space
//!   matrices of Eq. (2) and the outputs BA, SDD, TDD, and the dynamics
//!   both engines share ([`model::dynamics`]: the continuous states, the
//!   plant in each tire mode, the tire's laws, the rates);
//! - [`exchange`]: the same model for Model Exchange, an ODE with events
//!   and a delay history that a master's own solver integrates;
//! - [`solver`]: the precise (fine) integration method for the delay
//!   differential equation, Eq. (22)-(24), its internal step chosen from a
//!   relative tolerance ([`solver::accuracy`]);
//! - [`road`]: harmonic, ISO 8608 and paper-compatible random roads, roads
//!   from files and from an external input;
//! - [`metrics`]: running RMS values and the objective J of Eq. (6);
//! - [`analysis`]: stability (section 3), frequency response (section 2.2)
//!   and particle swarm optimisation (sections 2.3.2 and 4.2);
//! - [`comfort`]: the ISO 2631-1 W_k weighting and comfort scale;
//! - [`limits`]: the numerical limits every configuration is checked
//!   against, whoever builds it (the FMU, the command line, a library user);
//! - [`bytes`]: the one little-endian codec of saved states;
//! - [`math`]: the transcendental functions the results depend on, from one
//!   pure-Rust implementation (the same bits on every platform).
//!
//! # The metrics beyond Eq. (6)
//!
//! [`solver::SimulationConfig::metrics`] chooses what a run accumulates
//! besides the RMS values of BA, SDD, TDD and J ([`solver::Metrics`]; the
//! levels are ordered and the default costs what a step always did):
//! - always: the dynamic tire load `k_t (x_g − x_t)` (N) and
//!   `RMS(dynamic tire load) / W` with the static load
//!   `W = (m_s + m_h + m_t) g0` (CS: `(m_s + m_t) g0`);
//! - [`solver::Metrics::RoadHolding`]: the time without tire contact
//!   (dynamic tire load below −W, crossings located inside the steps), its
//!   first occurrence, and the largest |SDD| ([`solver::RoadHolding`]);
//! - [`solver::Metrics::Comfort`]: also the ISO 2631-1 W_k-weighted body
//!   acceleration a_w(t), its running RMS and the vibration dose value
//!   `VDV = (∫ a_w⁴ dt)^{1/4}` ([`solver::ComfortValues`]), the filter
//!   integrated as 8 more states of the exact step.
//!
//! The outputs the levels share are the same to the bit at every level.
//! [`analysis::optimize::Objective::Comfort`] minimises RMS a_w under
//! road-holding, travel and static-sag constraints.
//!
//! **What this crate owns and must never import.** It owns the physics and
//! the numerics. It has no FFI and no `unsafe` outside the solver's
//! whole-step loop (`solver::kernel`), and it never imports a command-line,
//! progress-display or JSON crate (clap, indicatif, serde_json) nor the FMU
//! layers: the co-simulation slave (`tdvass-fmu`), the FMI 2.0 FMU
//! (`tdvass-fmi2`) and the command line (`tdvass-cli`) are built on it,
//! never the other way round.
//!
//! # Example: Table 2, TDVASS row
//!
//! The paper's harmonic road `x_g = 0.05 sin 5t` (m), 15 s from rest, the
//! TDVASS with g1 = 5386 N/m and tau1 = 2e-4 s (the defaults of
//! [`Params`]); RMS values over the whole run:
//!
//! ```
//! use tdvass::road::RoadSpec;
//! use tdvass::solver::{SimulationConfig, simulate};
//! use tdvass::{Params, Variant};
//!
//! let config = SimulationConfig {
//!     variant: Variant::Tdvass,
//!     params: Params::with_controller(5386.0, 2e-4), // g (N/m), tau (s)
//!     road: RoadSpec::Harmonic { amplitude: 0.05, angular_frequency: 5.0 }, // m, rad/s
//!     ..SimulationConfig::default()
//! };
//! let run = simulate(config, 15.0)?; // 15 s
//! let body_acceleration = run.rms.body_acceleration; // m/s²
//! let suspension_deflection = run.rms.suspension_deflection; // m
//! let tire_deflection_mm = run.rms.tire_deflection * 1e3; // mm
//! // The paper prints 0.3068 m/s², 0.0388 m and 0.6251 mm.
//! assert!((body_acceleration - 0.3069).abs() < 5e-5);
//! assert!((suspension_deflection - 0.0388).abs() < 5e-5);
//! assert!((tire_deflection_mm - 0.6250).abs() < 5e-5);
//! # Ok::<(), tdvass::Error>(())
//! ```
//!
//! For a run driven step by step (the FMU's way), build a
//! [`solver::Simulator`] from the same configuration and call
//! `advance_to(t)` and `outputs()`.
//!
//! # The analyses
//!
//! - [`analysis::stability::StabilityReport::compute`]: section 3 for one
//!   gain (Routh–Hurwitz range, delay-independent bound, crossings,
//!   critical delays, stable delay intervals);
//! - [`analysis::spectrum::spectral_abscissa`]: the real part of the
//!   rightmost characteristic root at one (g, tau);
//! - [`analysis::frf::frequency_response`]: `|X_s/X_g|` and `|A_s/X_g|` of
//!   Eq. (4), (5);
//! - [`analysis::pso::pso_minimize`]: the particle swarm optimiser of
//!   Eq. (7), and [`analysis::optimize::optimize`] for the paper's two
//!   problems.
//!
//! Each has a short example in its documentation.

#![deny(unsafe_code)]

pub mod analysis;
pub mod bytes;
pub mod car;
pub mod chassis;
pub mod comfort;
pub mod error;
pub mod exchange;
pub mod limits;
pub mod math;
pub mod metrics;
pub mod model;
mod monotone;
pub mod road;
pub mod solver;

pub use error::{Error, Result};
pub use model::{Params, TireContact, Variant};
