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
        let intervals = stable_delay_intervals(&table1(), sign * bound.gain * 0.99, 0.5).unwrap();
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
    let solver = CharacteristicRootSolver::new(&tdvass(-50000.0, 0.0), Variant::Tdvass).unwrap();
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
