//! Stability of the delay system (paper section 3, corrected by notes.md
//! section 2).
//!
//! The characteristic equation of Eq. (8) is
//! `D(s, tau) = P(s) + Q(s) e^{-s tau} = 0` with s in 1/s and tau in s.
//! [`CharacteristicPolynomials`] (in `analysis::characteristic`) obtains P
//! and Q by expanding the determinant of the mass–spring–damper matrix of
//! Eq. (1) for any parameters; for the TDVASS it reproduces the a_0..a_6,
//! b_2..b_4 of Eq. (9).
//!
//! From them:
//! - [`routh_hurwitz_g_max`]: the end of the Routh–Hurwitz gain range of the
//!   delay-free system, Eq. (10) and Fig. 4 (171870.87 N/m for Table 1);
//! - [`delay_independent_g_max`]: the largest |g| for which F(ω) of
//!   Eq. (14)-(15) has no positive root (24427.66 N/m for Table 1);
//! - [`crossings`] and [`critical_delays`]: the imaginary-axis crossings,
//!   their direction (Eq. (17)) and the critical delays of Eq. (13), (16);
//! - [`stable_delay_intervals`]: the union of stable delay intervals
//!   (notes.md item 2.3);
//! - [`stability_map`]: the (g, tau) map of Fig. 8 with the spectral
//!   abscissa of every point.
//!
//! Gains g are in N/m, frequencies ω in rad/s, delays tau in s.

use super::parallel::in_parallel;
pub use crate::analysis::characteristic::CharacteristicPolynomials;
use crate::analysis::characteristic::{parts_on_imaginary_axis, squared_modulus_on_imaginary_axis};
use crate::analysis::polynomial::Polynomial;
use crate::analysis::spectrum::{CharacteristicRootSolver, RootTracker};
use crate::error::{Error, Result};
use crate::model::{Params, Variant};
use nalgebra::Complex;
use std::f64::consts::TAU as FULL_TURN;

/// The Routh first column of Fig. 4 for a real polynomial, normalised to a
/// positive leading coefficient. The polynomial is Hurwitz (all roots in
/// Re s < 0) iff every entry is > 0; a zero pivot stops the table (the
/// column is then shorter than degree + 1 and the test fails).
pub fn routh_first_column(polynomial: &Polynomial) -> Vec<f64> {
    let Some(degree) = polynomial.degree() else {
        return Vec::new();
    };
    let sign = polynomial.coefficient(degree).signum();
    let descending: Vec<f64> = (0..=degree)
        .rev()
        .map(|k| sign * polynomial.coefficient(k))
        .collect();
    let mut upper: Vec<f64> = descending.iter().step_by(2).copied().collect();
    let mut lower: Vec<f64> = descending.iter().skip(1).step_by(2).copied().collect();
    let mut column = vec![upper[0]];
    for _ in 0..degree {
        let pivot = lower.first().copied().unwrap_or(0.0);
        column.push(pivot);
        if pivot <= 0.0 || !pivot.is_finite() {
            break;
        }
        let next: Vec<f64> = (0..upper.len().saturating_sub(1))
            .map(|j| {
                let upper_next = upper.get(j + 1).copied().unwrap_or(0.0);
                let lower_next = lower.get(j + 1).copied().unwrap_or(0.0);
                (pivot * upper_next - upper[0] * lower_next) / pivot
            })
            .collect();
        upper = lower;
        lower = next;
    }
    column
}

/// Whether all roots of `polynomial` have negative real part, by the Routh
/// table (Fig. 4): the first column has degree + 1 entries, all positive.
pub fn is_hurwitz(polynomial: &Polynomial) -> bool {
    let Some(degree) = polynomial.degree() else {
        return false;
    };
    let column = routh_first_column(polynomial);
    column.len() == degree + 1 && column.iter().all(|&entry| entry > 0.0)
}

