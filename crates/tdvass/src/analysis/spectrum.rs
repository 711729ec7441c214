//! Rightmost characteristic roots of the delay equation (paper section 3.3,
//! "characteristic root method").
//!
//! The TDVASS of Eq. (2) is the delay differential equation
//! `x'(t) = A x(t) + b x_t(t - tau)` (the delayed term is
//! `B x(t - tau)` with `B = b e_{x_t}^T`, column index 4). Its characteristic
//! roots s (1/s) solve Eq. (8), `P(s) + Q(s) e^{-s tau} = 0`.
//!
//! For tau > 0 the infinitesimal generator of the solution semigroup is
//! discretised by Chebyshev collocation (Breda–Maset–Vermiglio): the state
//! is `x(t)` plus the history of x_t on N Chebyshev points of [-tau, 0)
//! (only x_t is delayed, so the histories of the other five coordinates never
//! act on the dynamics and are left out; they would only add the
//! eigenvalues of the Dirichlet Chebyshev derivative). The eigenvalues of this
//! (6 + N)×(6 + N) matrix approximate the roots; the rightmost ones are
//! polished by Newton on `P(s) + Q(s) e^{-s tau}`. N grows with the delay
//! and the frequency scale of the roots (see
//! [`CharacteristicRootSolver::nodes_for_delay`]).
//!
//! For tau = 0 the roots are the eigenvalues of `A + B`. For the CS and the
//! PVASS (no delayed term) they are the roots of their own P(s): for the CS
//! the 6×6 plant has two dummy coordinates, so its 4th-order polynomial is
//! used instead.
//!
//! One spectrum costs about 0.1–0.5 ms for tau ≤ 0.5 s (N = 16–40). For the
//! (g, tau) map, [`RootTracker`] recomputes it only every 0.02 s of delay and
//! continues the rightmost roots by Newton in between (agreement with fresh
//! spectra to about 1e-8 1/s; a 400×400 map takes a few seconds).

use crate::analysis::characteristic::CharacteristicPolynomials;
use crate::analysis::polynomial::{Polynomial, matrix_eigenvalues, polish_root};
use crate::error::{Error, Result};
use crate::model::{Params, Plant, Variant, X_T};
use nalgebra::{Complex, DMatrix};

/// Smallest number of Chebyshev collocation nodes used for tau > 0.
pub const MIN_NODES: usize = 16;
/// Largest number of Chebyshev collocation nodes (reached at
/// tau ≈ 300 / Ω, about 3.8 s for Table 1 with g = 50000 N/m; one spectrum
/// then costs some 30 ms).
pub const MAX_NODES: usize = 200;

/// Characteristic roots of one variant and gain at any delay.
#[derive(Debug, Clone)]
pub struct CharacteristicRootSolver {
    variant: Variant,
    p: Polynomial,
    q: Polynomial,
    dp: Polynomial,
    dq: Polynomial,
    plant: Plant,
    frequency_scale: f64,
}

impl CharacteristicRootSolver {
    /// Prepares P, Q (Eq. (9)), the plant of Eq. (2) and the frequency scale
    /// (rad/s) of the roots for `params` (its g; tau is given per call).
    pub fn new(params: &Params, variant: Variant) -> Result<CharacteristicRootSolver> {
        let plant = Plant::new(*params, variant)?;
        let polynomials = CharacteristicPolynomials::new(params, variant)?;
        let p = polynomials.p_polynomial();
        let q = polynomials.q_polynomial();
        let mut frequency_scale: f64 = 1.0;
        for root in p
            .roots()?
            .into_iter()
            .chain(polynomials.zero_delay().roots()?)
        {
            frequency_scale = frequency_scale.max(root.im.abs());
        }
        if !q.is_zero() {
            for z in polynomials
                .discriminant_in_omega_squared()
                .real_roots(1e-7)?
            {
                if z > 0.0 {
                    frequency_scale = frequency_scale.max(z.sqrt());
                }
            }
        }
        Ok(CharacteristicRootSolver {
            variant,
            dp: p.derivative(),
            dq: q.derivative(),
            p,
            q,
            plant,
            frequency_scale,
        })
    }

