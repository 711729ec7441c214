//! Real polynomials and their complex roots.
//!
//! A [`Polynomial`] stores its real coefficients lowest degree first:
//! `c[0] + c[1] x + ... + c[n] x^n`. The characteristic polynomials P(s),
//! Q(s) of Eq. (8)-(9) (s in 1/s, coefficients in SI units of
//! kg, N/m, N·s/m products) and the discriminant F(ω) of Eq. (15) are built
//! from them in [`crate::analysis::stability`].
//!
//! Roots are the eigenvalues of the (scaled, balanced) companion matrix,
//! computed with nalgebra's real Schur decomposition, each polished by a
//! few safeguarded Newton steps on the original polynomial.

use crate::error::{Error, Result};
use nalgebra::{Complex, DMatrix, Schur};
use std::ops::{Add, Mul, Neg, Sub};

/// A real polynomial, coefficients lowest degree first.
///
/// Trailing (highest-degree) zero coefficients are removed on construction,
/// so the last stored coefficient is the leading one; the zero polynomial
/// stores no coefficients.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polynomial {
    coefficients: Vec<f64>,
}

impl Polynomial {
    /// The polynomial `c[0] + c[1] x + ... + c[n] x^n`.
    pub fn new(coefficients: Vec<f64>) -> Polynomial {
        let mut coefficients = coefficients;
        while coefficients.last() == Some(&0.0) {
            coefficients.pop();
        }
        Polynomial { coefficients }
    }

    /// The zero polynomial.
    pub fn zero() -> Polynomial {
        Polynomial::default()
    }

    /// The constant polynomial `value`.
    pub fn constant(value: f64) -> Polynomial {
        Polynomial::new(vec![value])
    }

    /// The monomial `coefficient x^power`.
    pub fn monomial(coefficient: f64, power: usize) -> Polynomial {
        let mut coefficients = vec![0.0; power + 1];
        coefficients[power] = coefficient;
        Polynomial::new(coefficients)
    }

    /// Coefficients lowest degree first (no trailing zeros).
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// Coefficient of `x^power` (0 beyond the degree).
    pub fn coefficient(&self, power: usize) -> f64 {
        self.coefficients.get(power).copied().unwrap_or(0.0)
    }

    /// The degree, `None` for the zero polynomial.
    pub fn degree(&self) -> Option<usize> {
        self.coefficients.len().checked_sub(1)
    }

    /// Whether this is the zero polynomial.
    pub fn is_zero(&self) -> bool {
        self.coefficients.is_empty()
    }

    /// Whether every coefficient is finite.
    pub fn is_finite(&self) -> bool {
        self.coefficients.iter().all(|c| c.is_finite())
    }

