//! The characteristic quasi-polynomial of the delay system, Eq. (8)-(9):
//! `D(s, tau) = P(s) + Q(s) e^{-s tau}`, from the determinant of the
//! Laplace-transformed Eq. (1). Both the crossing analysis
//! ([`super::stability`]) and the spectrum ([`super::spectrum`]) start
//! from it; it imports neither.

use crate::analysis::polynomial::Polynomial;
use crate::error::Result;
use crate::model::{MassSpringDamper, Params, Variant};
use nalgebra::Complex;

/// P(s) and Q(s) of Eq. (8)-(9): `D(s, tau) = P(s) + Q(s) e^{-s tau}`.
///
/// Coefficients lowest degree first, in products of the SI units of the
/// parameters (kg, N/m, N·s/m). `D(s, tau) / (m_s m_h m_t)` is
/// `det(s I - A - b e_{x_t}^T e^{-s tau})` of the plant of Eq. (2).
#[derive(Debug, Clone, PartialEq)]
pub struct CharacteristicPolynomials {
    /// P(s): the delay-free part, degree 6 (4 for the CS).
    pub p: Vec<f64>,
    /// Q(s): the part multiplied by e^{-s tau}; empty (zero) for CS and
    /// PVASS, `b_2 s^2 + b_3 s^3 + b_4 s^4` for the TDVASS.
    pub q: Vec<f64>,
}

impl CharacteristicPolynomials {
    /// Expands the determinant of the Laplace-transformed Eq. (1):
    /// `K(s) = M s^2 + C s + K` plus the delayed feedback column
    /// `g e^{-s tau} [0, 1, -1]^T` on the x_t coordinate (TDVASS only).
    ///
    /// As the feedback matrix has rank one, `det(K(s) + e^{-s tau} G)` is
    /// `det K(s) + e^{-s tau} det(K(s) with its x_t column replaced by G)`.
    /// The CS uses its own 2×2 body–wheel matrix (degree-4 P, Q = 0).
    pub fn new(params: &Params, variant: Variant) -> Result<CharacteristicPolynomials> {
        let eq1 = MassSpringDamper::new(params, variant)?;
        let n = eq1.dimension();
        // Entry (i, j) of K(s) = M s² + C s + K, coefficients lowest first.
        let mut matrix: Vec<Vec<Polynomial>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| match (eq1.stiffness(i, j), eq1.damping(i, j)) {
                        (Some(k), Some(c)) if i == j => Polynomial::new(vec![k, c, eq1.masses[i]]),
                        (Some(k), Some(c)) => Polynomial::new(vec![k, c]),
                        _ => Polynomial::zero(),
                    })
                    .collect()
            })
            .collect();
        let p = determinant(&matrix);
        if n == 2 {
            return Ok(CharacteristicPolynomials {
                p: p.coefficients().to_vec(),
                q: Vec::new(),
            });
        }
        // The wheel's column replaced by the delayed force, moved to the
        // left-hand side: `−f`.
        let wheel = eq1.wheel();
        for (i, row) in matrix.iter_mut().enumerate() {
            row[wheel] = if i == 0 {
                Polynomial::zero()
            } else {
                Polynomial::constant(-eq1.feedback[i])
            };
        }
        let q = determinant(&matrix);
        Ok(CharacteristicPolynomials {
            p: p.coefficients().to_vec(),
            q: q.coefficients().to_vec(),
        })
    }

    /// P(s) as a [`Polynomial`].
    pub fn p_polynomial(&self) -> Polynomial {
        Polynomial::new(self.p.clone())
    }

    /// Q(s) as a [`Polynomial`].
    pub fn q_polynomial(&self) -> Polynomial {
        Polynomial::new(self.q.clone())
    }

    /// `D(s, 0) = P(s) + Q(s)`, Eq. (10).
    pub fn zero_delay(&self) -> Polynomial {
        &self.p_polynomial() + &self.q_polynomial()
    }

    /// `D(s, tau)` of Eq. (8) at complex s (1/s) and delay tau (s).
    pub fn evaluate(&self, s: Complex<f64>, tau: f64) -> Complex<f64> {
        horner(&self.p, s) + horner(&self.q, s) * (-s * tau).exp()
    }

    /// F(ω) of Eq. (14)-(15) as a polynomial in `z = ω²` (rad²/s²):
    /// `|P(iω)|² - |Q(iω)|²`.
    pub fn discriminant_in_omega_squared(&self) -> Polynomial {
        &squared_modulus_on_imaginary_axis(&self.p_polynomial())
            - &squared_modulus_on_imaginary_axis(&self.q_polynomial())
    }
}

/// Horner evaluation of coefficients (lowest degree first) at complex s.
fn horner(coefficients: &[f64], s: Complex<f64>) -> Complex<f64> {
    coefficients
        .iter()
        .rev()
        .fold(Complex::new(0.0, 0.0), |acc, &c| acc * s + c)
}

/// Determinant of a square matrix of polynomials by Laplace expansion along
/// the first row (used for the 2×2 and 3×3 matrices of Eq. (1)).
fn determinant(matrix: &[Vec<Polynomial>]) -> Polynomial {
    match matrix.len() {
        0 => Polynomial::constant(1.0),
        1 => matrix[0][0].clone(),
        n => {
            let mut total = Polynomial::zero();
            for column in 0..n {
                if matrix[0][column].is_zero() {
                    continue;
                }
                let minor: Vec<Vec<Polynomial>> = matrix[1..]
                    .iter()
                    .map(|row| {
                        row.iter()
                            .enumerate()
                            .filter(|&(j, _)| j != column)
                            .map(|(_, entry)| entry.clone())
                            .collect()
                    })
                    .collect();
                let term = &matrix[0][column] * &determinant(&minor);
                total = if column % 2 == 0 {
                    &total + &term
                } else {
                    &total - &term
                };
            }
            total
        }
    }
}

/// Real and imaginary parts of `p(iω)` as polynomials in ω:
/// `Re p(iω) = Σ_{k even} (-1)^{k/2} c_k ω^k`,
/// `Im p(iω) = Σ_{k odd} (-1)^{(k-1)/2} c_k ω^k` (Eq. (11)).
pub(crate) fn parts_on_imaginary_axis(p: &Polynomial) -> (Polynomial, Polynomial) {
    let coefficients = p.coefficients();
    let mut real = vec![0.0; coefficients.len()];
    let mut imaginary = vec![0.0; coefficients.len()];
    for (k, &c) in coefficients.iter().enumerate() {
        let sign = if (k / 2).is_multiple_of(2) { 1.0 } else { -1.0 };
        if k.is_multiple_of(2) {
            real[k] = sign * c;
        } else {
            imaginary[k] = sign * c;
        }
    }
    (Polynomial::new(real), Polynomial::new(imaginary))
}

/// `|p(iω)|²` as a polynomial in `z = ω²`.
pub(crate) fn squared_modulus_on_imaginary_axis(p: &Polynomial) -> Polynomial {
    let (real, imaginary) = parts_on_imaginary_axis(p);
    let in_omega = &(&real * &real) + &(&imaginary * &imaginary);
    in_omega
        .even_part_in_square()
        .unwrap_or_else(Polynomial::zero)
}
