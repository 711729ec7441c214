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
    let tau_max = tau_values.iter().copied().fold(0.0, f64::max);
    let column = |g: f64| -> Result<Vec<MapPoint>> {
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
    };
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(g_values.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut columns: Vec<Option<Result<Vec<MapPoint>>>> = vec![None; g_values.len()];
    let finished: Vec<Vec<(usize, Result<Vec<MapPoint>>)>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let index = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if index >= g_values.len() {
                            break done;
                        }
                        done.push((index, column(g_values[index])));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|handle| {
                handle.join().unwrap_or_else(|_| {
                    vec![(
                        usize::MAX,
                        Err(Error::Numerical {
                            what: "stability map",
                            reason: "a worker thread panicked".to_string(),
                        }),
                    )]
                })
            })
            .collect()
    });
    for (index, result) in finished.into_iter().flatten() {
        if index == usize::MAX {
            result?;
        } else {
            columns[index] = Some(result);
        }
    }
    let mut points = Vec::with_capacity(g_values.len() * tau_values.len());
    for column in columns {
        match column {
            Some(result) => points.extend(result?),
            None => {
                return Err(Error::Numerical {
                    what: "stability map",
                    reason: "a gain column was not computed".to_string(),
                });
            }
        }
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Plant, X_T};
    use nalgebra::Matrix6;

    /// Printed precision of section 3.2; the paper's last digit may be
    /// rounded either way.
    const PRINTED: f64 = 1.5e-4;

    fn table1() -> Params {
        Params::default()
    }

    /// Parameters away from Table 1, to check that nothing is Table-1 specific.
    fn modified() -> Params {
        Params {
            m_s: 410.0,
            m_h: 7.5,
            m_t: 36.0,
            k_s: 21000.0,
            k_h: 9100.0,
            k_t: 175000.0,
            c_s: 1100.0,
            c_h: 510.0,
            g: -27000.0,
            tau: 0.01,
        }
    }

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance
    }

    #[test]
    fn tdvass_polynomials_are_the_printed_eq9() {
        for params in [Params::with_controller(50000.0, 0.0), modified()] {
            let Params {
                m_s,
                m_h,
                m_t,
                k_s,
                k_h,
                k_t,
                c_s,
                c_h,
                g,
                ..
            } = params;
            let a = [
                k_s * k_h * k_t,
                k_t * (c_h * k_s + c_s * k_h),
                c_h * c_s * k_t
                    + k_s * k_h * (m_s + m_h + m_t)
                    + k_s * k_t * (m_s + m_h)
                    + k_h * k_t * m_s,
                c_h * k_s * (m_s + m_h + m_t)
                    + c_s * k_h * (m_s + m_h + m_t)
                    + c_s * k_t * (m_s + m_h)
                    + c_h * k_t * m_s,
                c_h * c_s * (m_s + m_h + m_t)
                    + k_h * m_s * (m_h + m_t)
                    + k_s * m_t * (m_h + m_s)
                    + k_t * m_s * m_h,
                c_h * m_s * (m_h + m_t) + c_s * m_t * (m_h + m_s),
                m_s * m_h * m_t,
            ];
            let b = [
                0.0,
                0.0,
                -g * k_s * (m_s + m_h),
                -c_s * g * (m_s + m_h),
                -g * m_s * m_h,
            ];
            let polynomials = CharacteristicPolynomials::new(&params, Variant::Tdvass).unwrap();
            assert_eq!(polynomials.p.len(), 7);
            assert_eq!(polynomials.q.len(), 5);
            for (got, want) in polynomials.p.iter().zip(a) {
                assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} vs {want}");
            }
            for (got, want) in polynomials.q.iter().zip(b) {
                assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} vs {want}");
            }
        }
    }

    #[test]
    fn cs_and_pvass_have_no_delayed_term() {
        let cs = CharacteristicPolynomials::new(&table1(), Variant::Cs).unwrap();
        assert_eq!(cs.p.len(), 5);
        assert!(cs.q.is_empty());
        let p = table1();
        assert_eq!(cs.p[4], p.m_s * p.m_t);
        assert_eq!(cs.p[0], p.k_s * p.k_t);
        let pvass = CharacteristicPolynomials::new(&table1(), Variant::Pvass).unwrap();
        assert_eq!(pvass.p.len(), 7);
        assert!(pvass.q.is_empty());
        assert!(
            CharacteristicPolynomials::new(
                &Params {
                    m_t: 0.0,
                    ..table1()
                },
                Variant::Cs
            )
            .is_err()
        );
    }

    /// `det(s I - A - b e_{x_t}^T e^{-s tau})` from the plant of Eq. (2).
    fn plant_determinant(params: &Params, variant: Variant, s: Complex<f64>) -> Complex<f64> {
        let plant = Plant::new(*params, variant).unwrap();
        let delay = (-s * params.tau).exp();
        let mut matrix = Matrix6::<Complex<f64>>::identity() * s;
        for row in 0..6 {
            for column in 0..6 {
                matrix[(row, column)] -= plant.a[(row, column)];
            }
            matrix[(row, X_T)] -= plant.b[row] * delay;
        }
        matrix.determinant()
    }

    #[test]
    fn characteristic_function_is_the_plant_determinant() {
        let params = modified();
        for s in [
            Complex::new(-1.5, 7.0),
            Complex::new(0.3, 62.0),
            Complex::new(-20.0, -3.0),
        ] {
            for variant in Variant::ALL {
                let polynomials = CharacteristicPolynomials::new(&params, variant).unwrap();
                let (leading, dummy_factor) = match variant {
                    // The CS plant has two coordinates without dynamics: det = s² P / (m_s m_t).
                    Variant::Cs => (params.m_s * params.m_t, s * s),
                    _ => (params.m_s * params.m_h * params.m_t, Complex::new(1.0, 0.0)),
                };
                let expected = plant_determinant(&params, variant, s);
                let got = polynomials.evaluate(s, params.tau) / leading * dummy_factor;
                assert!(
                    (expected - got).norm() <= 1e-9 * expected.norm(),
                    "{variant:?} at {s}: {expected} vs {got}"
                );
            }
        }
    }

    #[test]
    fn routh_first_column_of_a_known_polynomial() {
        // s³ + s² + 2 s + 24: Routh column 1, 1, -22, 24 (two roots in Re s > 0).
        let p = Polynomial::new(vec![24.0, 2.0, 1.0, 1.0]);
        assert_eq!(routh_first_column(&p), vec![1.0, 1.0, -22.0]);
        assert!(!is_hurwitz(&p));
        // (s + 1)(s + 2)(s + 3) = s³ + 6 s² + 11 s + 6: column 1, 6, 10, 6.
        let q = Polynomial::new(vec![6.0, 11.0, 6.0, 1.0]);
        assert_eq!(routh_first_column(&q), vec![1.0, 6.0, 10.0, 6.0]);
        assert!(is_hurwitz(&q));
        assert!(is_hurwitz(&q.scaled(-2.0)));
        assert!(!is_hurwitz(&Polynomial::new(vec![1.0, 0.0, 1.0])));
    }

    fn rightmost_real_part(polynomial: &Polynomial) -> f64 {
        polynomial
            .roots()
            .unwrap()
            .iter()
            .map(|r| r.re)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn routh_hurwitz_bound_of_table1() {
        let g_max = routh_hurwitz_g_max(&table1()).unwrap();
        assert!(close(g_max, 171870.87, 0.01), "{g_max}");
        let below = tdvass_polynomials(&table1(), g_max * (1.0 - 1e-7))
            .unwrap()
            .zero_delay();
        let above = tdvass_polynomials(&table1(), g_max * (1.0 + 1e-7))
            .unwrap()
            .zero_delay();
        assert!(is_hurwitz(&below) && !is_hurwitz(&above));
        assert!(rightmost_real_part(&below) < 0.0 && rightmost_real_part(&above) > 0.0);
        let intervals = routh_hurwitz_intervals(&table1()).unwrap();
        assert_eq!(intervals.len(), 1);
        assert_eq!(intervals[0].0, f64::NEG_INFINITY);
    }

    #[test]
    fn routh_hurwitz_bound_agrees_with_bisection_for_other_parameters() {
        let params = modified();
        let hurwitz = |g: f64| is_hurwitz(&tdvass_polynomials(&params, g).unwrap().zero_delay());
        assert!(hurwitz(0.0));
        let mut high = 1000.0;
        while hurwitz(high) {
            high *= 2.0;
        }
        let mut low = high / 2.0;
        while high - low > 1e-9 * high {
            let middle = 0.5 * (low + high);
            if hurwitz(middle) {
                low = middle;
            } else {
                high = middle;
            }
        }
        let exact = routh_hurwitz_g_max(&params).unwrap();
        assert!(
            (exact - low).abs() <= 1e-8 * low,
            "{exact} vs bisection {low}"
        );
    }

    #[test]
    fn delay_independent_bound_of_table1() {
        let bound = delay_independent_bound(&table1()).unwrap();
        assert!(close(bound.gain, 24427.66, 0.01), "{bound:?}");
        assert!(close(bound.tangency_omega, 69.02, 0.005), "{bound:?}");
        assert_eq!(delay_independent_g_max(&table1()).unwrap(), bound.gain);
        for sign in [1.0, -1.0] {
            assert!(
                crossings(&table1(), sign * bound.gain * (1.0 - 1e-4))
                    .unwrap()
                    .is_empty()
            );
            let split = crossings(&table1(), sign * bound.gain * (1.0 + 1e-4)).unwrap();
            assert_eq!(split.len(), 2, "{split:?}");
            assert_eq!((split[0].direction, split[1].direction), (-1, 1));
            assert!(
                split
                    .iter()
                    .all(|c| close(c.omega, bound.tangency_omega, 0.5))
            );
            let intervals =
                stable_delay_intervals(&table1(), sign * bound.gain * 0.99, 0.5).unwrap();
            assert_eq!(intervals, vec![(0.0, 0.5)]);
        }
        assert!(bound.gain < routh_hurwitz_g_max(&table1()).unwrap());
    }

    #[test]
    fn delay_independent_bound_for_other_parameters_is_a_tangency() {
        let params = modified();
        let bound = delay_independent_bound(&params).unwrap();
        let f_min = |gain: f64| {
            let f = tdvass_polynomials(&params, gain)
                .unwrap()
                .discriminant_in_omega_squared();
            (1..4000)
                .map(|k| f.eval((k as f64 * 0.05).powi(2)))
                .fold(f64::INFINITY, f64::min)
        };
        assert!(f_min(bound.gain * 0.999) > 0.0);
        assert!(f_min(bound.gain * 1.001) < 0.0);
    }

    #[test]
    fn crossings_at_plus_and_minus_50000() {
        for gain in [50000.0, -50000.0] {
            let found = crossings(&table1(), gain).unwrap();
            assert_eq!(found.len(), 2, "{found:?}");
            assert!(close(found[0].omega, 62.3487, 5e-5), "{found:?}");
            assert_eq!(found[0].direction, -1);
            assert!(close(found[1].omega, 75.1147, 5e-5), "{found:?}");
            assert_eq!(found[1].direction, 1);
            for crossing in &found {
                assert!((0.0..FULL_TURN).contains(&crossing.theta));
                // The root iω solves Eq. (8) at the first critical delay.
                let polynomials = tdvass_polynomials(&table1(), gain).unwrap();
                let s = Complex::new(0.0, crossing.omega);
                let residual = polynomials.evaluate(s, crossing.theta / crossing.omega);
                let size = polynomials.p_polynomial().eval_complex(s).norm();
                assert!(residual.norm() <= 1e-10 * size, "{residual}");
            }
        }
    }

    #[test]
    fn critical_delays_of_section_3_2() {
        let series = |gain: f64, index: usize| {
            let found = crossings(&table1(), gain).unwrap();
            critical_delays(&found[index], 0.5)
        };
        // Index 1 is ω = 75.1147 (series τ1j, τ3j), index 0 is ω = 62.3487
        // (series τ2j, τ4j), notes.md item 2.2; τ15 = 0.3848 (item 2.1).
        let printed: [(f64, usize, [f64; 5]); 4] = [
            (50000.0, 1, [0.0501, 0.1338, 0.2174, 0.3011, 0.3848]),
            (50000.0, 0, [0.0945, 0.1952, 0.2960, 0.3968, 0.4976]),
            (-50000.0, 1, [0.0083, 0.0919, 0.1756, 0.2592, 0.3429]),
            (-50000.0, 0, [0.0441, 0.1449, 0.2456, 0.3464, 0.4472]),
        ];
        for (gain, index, expected) in printed {
            let delays = series(gain, index);
            assert!(delays.len() >= 5, "{delays:?}");
            for (got, want) in delays.iter().zip(expected) {
                assert!(close(*got, want, PRINTED), "g = {gain}: {got} vs {want}");
            }
        }
        let found = crossings(&table1(), 50000.0).unwrap();
        let delays = critical_delays(&found[1], 0.5);
        assert!(close(
            delays[1] - delays[0],
            FULL_TURN / found[1].omega,
            1e-12
        ));
        assert!(critical_delays(&found[1], 0.01).is_empty());
    }

    #[test]
    fn stable_delay_sets_are_unions_of_intervals() {
        let expected: [(f64, [(f64, f64); 4]); 2] = [
            (
                50000.0,
                [
                    (0.0, 0.0502),
                    (0.0945, 0.1338),
                    (0.1953, 0.2175),
                    (0.2961, 0.3011),
                ],
            ),
            (
                -50000.0,
                [
                    (0.0, 0.0083),
                    (0.0441, 0.0920),
                    (0.1449, 0.1756),
                    (0.2457, 0.2593),
                ],
            ),
        ];
        for (gain, want) in expected {
            let got = stable_delay_intervals(&table1(), gain, 0.5).unwrap();
            assert_eq!(got.len(), 4, "{got:?}");
            for (interval, reference) in got.iter().zip(want) {
                assert!(close(interval.0, reference.0, PRINTED), "{got:?}");
                assert!(close(interval.1, reference.1, PRINTED), "{got:?}");
            }
        }
    }

    #[test]
    fn beyond_the_routh_hurwitz_bound_the_zero_delay_system_is_unstable() {
        let gain = 180000.0;
        let intervals = stable_delay_intervals(&table1(), gain, 0.5).unwrap();
        assert!(
            intervals.iter().all(|interval| interval.0 > 0.0),
            "{intervals:?}"
        );
        let schedule = SwitchingSchedule::new(&table1(), gain, 0.5).unwrap();
        assert!(schedule.unstable_roots_at_zero_delay >= 2);
        assert!(!schedule.is_stable_at(0.0));
    }

    #[test]
    fn bad_input_is_reported() {
        assert!(crossings(&table1(), f64::NAN).is_err());
        assert!(stable_delay_intervals(&table1(), 5000.0, -1.0).is_err());
        assert!(stable_delay_intervals(&table1(), 5000.0, f64::INFINITY).is_err());
        let broken = Params {
            c_h: -3.0,
            ..table1()
        };
        assert!(routh_hurwitz_g_max(&broken).is_err());
        assert!(delay_independent_g_max(&broken).is_err());
        assert!(StabilityReport::compute(&broken, 1.0, 0.5).is_err());
        assert!(stability_map(&table1(), &[1.0], &[f64::NAN]).is_err());
        assert!(stability_map(&table1(), &[f64::INFINITY], &[0.1]).is_err());
        let undamped = Params {
            c_s: 0.0,
            c_h: 0.0,
            ..table1()
        };
        assert!(delay_independent_g_max(&undamped).unwrap().is_nan());
    }

    #[test]
    fn small_map_agrees_with_the_intervals_and_the_spectrum() {
        let gains = [-120000.0, -50000.0, 0.0, 20000.0, 50000.0, 100000.0];
        let delays = [0.0, 0.004, 0.03, 0.07, 0.11, 0.16, 0.2, 0.25, 0.33];
        let map = stability_map(&table1(), &gains, &delays).unwrap();
        assert_eq!(map.len(), gains.len() * delays.len());
        for (index, point) in map.iter().enumerate() {
            assert_eq!(point.g, gains[index / delays.len()]);
            assert_eq!(point.tau, delays[index % delays.len()]);
            let intervals = stable_delay_intervals(&table1(), point.g, 0.5).unwrap();
            let inside = intervals
                .iter()
                .any(|&(from, to)| point.tau >= from && point.tau < to);
            assert_eq!(point.stable, inside, "{point:?} {intervals:?}");
            assert_eq!(point.stable, point.spectral_abscissa < 0.0, "{point:?}");
        }
    }

    fn tdvass(g: f64, tau: f64) -> Params {
        Params::with_controller(g, tau)
    }

    /// The slowest test here: 225 full spectra, about 0.1 s with the crate's
    /// optimised test profile, about 5 s fully unoptimised.
    #[test]
    fn slow_spectrum_agrees_with_the_crossing_analysis_on_a_grid() {
        let params = Params::default();
        let gains: Vec<f64> = (0..15)
            .map(|i| -150000.0 + 300000.0 * i as f64 / 14.0)
            .collect();
        let delays: Vec<f64> = (0..15).map(|j| 0.45 * j as f64 / 14.0).collect();
        let mut compared = 0;
        for &g in &gains {
            let intervals = stable_delay_intervals(&params, g, 0.5).unwrap();
            let critical: Vec<f64> = crossings(&params, g)
                .unwrap()
                .iter()
                .flat_map(|c| critical_delays(c, 0.5))
                .collect();
            let solver = CharacteristicRootSolver::new(&tdvass(g, 0.0), Variant::Tdvass).unwrap();
            for &tau in &delays {
                if critical.iter().any(|&c| (c - tau).abs() < 1e-3) {
                    continue;
                }
                let by_crossings = intervals.iter().any(|&(from, to)| tau >= from && tau < to);
                let abscissa = solver.spectral_abscissa(tau).unwrap();
                assert_eq!(by_crossings, abscissa < 0.0, "g {g} tau {tau}: {abscissa}");
                compared += 1;
            }
        }
        assert!(compared > 200, "{compared}");
    }

    #[test]
    fn tracking_matches_fresh_spectra() {
        let solver =
            CharacteristicRootSolver::new(&tdvass(-50000.0, 0.0), Variant::Tdvass).unwrap();
        let found = crossings(&Params::default(), -50000.0).unwrap();
        let critical: Vec<(f64, f64)> = found
            .iter()
            .flat_map(|c| critical_delays(c, 0.45).into_iter().map(|d| (d, c.omega)))
            .collect();
        let mut tracker = RootTracker::new(&solver, critical).with_refresh_step(0.1);
        for k in 0..=60 {
            let tau = 0.45 * k as f64 / 60.0;
            let tracked = tracker.spectral_abscissa(tau).unwrap();
            let fresh = solver.spectral_abscissa(tau).unwrap();
            assert!(
                (tracked - fresh).abs() < 1e-8,
                "tau {tau}: {tracked} vs {fresh}"
            );
        }
    }
}