    /// Value at a real point (Horner).
    pub fn eval(&self, x: f64) -> f64 {
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, &c| acc * x + c)
    }

    /// Value at a complex point (Horner).
    pub fn eval_complex(&self, s: Complex<f64>) -> Complex<f64> {
        self.coefficients
            .iter()
            .rev()
            .fold(Complex::new(0.0, 0.0), |acc, &c| acc * s + c)
    }

    /// Value and first derivative at a complex point, in one Horner pass.
    pub fn eval_complex_with_derivative(&self, s: Complex<f64>) -> (Complex<f64>, Complex<f64>) {
        let zero = Complex::new(0.0, 0.0);
        self.coefficients
            .iter()
            .rev()
            .fold((zero, zero), |(value, slope), &c| {
                (value * s + c, slope * s + value)
            })
    }

    /// The derivative polynomial.
    pub fn derivative(&self) -> Polynomial {
        Polynomial::new(
            self.coefficients
                .iter()
                .enumerate()
                .skip(1)
                .map(|(power, &c)| c * power as f64)
                .collect(),
        )
    }

    /// The polynomial multiplied by a scalar.
    pub fn scaled(&self, factor: f64) -> Polynomial {
        Polynomial::new(self.coefficients.iter().map(|c| c * factor).collect())
    }

    /// `p(x)` rewritten as a polynomial in `z = x²`, for a polynomial that is
    /// even in x (odd coefficients must be zero). Returns `None` otherwise.
    pub fn even_part_in_square(&self) -> Option<Polynomial> {
        if self
            .coefficients
            .iter()
            .skip(1)
            .step_by(2)
            .any(|&c| c != 0.0)
        {
            return None;
        }
        Some(Polynomial::new(
            self.coefficients.iter().step_by(2).copied().collect(),
        ))
    }

    /// All complex roots, with multiplicity (`degree` of them).
    ///
    /// Exact zero roots (vanishing low-order coefficients) are split off
    /// first. The remaining roots are the eigenvalues of the companion matrix
    /// of the polynomial in the scaled variable `x / rho`, with
    /// `rho = |c_0 / c_n|^(1/n)`, balanced before the Schur decomposition;
    /// each eigenvalue is then polished by Newton steps on `p` that are
    /// accepted only while they decrease `|p|`.
    ///
    /// Errors: the zero polynomial (every point is a root), non-finite
    /// coefficients, or a Schur decomposition that does not converge.
    pub fn roots(&self) -> Result<Vec<Complex<f64>>> {
        if self.is_zero() {
            return Err(Error::Numerical {
                what: "polynomial roots",
                reason: "the zero polynomial has no isolated roots".to_string(),
            });
        }
        if !self.is_finite() {
            return Err(Error::Numerical {
                what: "polynomial roots",
                reason: format!("non-finite coefficient in {:?}", self.coefficients),
            });
        }
        let zero_roots = self.coefficients.iter().take_while(|&&c| c == 0.0).count();
        let reduced = &self.coefficients[zero_roots..];
        let mut roots = vec![Complex::new(0.0, 0.0); zero_roots];
        let degree = reduced.len() - 1;
        if degree == 0 {
            return Ok(roots);
        }
        let leading = reduced[degree];
        let rho = (reduced[0] / leading).abs().powf(1.0 / degree as f64);
        // Monic polynomial in t = x / rho: t^n + sum d_k t^k, d_k = c_k rho^(k-n) / c_n.
        let mut companion = DMatrix::<f64>::zeros(degree, degree);
        for k in 0..degree {
            let scaled = reduced[k] * rho.powi(k as i32 - degree as i32) / leading;
            companion[(0, degree - 1 - k)] = -scaled;
        }
        for row in 1..degree {
            companion[(row, row - 1)] = 1.0;
        }
        let eigenvalues = matrix_eigenvalues(companion)?;
        let original = Polynomial::new(reduced.to_vec());
        roots.extend(
            eigenvalues
                .into_iter()
                .map(|t| polish_root(&original, t * rho, 8)),
        );
        Ok(roots)
    }

    /// The real roots: roots whose imaginary part is at most
    /// `relative_tolerance` times their modulus (or at most
    /// `relative_tolerance` when the root is smaller than 1), real parts
    /// returned in increasing order. Close pairs produced by a double root
    /// appear twice.
    pub fn real_roots(&self, relative_tolerance: f64) -> Result<Vec<f64>> {
        let mut real: Vec<f64> = self
            .roots()?
            .into_iter()
            .filter(|r| r.im.abs() <= relative_tolerance * r.norm().max(1.0))
            .map(|r| r.re)
            .collect();
        real.sort_by(f64::total_cmp);
        Ok(real)
    }
}