/// The TDVASS characteristic polynomials at gain `gain` (N/m).
fn tdvass_polynomials(params: &Params, gain: f64) -> Result<CharacteristicPolynomials> {
    if !gain.is_finite() {
        return Err(Error::InvalidParameter {
            name: "g",
            value: gain,
            reason: "must be finite",
        });
    }
    CharacteristicPolynomials::new(&Params { g: gain, ..*params }, Variant::Tdvass)
}

/// The gains (N/m) at which the delay-free TDVASS, Eq. (10), has a root on
/// the imaginary axis, sorted. `D(s, 0) = P(s) + g Q_1(s)` with
/// `Q_1 = Q / g`; a root `s = iω` (ω > 0) needs `Im(P(iω) conj Q_1(iω)) = 0`
/// and then `g = -Re(P(iω) conj Q_1(iω)) / |Q_1(iω)|²`. (`D(0, 0) = a_0`
/// does not depend on g, and deg Q < deg P, so these are the only gains where
/// the Routh–Hurwitz verdict can change.)
fn zero_delay_boundary_gains(params: &Params) -> Result<Vec<f64>> {
    let unit = tdvass_polynomials(params, 1.0)?;
    let p = unit.p_polynomial();
    let q_unit = unit.q_polynomial();
    let (p_real, p_imaginary) = parts_on_imaginary_axis(&p);
    let (q_real, q_imaginary) = parts_on_imaginary_axis(&q_unit);
    let cross = &(&p_imaginary * &q_real) - &(&p_real * &q_imaginary);
    if cross.is_zero() {
        return Ok(Vec::new());
    }
    // `cross` is odd in ω: divide by ω, then write it in z = ω².
    let divided = Polynomial::new(cross.coefficients().iter().skip(1).copied().collect());
    let Some(in_square) = divided.even_part_in_square() else {
        return Err(Error::Numerical {
            what: "Routh-Hurwitz boundary",
            reason: "Im(P(iw) conj Q(iw)) is not odd in w".to_string(),
        });
    };
    if in_square.degree().unwrap_or(0) == 0 {
        return Ok(Vec::new());
    }
    let mut gains = Vec::new();
    for z in in_square.real_roots(1e-7)? {
        if z <= 0.0 {
            continue;
        }
        let s = Complex::new(0.0, z.sqrt());
        let p_value = p.eval_complex(s);
        let q_value = q_unit.eval_complex(s);
        let q_norm = q_value.norm_sqr();
        if q_norm > 0.0 && q_norm.is_finite() {
            gains.push(-(p_value * q_value.conj()).re / q_norm);
        }
    }
    gains.sort_by(f64::total_cmp);
    gains.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * a.abs().max(1.0));
    Ok(gains)
}

/// The gain ranges (N/m) on which the delay-free TDVASS (tau = 0, Eq. (10))
/// is Routh–Hurwitz stable, as open intervals `(from, to)` (infinite ends
/// allowed). The ends are exact (roots of a polynomial, Newton-polished);
/// at an end a root pair sits on the imaginary axis, so ends are excluded
/// (two intervals sharing an end mean the root locus touches the axis there
/// and returns).
pub fn routh_hurwitz_intervals(params: &Params) -> Result<Vec<(f64, f64)>> {
    let boundaries = zero_delay_boundary_gains(params)?;
    let mut edges = vec![f64::NEG_INFINITY];
    edges.extend(boundaries.iter().copied());
    edges.push(f64::INFINITY);
    let mut intervals: Vec<(f64, f64)> = Vec::new();
    for window in edges.windows(2) {
        let (from, to) = (window[0], window[1]);
        let probe = match (from.is_finite(), to.is_finite()) {
            (true, true) => 0.5 * (from + to),
            (true, false) => from + from.abs().max(1.0),
            (false, true) => to - to.abs().max(1.0),
            (false, false) => 0.0,
        };
        if is_hurwitz(&tdvass_polynomials(params, probe)?.zero_delay()) {
            intervals.push((from, to));
        }
    }
    Ok(intervals)
}