    /// Whether the equation has a delayed term (TDVASS with g ≠ 0).
    pub fn has_delay_term(&self) -> bool {
        !self.q.is_zero()
    }

    /// Frequency scale Ω (rad/s): the largest imaginary part of the roots of
    /// P and P + Q and the largest crossing frequency (positive root of F,
    /// Eq. (15)); no root can reach the imaginary axis above the latter.
    pub fn frequency_scale(&self) -> f64 {
        self.frequency_scale
    }

    /// `D(s, tau)` of Eq. (8) and `∂D/∂s`.
    pub fn characteristic_value_and_slope(
        &self,
        s: Complex<f64>,
        tau: f64,
    ) -> (Complex<f64>, Complex<f64>) {
        let (p, dp) = (self.p.eval_complex(s), self.dp.eval_complex(s));
        if self.q.is_zero() {
            return (p, dp);
        }
        let (q, dq) = (self.q.eval_complex(s), self.dq.eval_complex(s));
        let delay_factor = (-s * tau).exp();
        (p + q * delay_factor, dp + (dq - q * tau) * delay_factor)
    }

    /// Newton's method on `D(s, tau) = 0` from `start`. Returns the root if
    /// the iteration converges (step below 1e-12 relative, or a residual
    /// below 1e-9 of the size of the terms), `None` otherwise.
    pub fn polish(&self, start: Complex<f64>, tau: f64) -> Option<Complex<f64>> {
        let mut s = start;
        for _ in 0..60 {
            let (value, slope) = self.characteristic_value_and_slope(s, tau);
            if !(value.re.is_finite() && value.im.is_finite()) || slope.norm() == 0.0 {
                return None;
            }
            let step = value / slope;
            s -= step;
            if !(s.re.is_finite() && s.im.is_finite()) {
                return None;
            }
            if step.norm() <= 1e-12 * s.norm().max(1.0) {
                return Some(s);
            }
        }
        let (value, _) = self.characteristic_value_and_slope(s, tau);
        let size =
            self.p.eval_complex(s).norm() + (self.q.eval_complex(s) * (-s * tau).exp()).norm();
        (value.norm() <= 1e-9 * size).then_some(s)
    }

    /// Number of Chebyshev nodes for delay `tau` (s):
    /// `N = 16 + 0.6 Ω tau`, capped to [`MIN_NODES`, `MAX_NODES`]. A degree-N
    /// Chebyshev interpolant resolves `e^{iωθ}` on [-tau, 0] once N exceeds
    /// about ω tau / 2; the eigenvalues only need to fall in Newton's basin.
    pub fn nodes_for_delay(&self, tau: f64) -> usize {
        let wanted = MIN_NODES as f64 + 0.6 * self.frequency_scale * tau;
        (wanted.ceil() as usize).clamp(MIN_NODES, MAX_NODES)
    }

    /// The (6 + N)×(6 + N) Chebyshev collocation matrix of the infinitesimal
    /// generator for delay `tau` > 0 (s) with `nodes` = N history points.
    ///
    /// Unknowns: x (6 states), then x_t at `θ_j = (tau/2)(cos(jπ/N) - 1)`,
    /// j = 1..N (θ_N = -tau). Rows: `x' = A x + b x_t(θ_N)` and
    /// `d/dθ x_t(θ_j) = Σ_k D_jk x_t(θ_k)` with `x_t(θ_0) = x_t(0)` the
    /// current state and D the Chebyshev differentiation matrix scaled by
    /// 2/tau.
    pub fn collocation_matrix(&self, tau: f64, nodes: usize) -> DMatrix<f64> {
        let n = nodes.max(1);
        let size = 6 + n;
        let mut matrix = DMatrix::<f64>::zeros(size, size);
        for row in 0..6 {
            for column in 0..6 {
                matrix[(row, column)] = self.plant.a[(row, column)];
            }
            matrix[(row, size - 1)] += self.plant.b[row];
        }
        let differentiation = chebyshev_differentiation(n);
        let scale = 2.0 / tau;
        for j in 1..=n {
            let row = 6 + j - 1;
            matrix[(row, X_T)] = scale * differentiation[(j, 0)];
            for k in 1..=n {
                matrix[(row, 6 + k - 1)] = scale * differentiation[(j, k)];
            }
        }
        matrix
    }

