//! The paper's analyses: stability of the delay system (section 3),
//! frequency response (section 2.2, Eq. (3)-(5)) and particle swarm
//! optimisation (sections 2.3.2 and 4.2).
//!
//! Stability and the frequency response are about the linear model, the
//! paper's bilateral tire. The unilateral tire
//! ([`crate::solver::SimulationConfig::tire_contact`]) changes the
//! time-domain runs only, and so the optimisation, which runs them (its
//! stability filter stays that of the linear model).

pub mod characteristic;
pub mod frf;
pub mod optimize;
mod parallel;
pub mod polynomial;
pub mod pso;
pub mod spectrum;
pub mod stability;
