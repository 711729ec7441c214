//! Frequency response of the body to the road (paper section 2.2,
//! Eq. (3)-(5)).
//!
//! The Fourier transform of Eq. (1) gives the complex dynamic-stiffness
//! system of Eq. (3), `A(ω) [X_s, X_h, X_t]^T = [0, 0, k_t X_g]^T`, whose
//! entries contain the delayed feedback `g e^{-iωτ}` (TDVASS only). The body
//! displacement gain `|X_s/X_g|` is Eq. (4) and the body acceleration gain
//! `ω² |X_s/X_g|` (in (m/s²)/m = 1/s²) is Eq. (5) (notes.md item 2.5: Eq. (5)
//! is the acceleration gain). The CS uses its own 2×2 body–wheel system.
//!
//! Angular frequencies ω are in rad/s, frequencies f in Hz (ω = 2π f).
//! With absolute tire-displacement feedback the static body gain is
//! `1 - g/k_h` (notes.md item 1), not 1.

use crate::error::{Error, Result};
use crate::model::{MassSpringDamper, Params, Variant};
use nalgebra::{Complex, Matrix3};
use std::f64::consts::PI;

/// The 3×3 complex matrix A(ω) of Eq. (3) for the PVASS/TDVASS (the gain
/// acting is `params.effective_gain(variant)`, so it is zero for the PVASS),
/// assembled from Eq. (1) ([`MassSpringDamper`]): `−M ω² + iω C + K` minus
/// the delayed force `f e^{−iωτ}` in the wheel's column. For the CS the
/// matrix is the 2×2 body–wheel system embedded on the `X_s` and `X_t` rows
/// and columns, with `A_22 = 1` and no coupling, so that solving it gives
/// `X_h = 0` and the CS `X_s`, `X_t`.
pub fn dynamic_stiffness_matrix(
    params: &Params,
    variant: Variant,
    omega: f64,
) -> Result<Matrix3<Complex<f64>>> {
    let eq1 = MassSpringDamper::new(params, variant)?;
    let i_omega = Complex::new(0.0, omega);
    let zero = Complex::new(0.0, 0.0);
    let n = eq1.dimension();
    // Rows and columns of the 3×3 matrix that hold the coordinates.
    let slots: Vec<usize> = if n == 2 { vec![0, 2] } else { vec![0, 1, 2] };
    let mut a = Matrix3::from_element(zero);
    if n == 2 {
        a[(1, 1)] = Complex::new(1.0, 0.0);
    }
    for i in 0..n {
        for j in 0..n {
            let inertia = if i == j {
                Complex::new(-eq1.masses[i] * omega * omega, 0.0)
            } else {
                zero
            };
            if let Some(entry) = eq1.assemble(i, j, inertia, |e| i_omega * e.damping + e.stiffness)
            {
                a[(slots[i], slots[j])] = entry;
            }
        }
    }
    if n == 3 {
        // The delayed force acts on the absorber and the wheel rows.
        let delayed = (-i_omega * params.tau).exp();
        let wheel = eq1.wheel();
        for i in 1..n {
            a[(i, wheel)] += delayed * -eq1.feedback[i];
        }
    }
    Ok(a)
}

/// The complex body displacement transfer `X_s/X_g` at angular frequency
/// `omega` (rad/s): Eq. (4) without the modulus for the PVASS/TDVASS,
/// `k_t (k_s + iω c_s) / det` of the 2×2 body–wheel system for the CS.
pub fn body_displacement_transfer(
    params: &Params,
    variant: Variant,
    omega: f64,
) -> Result<Complex<f64>> {
    params.validate()?;
    if !omega.is_finite() {
        return Err(Error::InvalidParameter {
            name: "omega",
            value: omega,
            reason: "the angular frequency must be finite",
        });
    }
    let a = dynamic_stiffness_matrix(params, variant, omega)?;
    let k_t = params.k_t;
    let (numerator, denominator) = match variant {
        Variant::Cs => {
            // Body and wheel (indices 0 and 2 of the embedded matrix).
            let numerator = -a[(0, 2)] * k_t;
            let denominator = a[(0, 0)] * a[(2, 2)] - a[(0, 2)] * a[(2, 0)];
            (numerator, denominator)
        }
        Variant::Pvass | Variant::Tdvass => {
            let (a11, a12, a21, a22, a23, a32, a33) = (
                a[(0, 0)],
                a[(0, 1)],
                a[(1, 0)],
                a[(1, 1)],
                a[(1, 2)],
                a[(2, 1)],
                a[(2, 2)],
            );
            let numerator = -a12 * a23 * k_t;
            let denominator = a11 * a23 * a32 - a11 * a22 * a33 + a12 * a21 * a33;
            (numerator, denominator)
        }
    };
    if denominator.norm() == 0.0 {
        return Err(Error::Numerical {
            what: "frequency response",
            reason: format!("the system of Eq. (3) is singular at omega = {omega} rad/s"),
        });
    }
    Ok(numerator / denominator)
}