    /// Approximate roots (unpolished eigenvalues) at delay `tau` (s) with
    /// `nodes` Chebyshev nodes; for tau = 0 the eigenvalues of `A + B`.
    pub fn approximate_roots(&self, tau: f64, nodes: usize) -> Result<Vec<Complex<f64>>> {
        if !self.has_delay_term() {
            return self.p.roots();
        }
        if tau == 0.0 {
            let mut closed_loop = self.plant.a;
            for row in 0..6 {
                closed_loop[(row, X_T)] += self.plant.b[row];
            }
            return matrix_eigenvalues(DMatrix::from_column_slice(6, 6, closed_loop.as_slice()));
        }
        matrix_eigenvalues(self.collocation_matrix(tau, nodes))
    }

    /// Distinct polished roots from `candidates` at delay `tau`, sorted by
    /// decreasing real part (then decreasing imaginary part).
    pub fn polish_all(&self, candidates: &[Complex<f64>], tau: f64) -> Vec<Complex<f64>> {
        let mut roots: Vec<Complex<f64>> = candidates
            .iter()
            .filter_map(|&start| self.polish(start, tau))
            .collect();
        sort_rightmost_first(&mut roots);
        deduplicate(&mut roots);
        roots
    }

    /// The `count` rightmost characteristic roots (1/s) at delay `tau` (s),
    /// sorted by decreasing real part, conjugate pairs both listed.
    ///
    /// Eigenvalues of the collocation matrix (or of A + B, or the roots of
    /// P) polished by Newton; only converged roots are kept.
    pub fn rightmost_roots(&self, tau: f64, count: usize) -> Result<Vec<Complex<f64>>> {
        check_delay(tau)?;
        if self.variant != Variant::Tdvass || !self.has_delay_term() {
            let mut roots: Vec<Complex<f64>> = self
                .p
                .roots()?
                .into_iter()
                .map(|r| polish_root(&self.p, r, 4))
                .collect();
            sort_rightmost_first(&mut roots);
            roots.truncate(count);
            return Ok(roots);
        }
        let approximations = self.approximate_roots(tau, self.nodes_for_delay(tau))?;
        let mut roots = self.polish_all(&approximations, tau);
        if roots.is_empty() {
            return Err(Error::Numerical {
                what: "characteristic roots",
                reason: format!("Newton polishing failed for every eigenvalue at tau = {tau} s"),
            });
        }
        roots.truncate(count);
        Ok(roots)
    }

    /// Real part (1/s) of the rightmost root at delay `tau` (s).
    pub fn spectral_abscissa(&self, tau: f64) -> Result<f64> {
        let roots = self.rightmost_roots(tau, 1)?;
        roots.first().map(|r| r.re).ok_or(Error::Numerical {
            what: "spectral abscissa",
            reason: "no characteristic root found".to_string(),
        })
    }
}

fn check_delay(tau: f64) -> Result<()> {
    if tau.is_finite() && tau >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: "tau",
            value: tau,
            reason: "the delay must be finite and >= 0",
        })
    }
}

/// Chebyshev differentiation matrix on the N + 1 points `cos(jπ/N)` of
/// [-1, 1] (Trefethen, Spectral Methods in MATLAB, `cheb`), diagonal by the
/// negative-sum trick.
pub fn chebyshev_differentiation(nodes: usize) -> DMatrix<f64> {
    let n = nodes;
    let points: Vec<f64> = (0..=n)
        .map(|j| (std::f64::consts::PI * j as f64 / n as f64).cos())
        .collect();
    let weight = |j: usize| {
        let end = if j == 0 || j == n { 2.0 } else { 1.0 };
        if j.is_multiple_of(2) { end } else { -end }
    };
    let mut d = DMatrix::<f64>::zeros(n + 1, n + 1);
    for i in 0..=n {
        let mut row_sum = 0.0;
        for j in 0..=n {
            if i != j {
                let entry = weight(i) / weight(j) / (points[i] - points[j]);
                d[(i, j)] = entry;
                row_sum += entry;
            }
        }
        d[(i, i)] = -row_sum;
    }
    d
}