/// Newton polishing of an approximate root of `p`: at most `max_steps`
/// steps, each accepted only if it does not increase `|p|`.
pub fn polish_root(p: &Polynomial, start: Complex<f64>, max_steps: usize) -> Complex<f64> {
    let mut root = start;
    let (mut value, mut slope) = p.eval_complex_with_derivative(root);
    for _ in 0..max_steps {
        if value.norm() == 0.0 || slope.norm() == 0.0 {
            break;
        }
        let candidate = root - value / slope;
        let (candidate_value, candidate_slope) = p.eval_complex_with_derivative(candidate);
        let improves = candidate_value.norm() <= value.norm();
        if !improves {
            break;
        }
        let step = (candidate - root).norm();
        root = candidate;
        value = candidate_value;
        slope = candidate_slope;
        if step <= 4.0 * f64::EPSILON * root.norm() {
            break;
        }
    }
    root
}

/// Diagonal similarity balancing (Parlett–Reinsch, radix 2) in place: rows
/// and columns are scaled by powers of two so that each row and column have
/// comparable norms. Eigenvalues are unchanged (exactly, as the scalings are
/// powers of two), their computed accuracy improves for badly scaled matrices.
pub fn balance(matrix: &mut DMatrix<f64>) {
    const RADIX: f64 = 2.0;
    let n = matrix.nrows();
    let mut converged = false;
    let mut sweeps = 0;
    while !converged && sweeps < 100 {
        converged = true;
        sweeps += 1;
        for i in 0..n {
            let mut column_norm = 0.0;
            let mut row_norm = 0.0;
            for j in 0..n {
                if j != i {
                    column_norm += matrix[(j, i)].abs();
                    row_norm += matrix[(i, j)].abs();
                }
            }
            if column_norm == 0.0 || row_norm == 0.0 {
                continue;
            }
            let total = column_norm + row_norm;
            let mut factor = 1.0;
            let mut column = column_norm;
            let mut row = row_norm;
            while column < row / RADIX {
                column *= RADIX;
                row /= RADIX;
                factor *= RADIX;
            }
            while column >= row * RADIX {
                column /= RADIX;
                row *= RADIX;
                factor /= RADIX;
            }
            if column + row < 0.95 * total {
                converged = false;
                for j in 0..n {
                    matrix[(i, j)] /= factor;
                    matrix[(j, i)] *= factor;
                }
            }
        }
    }
}

/// All eigenvalues of a real square matrix: balancing, then nalgebra's real
/// Schur decomposition (implicit double-shift QR).
///
/// Errors: a non-square or non-finite matrix, or no convergence of the QR
/// iteration (also after retrying with the transposed matrix).
pub fn matrix_eigenvalues(matrix: DMatrix<f64>) -> Result<Vec<Complex<f64>>> {
    if !matrix.is_square() {
        return Err(Error::Numerical {
            what: "matrix eigenvalues",
            reason: format!(
                "matrix is {}x{}, not square",
                matrix.nrows(),
                matrix.ncols()
            ),
        });
    }
    if matrix.iter().any(|v| !v.is_finite()) {
        return Err(Error::Numerical {
            what: "matrix eigenvalues",
            reason: "the matrix has a non-finite entry".to_string(),
        });
    }
    let n = matrix.nrows();
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut balanced = matrix;
    balance(&mut balanced);
    let max_iterations = 60 * n.max(4);
    let attempts = [balanced.clone(), balanced.transpose()];
    for candidate in attempts {
        if let Some(schur) = Schur::try_new(candidate, f64::EPSILON, max_iterations) {
            let eigenvalues: Vec<Complex<f64>> =
                schur.complex_eigenvalues().iter().copied().collect();
            if eigenvalues
                .iter()
                .all(|e| e.re.is_finite() && e.im.is_finite())
            {
                return Ok(eigenvalues);
            }
        }
    }
    Err(Error::Numerical {
        what: "matrix eigenvalues",
        reason: format!("the Schur (QR) iteration did not converge for a {n}x{n} matrix"),
    })
}

impl Add for &Polynomial {
    type Output = Polynomial;
    fn add(self, other: &Polynomial) -> Polynomial {
        let length = self.coefficients.len().max(other.coefficients.len());
        Polynomial::new(
            (0..length)
                .map(|k| self.coefficient(k) + other.coefficient(k))
                .collect(),
        )
    }
}