/// `|X_s/X_g|` (m/m) at `omega` (rad/s), Eq. (4).
pub fn body_displacement_gain(params: &Params, variant: Variant, omega: f64) -> Result<f64> {
    Ok(body_displacement_transfer(params, variant, omega)?.norm())
}

/// `ω² |X_s/X_g|` ((m/s²)/m) at `omega` (rad/s), Eq. (5).
pub fn body_acceleration_gain(params: &Params, variant: Variant, omega: f64) -> Result<f64> {
    Ok(omega * omega * body_displacement_gain(params, variant, omega)?)
}

/// One sample of the frequency response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfPoint {
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// `|X_s/X_g|` (m/m), Eq. (4).
    pub body_displacement: f64,
    /// `ω² |X_s/X_g|` ((m/s²)/m), Eq. (5).
    pub body_acceleration: f64,
}

/// Both gains on `points` log-spaced frequencies from `f_min_hz` to
/// `f_max_hz` (Hz, both included).
///
/// The conventional suspension's body resonance lies near 1 Hz, and the
/// TDVASS's static body gain is `1 − g/k_h`:
///
/// ```
/// use tdvass::analysis::frf::{frequency_response, peaks_hz};
/// use tdvass::{Params, Variant};
///
/// let params = Params::default(); // Table 1, g = 5386 N/m, tau = 2e-4 s
/// let curve = frequency_response(&params, Variant::Cs, 0.1, 30.0, 500)?; // Hz
/// let peaks = peaks_hz(&params, Variant::Cs, &curve)?;
/// assert!((peaks.body_displacement[0] - 0.99).abs() < 0.01); // Hz
///
/// let low = frequency_response(&params, Variant::Tdvass, 1e-4, 1e-3, 2)?;
/// let static_gain = 1.0 - params.g / params.k_h; // 0.164
/// assert!((low[0].body_displacement - static_gain).abs() < 1e-3);
/// # Ok::<(), tdvass::Error>(())
/// ```
pub fn frequency_response(
    params: &Params,
    variant: Variant,
    f_min_hz: f64,
    f_max_hz: f64,
    points: usize,
) -> Result<Vec<FrfPoint>> {
    params.validate()?;
    if !(f_min_hz.is_finite() && f_min_hz > 0.0) {
        return Err(Error::InvalidParameter {
            name: "f_min",
            value: f_min_hz,
            reason: "the lowest frequency must be finite and > 0 (log spacing)",
        });
    }
    if !(f_max_hz.is_finite() && f_max_hz > f_min_hz) {
        return Err(Error::InvalidParameter {
            name: "f_max",
            value: f_max_hz,
            reason: "the highest frequency must be finite and > f_min",
        });
    }
    if points < 2 {
        return Err(Error::InvalidSetting {
            name: "points",
            value: points as i64,
            reason: "at least 2 frequencies are needed",
        });
    }
    let ratio = f_max_hz / f_min_hz;
    (0..points)
        .map(|index| {
            let frequency_hz = if index == points - 1 {
                f_max_hz
            } else {
                f_min_hz * ratio.powf(index as f64 / (points - 1) as f64)
            };
            let omega = 2.0 * PI * frequency_hz;
            let body_displacement = body_displacement_gain(params, variant, omega)?;
            Ok(FrfPoint {
                frequency_hz,
                body_displacement,
                body_acceleration: omega * omega * body_displacement,
            })
        })
        .collect()
}

/// Local maxima (Hz) of the two gain curves.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrfPeaks {
    /// Peaks of `|X_s/X_g|`, increasing frequency.
    pub body_displacement: Vec<f64>,
    /// Peaks of `ω² |X_s/X_g|`, increasing frequency.
    pub body_acceleration: Vec<f64>,
}