/// Sorts by decreasing real part, then decreasing imaginary part.
fn sort_rightmost_first(roots: &mut [Complex<f64>]) {
    roots.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
}

/// Removes roots that coincide (to 1e-8 relative) with an earlier one.
fn deduplicate(roots: &mut Vec<Complex<f64>>) {
    let mut kept: Vec<Complex<f64>> = Vec::with_capacity(roots.len());
    for &root in roots.iter() {
        if !kept
            .iter()
            .any(|k| (k - root).norm() <= 1e-8 * root.norm().max(1.0))
        {
            kept.push(root);
        }
    }
    *roots = kept;
}

/// Newton continuation of the rightmost roots along increasing delays, for
/// the stability map: a full spectral computation
/// ([`CharacteristicRootSolver::rightmost_roots`]) at the first delay and
/// whenever the delay has advanced by the refresh step since the last one;
/// in between, each tracked root is continued by an Euler predictor
/// (`ds/dtau = s Q e^{-s tau} / ∂D/∂s`) and Newton, and the exact roots
/// `±iω` at every critical delay passed (from the crossing analysis) are
/// added, so no root entering the right half-plane is missed.
#[derive(Debug)]
pub struct RootTracker<'a> {
    solver: &'a CharacteristicRootSolver,
    /// (critical delay in s, crossing frequency in rad/s), sorted by delay.
    critical: Vec<(f64, f64)>,
    tracked: Vec<Complex<f64>>,
    last_tau: Option<f64>,
    last_refresh: f64,
    refresh_step: f64,
}

/// Number of rightmost roots carried by a [`RootTracker`].
const TRACKED_ROOTS: usize = 12;

impl<'a> RootTracker<'a> {
    /// A tracker for `solver`; `critical` lists (critical delay (s),
    /// crossing frequency (rad/s)) pairs, in any order.
    pub fn new(solver: &'a CharacteristicRootSolver, critical: Vec<(f64, f64)>) -> RootTracker<'a> {
        let mut critical = critical;
        critical.sort_by(|a, b| a.0.total_cmp(&b.0));
        RootTracker {
            solver,
            critical,
            tracked: Vec::new(),
            last_tau: None,
            last_refresh: 0.0,
            refresh_step: 0.02,
        }
    }

    /// Sets the delay advance (s) after which the spectrum is recomputed
    /// from scratch (default 0.02 s).
    pub fn with_refresh_step(mut self, refresh_step: f64) -> RootTracker<'a> {
        self.refresh_step = refresh_step;
        self
    }

    /// Real part (1/s) of the rightmost root at `tau` (s). Delays must be
    /// passed in non-decreasing order; a smaller delay restarts the tracking.
    pub fn spectral_abscissa(&mut self, tau: f64) -> Result<f64> {
        check_delay(tau)?;
        let continuing = self
            .last_tau
            .filter(|&last| tau >= last && tau - self.last_refresh < self.refresh_step);
        let roots = match continuing {
            Some(last) => self.continued(last, tau),
            None => Vec::new(),
        };
        let roots = if roots.is_empty() {
            self.last_refresh = tau;
            self.solver.rightmost_roots(tau, TRACKED_ROOTS)?
        } else {
            roots
        };
        self.last_tau = Some(tau);
        self.tracked = roots;
        Ok(self.tracked[0].re)
    }

    fn continued(&self, last: f64, tau: f64) -> Vec<Complex<f64>> {
        let step = tau - last;
        let mut candidates: Vec<Complex<f64>> = self
            .tracked
            .iter()
            .map(|&s| s + self.root_velocity(s, last) * step)
            .collect();
        let first = self.critical.partition_point(|&(delay, _)| delay <= last);
        let end = self.critical.partition_point(|&(delay, _)| delay <= tau);
        for &(delay, omega) in &self.critical[first..end] {
            for on_axis in [Complex::new(0.0, omega), Complex::new(0.0, -omega)] {
                candidates.push(on_axis + self.root_velocity(on_axis, delay) * (tau - delay));
            }
        }
        let mut roots = self.solver.polish_all(&candidates, tau);
        roots.truncate(TRACKED_ROOTS);
        if roots.len() < self.tracked.len().min(TRACKED_ROOTS) / 2 {
            return Vec::new();
        }
        roots
    }