/// The largest gain g (N/m) for which the delay-free TDVASS, Eq. (10), is
/// Routh–Hurwitz stable (first column of Fig. 4 all positive): the upper end
/// of the highest stable gain range, an open bound. 171870.87 N/m for
/// Table 1 (notes.md item 2.4). `+inf` if stable for all large g, NaN if
/// stable for no g.
pub fn routh_hurwitz_g_max(params: &Params) -> Result<f64> {
    Ok(routh_hurwitz_intervals(params)?
        .last()
        .map_or(f64::NAN, |interval| interval.1))
}

/// The delay-independent stability bound (section 3.1, Eq. (15)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayIndependentBound {
    /// Largest |g| (N/m): for |g| below it F(ω) has no positive root and the
    /// system is stable for every delay. NaN if the uncontrolled system is
    /// not stable (no gain is delay-independent stable).
    pub gain: f64,
    /// Frequency ω (rad/s) where F touches zero at |g| = gain.
    pub tangency_omega: f64,
}

/// The delay-independent stability bound of section 3.1: with
/// `Q = g Q_1`, `F(ω) = |P(iω)|² - g² |Q_1(iω)|²` has no positive root iff
/// `g² < min_{ω>0} |P(iω)|² / |Q_1(iω)|²`; the minimum is found among the
/// positive roots of the derivative of that ratio (a polynomial in ω²).
/// Below this bound no root can reach the imaginary axis for any g or tau,
/// so the system is stable for all delays iff the uncontrolled P is
/// Hurwitz. notes.md item 2.4: 24427.66 N/m, tangency at ω ≈ 69.02 rad/s.
pub fn delay_independent_bound(params: &Params) -> Result<DelayIndependentBound> {
    let unit = tdvass_polynomials(params, 1.0)?;
    let p = unit.p_polynomial();
    if !is_hurwitz(&p) {
        return Ok(DelayIndependentBound {
            gain: f64::NAN,
            tangency_omega: f64::NAN,
        });
    }
    let p_modulus = squared_modulus_on_imaginary_axis(&p);
    let q_modulus = squared_modulus_on_imaginary_axis(&unit.q_polynomial());
    let ratio_at = |z: f64| p_modulus.eval(z) / q_modulus.eval(z);
    let stationarity =
        &(&p_modulus.derivative() * &q_modulus) - &(&p_modulus * &q_modulus.derivative());
    let mut best = DelayIndependentBound {
        gain: f64::INFINITY,
        tangency_omega: f64::NAN,
    };
    let mut candidates: Vec<f64> = if stationarity.is_zero() {
        Vec::new()
    } else {
        stationarity
            .real_roots(1e-7)?
            .into_iter()
            .filter(|&z| z > 0.0)
            .collect()
    };
    if q_modulus.eval(0.0) > 0.0 {
        candidates.push(0.0);
    }
    for z in candidates {
        let ratio = ratio_at(z);
        if ratio.is_finite() && ratio >= 0.0 && ratio.sqrt() < best.gain {
            best = DelayIndependentBound {
                gain: ratio.sqrt(),
                tangency_omega: z.sqrt(),
            };
        }
    }
    Ok(best)
}

/// The largest |g| (N/m) for which the TDVASS is stable for every delay
/// (section 3.1): see [`delay_independent_bound`]. 24427.66 N/m for Table 1.
pub fn delay_independent_g_max(params: &Params) -> Result<f64> {
    Ok(delay_independent_bound(params)?.gain)
}

/// A crossing of a characteristic root pair `±iω` through the imaginary axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Crossing frequency ω > 0 (rad/s), a positive root of F(ω), Eq. (15).
    pub omega: f64,
    /// `sgn F'(ω)` of Eq. (17): +1 the pair moves to the right half-plane as
    /// tau increases (destabilising), -1 to the left (stabilising), 0 for a
    /// tangency (a double root of F: the pair touches the axis and returns).
    pub direction: i32,
    /// `θ = ω tau mod 2π` in [0, 2π) from Eq. (13): `e^{-iθ} = -P(iω)/Q(iω)`.
    pub theta: f64,
}