/// The interior local maxima of each sampled curve of `curve` (as returned by
/// [`frequency_response`], increasing frequency), each refined by a
/// golden-section search of the analytic gain over the two neighbouring
/// sample intervals (in log frequency). End points are not peaks.
pub fn peaks_hz(params: &Params, variant: Variant, curve: &[FrfPoint]) -> Result<FrfPeaks> {
    params.validate()?;
    let displacement = |f: f64| body_displacement_gain(params, variant, 2.0 * PI * f);
    let acceleration = |f: f64| body_acceleration_gain(params, variant, 2.0 * PI * f);
    Ok(FrfPeaks {
        body_displacement: refined_peaks(curve, |p| p.body_displacement, &displacement)?,
        body_acceleration: refined_peaks(curve, |p| p.body_acceleration, &acceleration)?,
    })
}

fn refined_peaks(
    curve: &[FrfPoint],
    sample: impl Fn(&FrfPoint) -> f64,
    gain: &dyn Fn(f64) -> Result<f64>,
) -> Result<Vec<f64>> {
    let mut peaks = Vec::new();
    for window in curve.windows(3) {
        let (before, here, after) = (sample(&window[0]), sample(&window[1]), sample(&window[2]));
        if here > before && here >= after {
            peaks.push(golden_section_maximum(
                gain,
                window[0].frequency_hz,
                window[2].frequency_hz,
            )?);
        }
    }
    Ok(peaks)
}

