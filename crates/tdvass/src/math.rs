//! The transcendental functions that the simulation's results depend on
//! (the harmonic road's sine and cosine, the ISO 8608 road's decay), from
//! one pure-Rust implementation, the `libm` crate: every platform then
//! computes the same bits. (The platforms' own `sin` differ in the last
//! bit: Windows' from glibc's.)

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// `sin x`.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// `cos x`.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// `e^x − 1`, accurate near 0.
#[inline]
pub fn exp_m1(x: f64) -> f64 {
    libm::expm1(x)
}

#[cfg(test)]
mod tests {
    #[test]
    fn agrees_with_the_platform_to_rounding() {
        for i in 0..1000 {
            let x = (i as f64 - 500.0) * 0.0371;
            let (s, c) = super::sin_cos(x);
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON, "{x}");
            assert!((c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
            assert_eq!(s, super::sin(x));
            assert_eq!(c, super::cos(x));
            let e = super::exp(x * 0.1);
            assert!((e - (x * 0.1).exp()).abs() <= 2.0 * f64::EPSILON * e);
            let m = super::exp_m1(x * 1e-3);
            assert!((m - (x * 1e-3).exp_m1()).abs() <= 2.0 * f64::EPSILON * m.abs().max(1e-300));
        }
    }
}