/// The imaginary-axis crossings of the TDVASS at gain `gain` (N/m): all
/// positive roots ω of F(ω) = |P(iω)|² − |Q(iω)|² (Eq. (14)-(15)), sorted by
/// ω, with their direction (Eq. (17)) and θ (Eq. (13)).
///
/// F is a polynomial in ω²; its roots come from the companion matrix, each
/// refined by Newton on the directly evaluated F(ω). Roots closer than 1e-6
/// (relative) are merged; a merged group across which F does not change
/// sign is a tangency (`direction = 0`). At g = ±50000 for Table 1:
/// ω = 62.3487 (−1) and 75.1147 (+1), notes.md item 2.2.
pub fn crossings(params: &Params, gain: f64) -> Result<Vec<Crossing>> {
    let polynomials = tdvass_polynomials(params, gain)?;
    let p = polynomials.p_polynomial();
    let q = polynomials.q_polynomial();
    if q.is_zero() {
        return Ok(Vec::new());
    }
    let discriminant = polynomials.discriminant_in_omega_squared();
    if discriminant.is_zero() {
        return Err(Error::Numerical {
            what: "stability crossings",
            reason: "F(w) vanishes identically (|P(iw)| = |Q(iw)| for all w)".to_string(),
        });
    }
    let f_of_omega = |omega: f64| {
        let s = Complex::new(0.0, omega);
        p.eval_complex(s).norm_sqr() - q.eval_complex(s).norm_sqr()
    };
    let dp = p.derivative();
    let dq = q.derivative();
    let f_slope = |omega: f64| {
        // d/dω |P(iω)|² = 2 Re(conj P(iω) · i P'(iω)), likewise for Q.
        let s = Complex::new(0.0, omega);
        let i = Complex::new(0.0, 1.0);
        2.0 * (p.eval_complex(s).conj() * i * dp.eval_complex(s)).re
            - 2.0 * (q.eval_complex(s).conj() * i * dq.eval_complex(s)).re
    };
    let mut omegas: Vec<f64> = discriminant
        .real_roots(1e-7)?
        .into_iter()
        .filter(|&z| z > 0.0)
        .map(f64::sqrt)
        .collect();
    omegas.sort_by(f64::total_cmp);
    let mut groups: Vec<Vec<f64>> = Vec::new();
    for omega in omegas {
        match groups.last_mut() {
            Some(group) if omega - group[group.len() - 1] <= 1e-6 * omega => group.push(omega),
            _ => groups.push(vec![omega]),
        }
    }
    let mut result = Vec::with_capacity(groups.len());
    for group in groups {
        let low = group[0] * (1.0 - 1e-6);
        let high = group[group.len() - 1] * (1.0 + 1e-6);
        let sign_low = f_of_omega(low).signum();
        let sign_high = f_of_omega(high).signum();
        let mut omega = group.iter().sum::<f64>() / group.len() as f64;
        let direction = if sign_low == sign_high {
            0
        } else {
            omega = refine_simple_root(&f_of_omega, &f_slope, omega, low, high);
            if sign_high > 0.0 { 1 } else { -1 }
        };
        let s = Complex::new(0.0, omega);
        let ratio = -p.eval_complex(s) / q.eval_complex(s);
        // e^{-iθ} = ratio  =>  θ = -arg(ratio)  (Eq. (13)).
        let theta = (-ratio.arg()).rem_euclid(FULL_TURN);
        let theta = if theta >= FULL_TURN { 0.0 } else { theta };
        result.push(Crossing {
            omega,
            direction,
            theta,
        });
    }
    Ok(result)
}

