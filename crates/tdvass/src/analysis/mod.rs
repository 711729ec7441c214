//! The paper's analyses: stability of the delay system (section 3),
//! frequency response (section 2.2, Eq. (3)-(5)) and particle swarm
//! optimisation (sections 2.3.2 and 4.2).

pub mod characteristic;
pub mod frf;
pub mod optimize;
pub mod polynomial;
pub mod pso;
pub mod spectrum;
pub mod stability;
