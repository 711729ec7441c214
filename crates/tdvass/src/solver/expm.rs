//! The matrix exponential by the precise integration method (PIM):
//! scaling by 2^N, a fourth-order Taylor increment, and N squarings that
//! carry the increment `T_a = e^{Aτ} − I` apart from the identity so that
//! no digits are lost to round-off (Zhong's 2^N algorithm).
//!
//! Layer: linear algebra (docs/architecture.md); it imports nothing of the
//! crate.

use nalgebra::{DMatrix, SMatrix};

/// The scaled matrix norm is brought below 2^-SCALED_NORM_EXPONENT before
/// the Taylor increment; the truncation error of the fourth-order increment
/// is then below (2^-10)^5 / 5! ≈ 7e-18 relative.
const SCALED_NORM_EXPONENT: i32 = 10;

/// `e^{M}` for a square static matrix by the 2^N precise integration method.
///
/// N is what the scaling needs and no more (the classical PIM fixes
/// N = 20): the truncation bound depends on the scaled norm alone, so a
/// short step costs fewer products and is as accurate. These products are
/// most of the cost of building a simulator (a PSO builds tens of
/// thousands). N comes from the norm's binary exponent, exactly, the same
/// on every platform.
///
/// With `τ = 1 / 2^N`: `T_a = Mτ + (Mτ)²/2 + (Mτ)³/6 + (Mτ)⁴/24`, then N times
/// `T_a ← 2 T_a + T_a T_a` (that is `(I + T_a)² − I`), and `e^M = I + T_a`.
pub fn precise_exp<const D: usize>(m: &SMatrix<f64, D, D>) -> SMatrix<f64, D, D> {
    SMatrix::identity() + precise_exp_increment(m)
}

/// `e^{M} − I`, the increment `T_a` of [`precise_exp`] before the identity
/// is added (the same operations: `precise_exp(m)` is
/// `I + precise_exp_increment(m)` to the bit). Kept apart from the
/// identity, a short step's increment keeps its relative accuracy.
pub fn precise_exp_increment<const D: usize>(m: &SMatrix<f64, D, D>) -> SMatrix<f64, D, D> {
    let norm = m.abs().row_sum().max();
    let squarings = if norm > 0.0 && norm.is_finite() {
        (ceil_log2(norm) + SCALED_NORM_EXPONENT).max(0) as u32
    } else {
        0
    };
    let scaled = m * 0.5f64.powi(squarings as i32);
    // One buffer for every product (each overwrites all of it).
    let mut product = SMatrix::<f64, D, D>::zeros();
    multiply(&mut product, &scaled, &scaled);
    let scaled2 = product;
    multiply(
        &mut product,
        &scaled2,
        &(0.5 * SMatrix::identity() + scaled * (1.0 / 6.0) + scaled2 * (1.0 / 24.0)),
    );
    let mut increment = scaled + product;
    for _ in 0..squarings {
        multiply(&mut product, &increment, &increment);
        increment = increment * 2.0 + product;
    }
    increment
}

/// [`precise_exp`] of a square matrix whose size is known only at run
/// time (the full car's augmented system, `crate::car`): the same scaling,
/// increment and squarings, with nalgebra's dynamic product.
///
/// # Panics
///
/// If `m` is not square.
pub fn precise_exp_dynamic(m: &DMatrix<f64>) -> DMatrix<f64> {
    assert!(m.is_square(), "the exponential of a square matrix");
    let size = m.nrows();
    let norm = m.abs().row_sum().max();
    let squarings = if norm > 0.0 && norm.is_finite() {
        (ceil_log2(norm) + SCALED_NORM_EXPONENT).max(0) as u32
    } else {
        0
    };
    let scaled = m * 0.5f64.powi(squarings as i32);
    let identity = DMatrix::<f64>::identity(size, size);
    let scaled2 = &scaled * &scaled;
    let tail =
        &scaled2 * (identity.clone() * 0.5 + &scaled * (1.0 / 6.0) + &scaled2 * (1.0 / 24.0));
    let mut increment = scaled + tail;
    for _ in 0..squarings {
        let product = &increment * &increment;
        increment = increment * 2.0 + product;
    }
    identity + increment
}