    /// `ds/dtau` along a root branch: `s Q(s) e^{-s tau} / ∂D/∂s`.
    fn root_velocity(&self, s: Complex<f64>, tau: f64) -> Complex<f64> {
        let (_, slope) = self.solver.characteristic_value_and_slope(s, tau);
        let delayed = self.solver.q.eval_complex(s) * (-s * tau).exp();
        if slope.norm() == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        s * delayed / slope
    }
}

/// The `count` rightmost characteristic roots (1/s) of `variant` at the
/// gain and delay of `params`, sorted by decreasing real part.
pub fn rightmost_roots(
    params: &Params,
    variant: Variant,
    count: usize,
) -> Result<Vec<Complex<f64>>> {
    CharacteristicRootSolver::new(params, variant)?.rightmost_roots(params.tau, count)
}

/// Real part (1/s) of the rightmost characteristic root of `variant` at the
/// gain and delay of `params`; the system is asymptotically stable iff it
/// is negative.
///
/// The paper's verification points A1* (stable) and A2* (unstable):
///
/// ```
/// use tdvass::analysis::spectrum::spectral_abscissa;
/// use tdvass::{Params, Variant};
///
/// let a1 = spectral_abscissa(&Params::with_controller(40000.0, 0.03), Variant::Tdvass)?; // N/m, s
/// let a2 = spectral_abscissa(&Params::with_controller(-40000.0, 0.11), Variant::Tdvass)?;
/// assert!((a1 - (-0.457)).abs() < 5e-4); // 1/s: decays like e^(-0.457 t)
/// assert!((a2 - 1.311).abs() < 5e-4); // 1/s: grows
/// # Ok::<(), tdvass::Error>(())
/// ```
pub fn spectral_abscissa(params: &Params, variant: Variant) -> Result<f64> {
    CharacteristicRootSolver::new(params, variant)?.spectral_abscissa(params.tau)
}

/// The `tdvass stable` report for one (g, tau).
#[derive(Debug, Clone, PartialEq)]
pub struct StableReport {
    /// Whether the spectral abscissa is negative.
    pub stable: bool,
    /// Real part (1/s) of the rightmost root.
    pub spectral_abscissa: f64,
    /// The rightmost roots (1/s), decreasing real part.
    pub rightmost_roots: Vec<Complex<f64>>,
}

