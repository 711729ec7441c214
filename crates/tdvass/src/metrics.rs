//! RMS values of BA, SDD, TDD, the objective J of Eq. (6) and the sums of
//! squares the solver keeps for them.

use crate::model::Performance;

/// Weights z1, z2, z3 of Eq. (6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weights {
    /// z1, weight of the body acceleration RMS.
    pub body_acceleration: f64,
    /// z2, weight of the suspension deflection RMS.
    pub suspension_deflection: f64,
    /// z3, weight of the tire deflection RMS (TDD in metres).
    pub tire_deflection: f64,
}

impl Default for Weights {
    /// The paper's z1 = 0.4, z2 = 0.2, z3 = 0.4.
    fn default() -> Self {
        Weights {
            body_acceleration: 0.4,
            suspension_deflection: 0.2,
            tire_deflection: 0.4,
        }
    }
}

/// RMS values of the three performance outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RmsValues {
    /// RMS of BA (m/s²).
    pub body_acceleration: f64,
    /// RMS of SDD (m).
    pub suspension_deflection: f64,
    /// RMS of TDD (m).
    pub tire_deflection: f64,
}

impl RmsValues {
    /// The objective J of Eq. (6): `z1 RMS(BA) + z2 RMS(SDD) + z3 RMS(TDD)`.
    pub fn objective(&self, weights: &Weights) -> f64 {
        weights.body_acceleration * self.body_acceleration
            + weights.suspension_deflection * self.suspension_deflection
            + weights.tire_deflection * self.tire_deflection
    }
}

/// Sums of squares of BA, SDD, TDD over a run of samples. The solver's
/// whole-step loop keeps one per run of internal grid nodes, the node part
/// of the RMS time integral (`solver::time_average`); [`RunningRms::values`]
/// is the plain sample mean `sqrt(Σ_{k=1..n} y_k² / n)` of Eq. (6) as the
/// paper writes it, which the simulator's RMS outputs no longer use (they
/// are time averages).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RunningRms {
    /// Σ BA², Σ SDD², Σ TDD².
    pub sums_of_squares: [f64; 3],
    /// n, the number of samples.
    pub samples: u64,
}

impl RunningRms {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, y: &Performance) {
        self.sums_of_squares[0] += y.body_acceleration * y.body_acceleration;
        self.sums_of_squares[1] += y.suspension_deflection * y.suspension_deflection;
        self.sums_of_squares[2] += y.tire_deflection * y.tire_deflection;
        self.samples += 1;
    }

    /// Adds one sample given as its three values (BA, SDD, TDD).
    #[inline(always)]
    pub fn add_values(&mut self, body_acceleration: f64, suspension: f64, tire: f64) {
        self.sums_of_squares[0] += body_acceleration * body_acceleration;
        self.sums_of_squares[1] += suspension * suspension;
        self.sums_of_squares[2] += tire * tire;
        self.samples += 1;
    }

    /// The RMS values so far (zero before the first sample).
    pub fn values(&self) -> RmsValues {
        if self.samples == 0 {
            return RmsValues::default();
        }
        let n = self.samples as f64;
        RmsValues {
            body_acceleration: (self.sums_of_squares[0] / n).sqrt(),
            suspension_deflection: (self.sums_of_squares[1] / n).sqrt(),
            tire_deflection: (self.sums_of_squares[2] / n).sqrt(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rms_and_objective() {
        let mut rms = RunningRms::default();
        assert_eq!(rms.values(), RmsValues::default());
        for (a, s, t) in [(3.0, 1.0, -2.0), (-4.0, 1.0, 2.0)] {
            rms.add(&Performance {
                body_acceleration: a,
                suspension_deflection: s,
                tire_deflection: t,
            });
        }
        let v = rms.values();
        assert!((v.body_acceleration - 12.5f64.sqrt()).abs() < 1e-15);
        assert_eq!(v.suspension_deflection, 1.0);
        assert_eq!(v.tire_deflection, 2.0);
        let j = v.objective(&Weights::default());
        assert!((j - (0.4 * 12.5f64.sqrt() + 0.2 + 0.8)).abs() < 1e-15);
    }
}