impl Sub for &Polynomial {
    type Output = Polynomial;
    fn sub(self, other: &Polynomial) -> Polynomial {
        let length = self.coefficients.len().max(other.coefficients.len());
        Polynomial::new(
            (0..length)
                .map(|k| self.coefficient(k) - other.coefficient(k))
                .collect(),
        )
    }
}

impl Mul for &Polynomial {
    type Output = Polynomial;
    fn mul(self, other: &Polynomial) -> Polynomial {
        if self.is_zero() || other.is_zero() {
            return Polynomial::zero();
        }
        let mut product = vec![0.0; self.coefficients.len() + other.coefficients.len() - 1];
        for (i, &a) in self.coefficients.iter().enumerate() {
            for (j, &b) in other.coefficients.iter().enumerate() {
                product[i + j] += a * b;
            }
        }
        Polynomial::new(product)
    }
}

impl Neg for &Polynomial {
    type Output = Polynomial;
    fn neg(self) -> Polynomial {
        self.scaled(-1.0)
    }
}

impl Add for Polynomial {
    type Output = Polynomial;
    fn add(self, other: Polynomial) -> Polynomial {
        &self + &other
    }
}

impl Sub for Polynomial {
    type Output = Polynomial;
    fn sub(self, other: Polynomial) -> Polynomial {
        &self - &other
    }
}

impl Mul for Polynomial {
    type Output = Polynomial;
    fn mul(self, other: Polynomial) -> Polynomial {
        &self * &other
    }
}

