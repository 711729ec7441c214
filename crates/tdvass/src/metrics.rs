//! RMS values of BA, SDD, TDD, the objective J of Eq. (6), the sums of
//! squares the solver keeps for them, and the time averages every output
//! reports from the integrals of the continuous states
//! ([`time_averages`]: both engines read them so).

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

/// The time averages from the integrals `∫ y² dt` and `∫ a_w⁴ dt`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Averages {
    /// RMS BA, SDD, TDD.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
    /// RMS(a_w) (m/s²).
    pub rms_weighted_acceleration: f64,
    /// VDV (m/s^1.75).
    pub vibration_dose_value: f64,
    /// `k_t RMS(TDD) / W`.
    pub dynamic_tire_load_ratio: f64,
}

/// The time averages over `duration` (s) of the integrals `integral`
/// (the first five of [`crate::model::dynamics::INTEGRAL_NAMES`]; negative
/// rounding counts as 0):
/// `sqrt(∫y²/duration)` (0 before any time has passed), J with `weights`,
/// `VDV = (∫a_w⁴)^{1/4}`, and the tire-load ratio with `k_t` (N/m) and
/// the static load W (N).
pub fn time_averages(
    integral: &[f64],
    duration: f64,
    weights: &Weights,
    k_t: f64,
    static_load: f64,
) -> Averages {
    let rms = rms_values(integral, duration);
    let (rms_weighted_acceleration, vibration_dose_value) =
        weighted_averages(integral[3], integral[4], duration);
    Averages {
        rms,
        objective: rms.objective(weights),
        rms_weighted_acceleration,
        vibration_dose_value,
        dynamic_tire_load_ratio: tire_load_ratio(k_t, rms.tire_deflection, static_load),
    }
}

/// `(RMS(a_w), VDV)` from `∫ a_w² dt` and `∫ a_w⁴ dt` over `duration`:
/// `sqrt(∫a_w²/duration)` (0 before any time has passed) and
/// `(∫a_w⁴)^{1/4}`.
pub fn weighted_averages(square: f64, fourth: f64, duration: f64) -> (f64, f64) {
    let rms = if duration > 0.0 {
        (square.max(0.0) / duration).sqrt()
    } else {
        0.0
    };
    (rms, fourth.max(0.0).sqrt().sqrt())
}

/// `∂ sqrt(I / duration) / ∂I = 1 / (2 sqrt(I duration))`: the partial of
/// a running RMS with respect to its integral `I = ∫ y² dt`, taken as 0
/// where the integral or the duration is 0 (the square root's slope is
/// unbounded there).
#[inline]
pub fn rms_slope(integral: f64, duration: f64) -> f64 {
    if duration > 0.0 && integral > 0.0 {
        0.5 / (integral * duration).sqrt()
    } else {
        0.0
    }
}

/// `∂ I^{1/4} / ∂I = I^{−3/4} / 4`: the partial of a vibration dose value
/// with respect to its integral `I = ∫ a_w⁴ dt`, taken as 0 where the
/// integral is 0.
#[inline]
pub fn dose_slope(fourth: f64) -> f64 {
    if fourth > 0.0 {
        0.25 / fourth.powf(0.75)
    } else {
        0.0
    }
}

/// The running RMS of the dynamic tire load over the static load W (N):
/// `k_t RMS(TDD) / W`, k_t (N/m), RMS(TDD) (m).
pub fn tire_load_ratio(k_t: f64, rms_tire_deflection: f64, static_load: f64) -> f64 {
    k_t * rms_tire_deflection / static_load
}

/// The running RMS values of BA, SDD and TDD from their integrals
/// `∫ y² dt` over `duration` (all 0 before any time has passed).
pub fn rms_values(integral: &[f64], duration: f64) -> RmsValues {
    if duration <= 0.0 {
        return RmsValues::default();
    }
    let rms = |i: usize| (integral[i].max(0.0) / duration).sqrt();
    RmsValues {
        body_acceleration: rms(0),
        suspension_deflection: rms(1),
        tire_deflection: rms(2),
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

    #[test]
    fn the_averages_are_zero_at_the_start_and_follow_the_integrals() {
        let weights = Weights::default();
        let zero = time_averages(&[1.0; 5], 0.0, &weights, 1.0, 1.0);
        assert_eq!(zero.rms, RmsValues::default());
        assert_eq!(zero.rms_weighted_acceleration, 0.0);
        let later = time_averages(&[4.0, 9.0, 16.0, 25.0, 16.0], 1.0, &weights, 2.0, 8.0);
        assert_eq!(later.rms.tire_deflection, 4.0);
        assert_eq!(later.rms_weighted_acceleration, 5.0);
        assert_eq!(later.vibration_dose_value, 2.0);
        assert_eq!(later.dynamic_tire_load_ratio, 1.0);
    }
}