/// Newton on a simple root of f inside the bracket `[low, high]`, falling back
/// to the start value if an iterate leaves the bracket.
fn refine_simple_root(
    f: &dyn Fn(f64) -> f64,
    slope: &dyn Fn(f64) -> f64,
    start: f64,
    low: f64,
    high: f64,
) -> f64 {
    let mut x = start;
    for _ in 0..20 {
        let derivative = slope(x);
        if derivative == 0.0 || !derivative.is_finite() {
            break;
        }
        let next = x - f(x) / derivative;
        if !(low..=high).contains(&next) {
            return start;
        }
        let converged = (next - x).abs() <= 4.0 * f64::EPSILON * x;
        x = next;
        if converged {
            break;
        }
    }
    x
}

/// The critical delays `tau_n = (θ + 2nπ)/ω`, n = 0, 1, ... (Eq. (16)), in s,
/// that do not exceed `tau_max` (s), increasing.
pub fn critical_delays(crossing: &Crossing, tau_max: f64) -> Vec<f64> {
    let mut delays = Vec::new();
    let usable = crossing.omega > 0.0 && crossing.omega.is_finite() && tau_max.is_finite();
    if !usable {
        return delays;
    }
    for n in 0.. {
        let delay = (crossing.theta + FULL_TURN * n as f64) / crossing.omega;
        if delay > tau_max {
            break;
        }
        delays.push(delay);
    }
    delays
}

/// Number of roots of the delay-free TDVASS (Eq. (10)) in Re s > 0.
fn right_half_plane_roots_at_zero_delay(polynomials: &CharacteristicPolynomials) -> Result<i64> {
    Ok(polynomials
        .zero_delay()
        .roots()?
        .iter()
        .filter(|root| root.re > 0.0)
        .count() as i64)
}

/// The per-gain stability switching data: right-half-plane root count at
/// tau = 0 and the sorted critical delays with their direction.
#[derive(Debug, Clone)]
struct SwitchingSchedule {
    unstable_roots_at_zero_delay: i64,
    /// (critical delay in s, +1 destabilising / -1 stabilising), sorted by
    /// delay, stabilising first at equal delays.
    events: Vec<(f64, i32)>,
}

impl SwitchingSchedule {
    fn new(params: &Params, gain: f64, tau_max: f64) -> Result<SwitchingSchedule> {
        let polynomials = tdvass_polynomials(params, gain)?;
        let unstable_roots_at_zero_delay = right_half_plane_roots_at_zero_delay(&polynomials)?;
        let mut events = Vec::new();
        for crossing in crossings(params, gain)? {
            if crossing.direction == 0 {
                continue;
            }
            for delay in critical_delays(&crossing, tau_max) {
                if delay > 0.0 {
                    events.push((delay, crossing.direction));
                }
            }
        }
        events.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        Ok(SwitchingSchedule {
            unstable_roots_at_zero_delay,
            events,
        })
    }

    /// The stable delay intervals in [0, tau_max]: walks the events from the
    /// tau = 0 count, +2 per destabilising and −2 per stabilising crossing,
    /// and keeps the stretches where the count is 0.
    fn intervals(&self, tau_max: f64) -> Result<Vec<(f64, f64)>> {
        let mut count = self.unstable_roots_at_zero_delay;
        let mut intervals = Vec::new();
        let mut stable_since = (count == 0).then_some(0.0);
        for &(delay, direction) in &self.events {
            let next = count + 2 * direction as i64;
            if next < 0 {
                return Err(Error::Numerical {
                    what: "stability switching",
                    reason: format!(
                        "the right-half-plane root count became {next} at tau = {delay} s"
                    ),
                });
            }
            if count == 0 && next > 0 {
                if let Some(start) = stable_since.take()
                    && delay > start
                {
                    intervals.push((start, delay));
                }
            } else if count > 0 && next == 0 {
                stable_since = Some(delay);
            }
            count = next;
        }
        if let Some(start) = stable_since
            && tau_max > start
        {
            intervals.push((start, tau_max));
        }
        Ok(intervals)
    }