impl Neg for Polynomial {
    type Output = Polynomial;
    fn neg(self) -> Polynomial {
        -&self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_roots(roots: &[f64]) -> Polynomial {
        roots.iter().fold(Polynomial::constant(1.0), |acc, &r| {
            &acc * &Polynomial::new(vec![-r, 1.0])
        })
    }

    fn sorted(mut roots: Vec<Complex<f64>>) -> Vec<Complex<f64>> {
        roots.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        roots
    }

    #[test]
    fn construction_trims_and_reports_degree() {
        let p = Polynomial::new(vec![1.0, 2.0, 0.0, 0.0]);
        assert_eq!(p.coefficients(), &[1.0, 2.0]);
        assert_eq!(p.degree(), Some(1));
        assert_eq!(Polynomial::zero().degree(), None);
        assert_eq!(
            Polynomial::monomial(3.0, 2).coefficients(),
            &[0.0, 0.0, 3.0]
        );
        assert_eq!(p.coefficient(7), 0.0);
    }

    #[test]
    fn evaluation_and_derivative() {
        // p = 1 - 3x + 2x^3
        let p = Polynomial::new(vec![1.0, -3.0, 0.0, 2.0]);
        assert_eq!(p.eval(2.0), 1.0 - 6.0 + 16.0);
        assert_eq!(p.derivative().coefficients(), &[-3.0, 0.0, 6.0]);
        let s = Complex::new(0.5, -1.5);
        let direct = 1.0 - 3.0 * s + 2.0 * s * s * s;
        let (value, slope) = p.eval_complex_with_derivative(s);
        assert!((value - direct).norm() < 1e-12);
        assert!((p.eval_complex(s) - direct).norm() < 1e-12);
        assert!((slope - (-3.0 + 6.0 * s * s)).norm() < 1e-12);
    }

    #[test]
    fn arithmetic() {
        let a = Polynomial::new(vec![1.0, 1.0]);
        let b = Polynomial::new(vec![-1.0, 1.0]);
        assert_eq!((&a * &b).coefficients(), &[-1.0, 0.0, 1.0]);
        assert_eq!((&a + &b).coefficients(), &[0.0, 2.0]);
        assert_eq!((&a - &a).degree(), None);
        assert_eq!((-a.clone()).coefficients(), &[-1.0, -1.0]);
        let x2 = Polynomial::new(vec![4.0, 0.0, -5.0, 0.0, 1.0]);
        assert_eq!(
            x2.even_part_in_square().unwrap().coefficients(),
            &[4.0, -5.0, 1.0]
        );
        assert!(a.even_part_in_square().is_none());
    }

    #[test]
    fn roots_of_polynomials_with_known_real_roots() {
        let expected = [-3.0, -1.0, 0.5, 2.0, 7.0];
        let p = from_roots(&expected);
        let roots = sorted(p.roots().unwrap());
        assert_eq!(roots.len(), 5);
        for (root, want) in roots.iter().zip(expected) {
            assert!((root.re - want).abs() < 1e-12, "{root} vs {want}");
            assert!(root.im.abs() < 1e-12);
        }
        let real = p.real_roots(1e-9).unwrap();
        assert_eq!(real.len(), 5);
    }

    #[test]
    fn roots_of_unity_and_zero_roots() {
        // x^2 (x^4 - 1): a companion matrix on which unshifted QR stalls.
        let p = Polynomial::new(vec![0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0]);
        let roots = p.roots().unwrap();
        assert_eq!(roots.len(), 6);
        assert_eq!(roots.iter().filter(|r| r.norm() == 0.0).count(), 2);
        for want in [
            Complex::new(1.0, 0.0),
            Complex::new(-1.0, 0.0),
            Complex::new(0.0, 1.0),
            Complex::new(0.0, -1.0),
        ] {
            assert!(
                roots.iter().any(|r| (r - want).norm() < 1e-12),
                "{want} missing from {roots:?}"
            );
        }
    }

    #[test]
    fn roots_with_badly_scaled_coefficients() {
        // Roots 1e-3, 60 ± 70i, 1e4: coefficients span many decades.
        let quadratic = Polynomial::new(vec![60.0 * 60.0 + 70.0 * 70.0, -120.0, 1.0]);
        let p = &(&from_roots(&[1e-3, 1e4]) * &quadratic).scaled(3.0e9);
        let roots = sorted(p.roots().unwrap());
        let want = [
            Complex::new(1e-3, 0.0),
            Complex::new(60.0, -70.0),
            Complex::new(60.0, 70.0),
            Complex::new(1e4, 0.0),
        ];
        for (root, want) in roots.iter().zip(want) {
            assert!(
                (root - want).norm() < 1e-10 * want.norm(),
                "{root} vs {want}"
            );
        }
    }

    #[test]
    fn double_roots_are_found_to_half_precision() {
        let p = from_roots(&[2.0, 2.0, -5.0]);
        let roots = p.real_roots(1e-6).unwrap();
        assert_eq!(roots.len(), 3);
        assert!((roots[1] - 2.0).abs() < 1e-6 && (roots[2] - 2.0).abs() < 1e-6);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        assert!(Polynomial::zero().roots().is_err());
        assert!(Polynomial::new(vec![1.0, f64::NAN]).roots().is_err());
        assert!(Polynomial::constant(3.0).roots().unwrap().is_empty());
        assert!(matrix_eigenvalues(DMatrix::zeros(2, 3)).is_err());
    }

    #[test]
    fn balancing_keeps_eigenvalues() {
        let m = DMatrix::from_row_slice(3, 3, &[1.0, 1e6, 0.0, 1e-6, 2.0, 1e5, 0.0, 1e-5, 3.0]);
        let mut balanced = m.clone();
        balance(&mut balanced);
        assert!(balanced.amax() < m.amax());
        let mut a = sorted(matrix_eigenvalues(m.clone()).unwrap());
        let mut b = sorted(m.complex_eigenvalues().iter().copied().collect());
        a.truncate(3);
        b.truncate(3);
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).norm() < 1e-9, "{x} vs {y}");
        }
    }
}