/// Maximiser of `gain` on [low, high] (Hz, low > 0) by golden-section search
/// in log frequency, to 1e-10 relative.
fn golden_section_maximum(gain: &dyn Fn(f64) -> Result<f64>, low: f64, high: f64) -> Result<f64> {
    let inverse_golden = (5.0_f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (low.ln(), high.ln());
    let mut c = b - inverse_golden * (b - a);
    let mut d = a + inverse_golden * (b - a);
    let mut gain_c = gain(c.exp())?;
    let mut gain_d = gain(d.exp())?;
    while b - a > 1e-10 {
        if gain_c >= gain_d {
            b = d;
            d = c;
            gain_d = gain_c;
            c = b - inverse_golden * (b - a);
            gain_c = gain(c.exp())?;
        } else {
            a = c;
            c = d;
            gain_c = gain_d;
            d = a + inverse_golden * (b - a);
            gain_d = gain(d.exp())?;
        }
    }
    Ok((0.5 * (a + b)).exp())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Plant, X_S, X_T};
    use nalgebra::{Matrix6, Vector3, Vector6};

    /// `X_s/X_g` from the state space of Eq. (2):
    /// `e_{x_s}^T (iω I - A - b e_{x_t}^T e^{-iωτ})^{-1} e`.
    fn state_space_transfer(params: &Params, variant: Variant, omega: f64) -> Complex<f64> {
        let plant = Plant::new(*params, variant).unwrap();
        let delay = (Complex::new(0.0, -omega * params.tau)).exp();
        let mut matrix = Matrix6::<Complex<f64>>::identity() * Complex::new(0.0, omega);
        for row in 0..6 {
            for column in 0..6 {
                matrix[(row, column)] -= plant.a[(row, column)];
            }
            matrix[(row, X_T)] -= plant.b[row] * delay;
        }
        let road: Vector6<Complex<f64>> = plant.e.map(|v| Complex::new(v, 0.0));
        matrix.lu().solve(&road).unwrap()[X_S]
    }

    fn delayed_params() -> Params {
        Params::with_controller(30000.0, 0.012)
    }

    #[test]
    fn eq4_agrees_with_solving_eq3_directly() {
        let params = delayed_params();
        for omega in [0.3, 6.0, 40.0, 69.0, 150.0] {
            let a = dynamic_stiffness_matrix(&params, Variant::Tdvass, omega).unwrap();
            let rhs = Vector3::new(
                Complex::new(0.0, 0.0),
                Complex::new(0.0, 0.0),
                Complex::new(params.k_t, 0.0),
            );
            let direct = a.lu().solve(&rhs).unwrap()[0];
            let formula = body_displacement_transfer(&params, Variant::Tdvass, omega).unwrap();
            assert!(
                (direct - formula).norm() <= 1e-10 * direct.norm(),
                "omega {omega}: {direct} vs {formula}"
            );
        }
    }

    #[test]
    fn every_variant_agrees_with_the_state_space_of_eq2() {
        let params = delayed_params();
        for variant in Variant::ALL {
            for omega in [0.5, 7.0, 55.0, 120.0] {
                let expected = state_space_transfer(&params, variant, omega);
                let got = body_displacement_transfer(&params, variant, omega).unwrap();
                assert!(
                    (expected - got).norm() <= 1e-9 * expected.norm(),
                    "{variant:?} at {omega}: {expected} vs {got}"
                );
            }
        }
    }

    #[test]
    fn static_gains() {
        let params = Params::default();
        let low = 1e-6;
        let tdvass = body_displacement_gain(&params, Variant::Tdvass, low).unwrap();
        let expected = 1.0 - params.g / params.k_h;
        assert!((tdvass - expected).abs() < 1e-6, "{tdvass} vs {expected}");
        assert!((tdvass - 0.164).abs() < 5e-4);
        for variant in [Variant::Pvass, Variant::Cs] {
            let gain = body_displacement_gain(&params, variant, low).unwrap();
            assert!((gain - 1.0).abs() < 1e-6, "{variant:?}: {gain}");
        }
        let acceleration = body_acceleration_gain(&params, Variant::Cs, 3.0).unwrap();
        let displacement = body_displacement_gain(&params, Variant::Cs, 3.0).unwrap();
        assert!((acceleration - 9.0 * displacement).abs() < 1e-12 * acceleration);
    }

    #[test]
    fn sweep_is_log_spaced_and_validated() {
        let params = Params::default();
        let curve = frequency_response(&params, Variant::Pvass, 0.1, 30.0, 5).unwrap();
        assert_eq!(curve.len(), 5);
        assert_eq!(curve[0].frequency_hz, 0.1);
        assert_eq!(curve[4].frequency_hz, 30.0);
        let ratios: Vec<f64> = curve
            .windows(2)
            .map(|w| w[1].frequency_hz / w[0].frequency_hz)
            .collect();
        for r in &ratios {
            assert!((r - ratios[0]).abs() < 1e-12);
        }
        assert!(frequency_response(&params, Variant::Cs, 0.0, 30.0, 10).is_err());
        assert!(frequency_response(&params, Variant::Cs, 5.0, 1.0, 10).is_err());
        assert!(frequency_response(&params, Variant::Cs, 0.1, 30.0, 1).is_err());
        let bad = Params {
            k_t: f64::NAN,
            ..params
        };
        assert!(frequency_response(&bad, Variant::Cs, 0.1, 30.0, 10).is_err());
        assert!(body_displacement_gain(&params, Variant::Cs, f64::INFINITY).is_err());
    }

    #[test]
    fn cs_peaks_are_the_body_and_wheel_hop_modes() {
        let params = Params::default();
        let curve = frequency_response(&params, Variant::Cs, 0.1, 30.0, 300).unwrap();
        let peaks = peaks_hz(&params, Variant::Cs, &curve).unwrap();
        // Undamped body mode on the series spring, and wheel hop.
        let series = params.k_s * params.k_t / (params.k_s + params.k_t);
        let body_hz = (series / params.m_s).sqrt() / (2.0 * PI);
        let wheel_hz = ((params.k_s + params.k_t) / params.m_t).sqrt() / (2.0 * PI);
        assert!(!peaks.body_displacement.is_empty());
        assert!(
            (peaks.body_displacement[0] / body_hz - 1.0).abs() < 0.15,
            "{peaks:?}"
        );
        assert!(
            peaks
                .body_acceleration
                .iter()
                .any(|f| (f / wheel_hz - 1.0).abs() < 0.15),
            "{peaks:?} vs wheel hop {wheel_hz}"
        );
        // Each refined peak is a local maximum of the analytic gain.
        for &f in &peaks.body_displacement {
            let at = |f: f64| body_displacement_gain(&params, Variant::Cs, 2.0 * PI * f).unwrap();
            assert!(at(f) >= at(f * 1.001) && at(f) >= at(f * 0.999));
        }
        for &f in &peaks.body_acceleration {
            let at = |f: f64| body_acceleration_gain(&params, Variant::Cs, 2.0 * PI * f).unwrap();
            assert!(at(f) >= at(f * 1.001) && at(f) >= at(f * 0.999));
        }
    }
}