    /// Whether the system is asymptotically stable at `tau` (s): no
    /// right-half-plane roots after the events at delays below tau.
    fn is_stable_at(&self, tau: f64) -> bool {
        let passed = self.events.partition_point(|&(delay, _)| delay < tau);
        let change: i64 = self.events[..passed]
            .iter()
            .map(|&(_, direction)| 2 * direction as i64)
            .sum();
        let on_boundary = self
            .events
            .get(passed)
            .is_some_and(|&(delay, _)| delay == tau);
        self.unstable_roots_at_zero_delay + change == 0 && !on_boundary
    }
}

/// The delays tau in [0, tau_max] (s) for which the TDVASS with gain
/// `gain` (N/m) is asymptotically stable, as a union of intervals
/// `(from, to)`: the first starts at 0 (closed) if the delay-free system is
/// stable, the others are open; an interval ending at `tau_max` means
/// stable up to tau_max.
///
/// Count of right-half-plane roots at tau = 0 from the roots of P + Q, then
/// +2 at each destabilising and −2 at each stabilising critical delay, in
/// increasing order (section 3.2 with notes.md items 2.2–2.3).
pub fn stable_delay_intervals(params: &Params, gain: f64, tau_max: f64) -> Result<Vec<(f64, f64)>> {
    check_tau_max(tau_max)?;
    SwitchingSchedule::new(params, gain, tau_max)?.intervals(tau_max)
}

fn check_tau_max(tau_max: f64) -> Result<()> {
    if tau_max.is_finite() && tau_max >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: "tau_max",
            value: tau_max,
            reason: "must be finite and >= 0",
        })
    }
}

/// One crossing with its critical delays up to tau_max.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossingDelays {
    /// The crossing (ω in rad/s, direction, θ).
    pub crossing: Crossing,
    /// Its critical delays (s), Eq. (16).
    pub critical_delays: Vec<f64>,
}

/// Everything section 3 says about one gain: the `tdvass stability` report.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityReport {
    /// Gain analysed (N/m).
    pub gain: f64,
    /// Largest delay considered (s).
    pub tau_max: f64,
    /// See [`routh_hurwitz_g_max`] (N/m).
    pub routh_hurwitz_g_max: f64,
    /// See [`delay_independent_g_max`] (N/m).
    pub delay_independent_g_max: f64,
    /// Crossings at `gain` with their critical delays up to tau_max.
    pub crossings: Vec<CrossingDelays>,
    /// Stable delay intervals in [0, tau_max] (s).
    pub stable_intervals: Vec<(f64, f64)>,
}

impl StabilityReport {
    /// Runs the analyses of section 3 for `gain` (N/m) up to `tau_max` (s);
    /// the other parameters come from `params` (its g and tau are ignored).
    ///
    /// Section 3 at g = 50000 N/m with the Table 1 parameters:
    ///
    /// ```
    /// use tdvass::Params;
    /// use tdvass::analysis::stability::StabilityReport;
    ///
    /// let report = StabilityReport::compute(&Params::default(), 50000.0, 0.5)?; // N/m, s
    /// assert!((report.routh_hurwitz_g_max - 171870.87).abs() < 0.01); // N/m
    /// let omegas: Vec<f64> = report.crossings.iter().map(|c| c.crossing.omega).collect();
    /// assert!((omegas[0] - 62.3487).abs() < 1e-4 && (omegas[1] - 75.1147).abs() < 1e-4); // rad/s
    /// // Stable for tau in [0, 0.0502) ∪ (0.0945, 0.1338) ∪ ... (s)
    /// let (from, to) = report.stable_intervals[0];
    /// assert_eq!(from, 0.0);
    /// assert!((to - 0.0502).abs() < 1e-4);
    /// assert!((report.stable_intervals[1].0 - 0.0945).abs() < 1e-4);
    /// # Ok::<(), tdvass::Error>(())
    /// ```
    pub fn compute(params: &Params, gain: f64, tau_max: f64) -> Result<StabilityReport> {
        check_tau_max(tau_max)?;
        let crossings = crossings(params, gain)?
            .into_iter()
            .map(|crossing| CrossingDelays {
                crossing,
                critical_delays: critical_delays(&crossing, tau_max),
            })
            .collect();
        Ok(StabilityReport {
            gain,
            tau_max,
            routh_hurwitz_g_max: routh_hurwitz_g_max(params)?,
            delay_independent_g_max: delay_independent_g_max(params)?,
            crossings,
            stable_intervals: stable_delay_intervals(params, gain, tau_max)?,
        })
    }
}