/// `out = a b`, column by column: column j is `Σ_k a_k b_kj` summed in k
/// order from `a_0 b_0j`, each term rounded before it is added
/// (nalgebra's order for static matrices, so the bits are the same). One
/// loop of our own, because the code the compiler makes of the generic
/// product for these sizes changes with where it is instantiated; this
/// product is most of the cost of building a simulator.
#[inline(never)]
#[allow(clippy::needless_range_loop)]
fn multiply<const D: usize>(
    out: &mut SMatrix<f64, D, D>,
    a: &SMatrix<f64, D, D>,
    b: &SMatrix<f64, D, D>,
) {
    // Column-major arrays: `x.data.0[j]` is column j. Plain index loops
    // over arrays of constant length: no iterator adaptors whose inlining
    // could differ from one build of the crate to the next.
    let (a, b) = (&a.data.0, &b.data.0);
    let c = &mut out.data.0;
    for j in 0..D {
        let scale = b[j][0];
        for i in 0..D {
            c[j][i] = a[0][i] * scale;
        }
        for k in 1..D {
            let scale = b[j][k];
            for i in 0..D {
                c[j][i] += a[k][i] * scale;
            }
        }
    }
}

/// The least integer e with `2^e >= x`, for a finite x > 0, from its bits
/// (no logarithm: exact on every platform).
fn ceil_log2(x: f64) -> i32 {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let mantissa = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        // Subnormal: below 2^-1022, far below any scaling that matters.
        return -1022;
    }
    let exponent = biased - 1023;
    if mantissa == 0 {
        exponent
    } else {
        exponent + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;

    #[test]
    fn agrees_with_nalgebra_exp() {
        let plant = crate::model::Plant::new(
            crate::model::Params::default(),
            crate::model::Variant::Tdvass,
        )
        .unwrap();
        for h in [1e-5, 1e-4, 1e-3, 0.05, 1.0] {
            let m: Matrix6<f64> = plant.a * h;
            let ours = precise_exp(&m);
            let reference = m.exp();
            let scale = reference.abs().max().max(1.0);
            assert!(
                (ours - reference).abs().max() < 1e-12 * scale,
                "h = {h}: {}",
                (ours - reference).abs().max()
            );
        }
    }

    #[test]
    fn the_dynamic_exponential_is_the_static_one() {
        let plant = crate::model::Plant::new(
            crate::model::Params::default(),
            crate::model::Variant::Tdvass,
        )
        .unwrap();
        for h in [1e-4, 1e-2, 1.0] {
            let m: Matrix6<f64> = plant.a * h;
            let ours = precise_exp_dynamic(&DMatrix::from_column_slice(6, 6, m.as_slice()));
            let reference = precise_exp(&m);
            let scale = reference.abs().max();
            let gap = (ours - DMatrix::from_column_slice(6, 6, reference.as_slice()))
                .abs()
                .max();
            assert!(gap <= 1e-13 * scale, "h = {h}: {gap}");
        }
    }

    #[test]
    fn ceil_log2_is_exact() {
        for (x, e) in [
            (1.0, 0),
            (2.0, 1),
            (3.0, 2),
            (0.5, -1),
            (0.75, 0),
            (1024.0, 10),
            (1025.0, 11),
        ] {
            assert_eq!(ceil_log2(x), e, "{x}");
        }
        for i in 1..2000 {
            let x = i as f64 * 0.37;
            assert_eq!(ceil_log2(x), x.log2().ceil() as i32, "{x}");
        }
    }

    #[test]
    fn rotation_and_nilpotent_cases_are_exact() {
        let theta: f64 = 0.7;
        let rotation = nalgebra::Matrix2::new(0.0, theta, -theta, 0.0);
        let e = precise_exp(&rotation);
        assert!((e[(0, 0)] - theta.cos()).abs() < 1e-15);
        assert!((e[(0, 1)] - theta.sin()).abs() < 1e-15);
        let shift = nalgebra::Matrix3::new(0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
        let e = precise_exp(&shift);
        assert!((e[(0, 2)] - 2.0).abs() < 1e-14);
        assert_eq!(
            precise_exp(&nalgebra::Matrix3::<f64>::zeros()),
            nalgebra::Matrix3::identity()
        );
    }
}