impl StableReport {
    /// Computes the `count` rightmost roots of `variant` at `params`.
    pub fn compute(params: &Params, variant: Variant, count: usize) -> Result<StableReport> {
        let roots = rightmost_roots(params, variant, count.max(1))?;
        let spectral_abscissa = roots.first().map(|r| r.re).ok_or(Error::Numerical {
            what: "spectral abscissa",
            reason: "no characteristic root found".to_string(),
        })?;
        let mut rightmost_roots = roots;
        rightmost_roots.truncate(count);
        Ok(StableReport {
            stable: spectral_abscissa < 0.0,
            spectral_abscissa,
            rightmost_roots,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tdvass(g: f64, tau: f64) -> Params {
        Params::with_controller(g, tau)
    }

    #[test]
    fn verification_points_of_section_3_3() {
        let points = [
            ("A1*", 40000.0, 0.03, true),
            ("A2*", -40000.0, 0.11, false),
            ("A3*", 40000.0, 0.15, false),
            ("A4*", -40000.0, 0.25, true),
            ("A5*", 40000.0, 0.3, true),
            ("A6*", -40000.0, 0.4, false),
        ];
        for (name, g, tau, stable) in points {
            let report = StableReport::compute(&tdvass(g, tau), Variant::Tdvass, 4).unwrap();
            assert_eq!(report.stable, stable, "{name}: {report:?}");
            // Clearly on one side: not a marginal verdict.
            assert!(report.spectral_abscissa.abs() > 0.05, "{name}: {report:?}");
            assert_eq!(report.rightmost_roots.len(), 4);
        }
    }

    #[test]
    fn polished_roots_solve_eq8_and_do_not_depend_on_the_node_count() {
        let solver =
            CharacteristicRootSolver::new(&tdvass(-40000.0, 0.0), Variant::Tdvass).unwrap();
        for tau in [2e-4, 0.05, 0.4] {
            let default = solver.rightmost_roots(tau, 6).unwrap();
            let nodes = solver.nodes_for_delay(tau);
            let finer = solver.polish_all(&solver.approximate_roots(tau, 2 * nodes).unwrap(), tau);
            for (a, b) in default.iter().zip(&finer) {
                assert!(
                    (a - b).norm() < 1e-8 * a.norm().max(1.0),
                    "tau {tau}: {a} vs {b}"
                );
            }
            for root in &default {
                let (value, slope) = solver.characteristic_value_and_slope(*root, tau);
                // Newton step below 1e-10 relative: a root of Eq. (8).
                assert!((value / slope).norm() < 1e-10 * root.norm().max(1.0));
            }
            for pair in default.windows(2) {
                assert!(pair[0].re >= pair[1].re);
            }
        }
    }

    #[test]
    fn zero_delay_roots_are_those_of_p_plus_q() {
        let params = tdvass(50000.0, 0.0);
        let roots = rightmost_roots(&params, Variant::Tdvass, 6).unwrap();
        let polynomials = CharacteristicPolynomials::new(&params, Variant::Tdvass).unwrap();
        let mut expected = polynomials.zero_delay().roots().unwrap();
        sort_rightmost_first(&mut expected);
        assert_eq!(roots.len(), 6);
        for (a, b) in roots.iter().zip(&expected) {
            assert!((a - b).norm() < 1e-8 * b.norm(), "{a} vs {b}");
        }
    }

    #[test]
    fn cs_and_pvass_use_their_own_polynomial() {
        let params = tdvass(50000.0, 0.3);
        let cs = rightmost_roots(&params, Variant::Cs, 10).unwrap();
        assert_eq!(cs.len(), 4);
        let pvass = rightmost_roots(&params, Variant::Pvass, 10).unwrap();
        assert_eq!(pvass.len(), 6);
        for variant in [Variant::Cs, Variant::Pvass] {
            let abscissa = spectral_abscissa(&params, variant).unwrap();
            assert!(abscissa < 0.0, "{variant:?}: {abscissa}");
            // g and tau do not matter without control.
            let other = spectral_abscissa(&tdvass(-90000.0, 0.01), variant).unwrap();
            assert!((abscissa - other).abs() < 1e-12);
        }
        // The CS body mode: |s|² ≈ k_s k_t / ((k_s + k_t) m_s).
        let p = Params::default();
        let body = cs.iter().map(|r| r.norm()).fold(f64::INFINITY, f64::min);
        let series = p.k_s * p.k_t / (p.k_s + p.k_t) / p.m_s;
        assert!((body * body / series - 1.0).abs() < 0.1, "{body}");
    }

    #[test]
    fn chebyshev_derivative_is_exact_for_polynomials() {
        let n = 7;
        let d = chebyshev_differentiation(n);
        let x: Vec<f64> = (0..=n)
            .map(|j| (std::f64::consts::PI * j as f64 / n as f64).cos())
            .collect();
        for i in 0..=n {
            let derivative: f64 = (0..=n).map(|j| d[(i, j)] * x[j].powi(3)).sum();
            assert!((derivative - 3.0 * x[i] * x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn report_and_bad_input() {
        let report = StableReport::compute(&tdvass(40000.0, 0.03), Variant::Tdvass, 2).unwrap();
        assert!(report.stable);
        assert!(report.spectral_abscissa < 0.0);
        assert_eq!(report.rightmost_roots.len(), 2);
        let solver = CharacteristicRootSolver::new(&tdvass(1.0, 0.0), Variant::Tdvass).unwrap();
        assert!(solver.rightmost_roots(-0.1, 3).is_err());
        assert!(solver.rightmost_roots(f64::NAN, 3).is_err());
        assert!(spectral_abscissa(&tdvass(f64::NAN, 0.1), Variant::Tdvass).is_err());
        assert!(spectral_abscissa(&tdvass(1.0, -0.1), Variant::Tdvass).is_err());
    }
}