/// One point of the (g, tau) stability map (Fig. 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapPoint {
    /// Gain (N/m).
    pub g: f64,
    /// Delay (s).
    pub tau: f64,
    /// Asymptotic stability from the crossing analysis (section 3.2).
    pub stable: bool,
    /// Real part (1/s) of the rightmost characteristic root.
    pub spectral_abscissa: f64,
}

/// The stability map over `g_values` × `tau_values` (Fig. 8), in g-major
/// order (all delays of the first gain, then the next gain).
///
/// `stable` comes from the crossing analysis of each gain
/// ([`stable_delay_intervals`]); the spectral abscissa from
/// [`RootTracker`]: the Chebyshev spectral method of
/// [`crate::analysis::spectrum`] at a subset of delays, Newton continuation
/// of the rightmost roots in between, seeded with the exact imaginary-axis
/// roots at every critical delay passed. Gains are processed in parallel
/// on all available cores (std scoped threads).
pub fn stability_map(
    params: &Params,
    g_values: &[f64],
    tau_values: &[f64],
) -> Result<Vec<MapPoint>> {
    params.validate()?;
    check_map_axes(g_values, tau_values)?;
    let tau_max = tau_values.iter().copied().fold(0.0, f64::max);
    let columns = in_parallel(g_values, "stability map", |g| {
        map_column(params, g, tau_values, tau_max)
    })?;
    Ok(columns.into_iter().flatten().collect())
}

/// The map's axes: finite gains, finite delays >= 0.
fn check_map_axes(g_values: &[f64], tau_values: &[f64]) -> Result<()> {
    for &tau in tau_values {
        if !(tau.is_finite() && tau >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                reason: "map delays must be finite and >= 0",
            });
        }
    }
    for &g in g_values {
        if !g.is_finite() {
            return Err(Error::InvalidParameter {
                name: "g",
                value: g,
                reason: "must be finite",
            });
        }
    }
    Ok(())
}

/// The map's points at gain g over `tau_values` (in their order): the
/// crossing analysis for `stable`, the rightmost roots tracked over the
/// delays in increasing order.
fn map_column(params: &Params, g: f64, tau_values: &[f64], tau_max: f64) -> Result<Vec<MapPoint>> {
    let schedule = SwitchingSchedule::new(params, g, tau_max)?;
    let solver = CharacteristicRootSolver::new(&Params { g, ..*params }, Variant::Tdvass)?;
    let critical: Vec<(f64, f64)> = crossings(params, g)?
        .iter()
        .filter(|c| c.direction != 0)
        .flat_map(|c| {
            critical_delays(c, tau_max)
                .into_iter()
                .map(move |delay| (delay, c.omega))
        })
        .collect();
    let mut tracker = RootTracker::new(&solver, critical);
    let mut order: Vec<usize> = (0..tau_values.len()).collect();
    order.sort_by(|&a, &b| tau_values[a].total_cmp(&tau_values[b]));
    let mut abscissae = vec![f64::NAN; tau_values.len()];
    for index in order {
        abscissae[index] = tracker.spectral_abscissa(tau_values[index])?;
    }
    Ok(tau_values
        .iter()
        .zip(abscissae)
        .map(|(&tau, spectral_abscissa)| MapPoint {
            g,
            tau,
            stable: schedule.is_stable_at(tau),
            spectral_abscissa,
        })
        .collect())
}

#[cfg(test)]
mod tests;
