//! The optimiser on test functions with known minima, its settings' checks
//! and its reproducibility.

use super::*;
use std::cell::RefCell;

fn sphere(x: &[f64]) -> Option<f64> {
    Some(x.iter().map(|v| v * v).sum())
}

fn rosenbrock(x: &[f64]) -> Option<f64> {
    let (a, b) = (x[0], x[1]);
    Some((1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2))
}

fn small(particles: usize, iterations: usize, seed: u64) -> PsoSettings {
    PsoSettings {
        particles,
        iterations,
        seed,
        ..PsoSettings::default()
    }
}

fn cube(dim: usize, lo: f64, hi: f64) -> Bounds {
    Bounds::new(vec![lo; dim], vec![hi; dim]).unwrap()
}

fn assert_non_increasing(history: &[f64]) {
    for pair in history.windows(2) {
        assert!(pair[1] <= pair[0], "history increased: {pair:?}");
    }
}

#[test]
fn default_matches_the_paper_swarm() {
    let s = PsoSettings::default();
    assert_eq!((s.particles, s.iterations), (100, 200));
    assert_eq!(s.inertia(0), 0.9);
    assert!((s.inertia(199) - 0.4).abs() < 1e-15);
    assert!(s.inertia(100) < s.inertia(99));
    s.validate().unwrap();
}

#[test]
fn sphere_2d() {
    let r = pso_minimize(sphere, &cube(2, -5.0, 5.0), &small(20, 150, 7), None).unwrap();
    assert!(r.best_value < 1e-8, "best {}", r.best_value);
    assert_eq!(r.history.len(), 150);
    assert_eq!(r.evaluations, 20 * 151);
    assert_eq!(*r.history.last().unwrap(), r.best_value);
    assert_non_increasing(&r.history);
}

#[test]
fn sphere_5d() {
    let r = pso_minimize(sphere, &cube(5, -5.0, 5.0), &small(30, 300, 3), None).unwrap();
    assert!(r.best_value < 1e-8, "best {}", r.best_value);
    assert_eq!(sphere(&r.best_position), Some(r.best_value));
    assert_non_increasing(&r.history);
}

#[test]
fn rosenbrock_2d() {
    let r = pso_minimize(rosenbrock, &cube(2, -2.0, 2.0), &small(30, 400, 11), None).unwrap();
    let p = &r.best_position;
    assert!(
        (p[0] - 1.0).abs() < 1e-3 && (p[1] - 1.0).abs() < 1e-3,
        "best position {p:?}, value {}",
        r.best_value
    );
    assert_non_increasing(&r.history);
}

#[test]
fn same_seed_same_result_and_other_seed_differs() {
    let b = cube(3, -3.0, 4.0);
    let a = pso_minimize(rosenbrock3, &b, &small(15, 40, 42), None).unwrap();
    let again = pso_minimize(rosenbrock3, &b, &small(15, 40, 42), None).unwrap();
    assert_eq!(a, again);
    let other = pso_minimize(rosenbrock3, &b, &small(15, 40, 43), None).unwrap();
    assert_ne!(a.best_position, other.best_position);
}

fn rosenbrock3(x: &[f64]) -> Option<f64> {
    Some(
        x.windows(2)
            .map(|p| (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2))
            .sum(),
    )
}

#[test]
fn bit_identical_whatever_the_thread_count() {
    let b = cube(3, -3.0, 4.0);
    let s = small(17, 60, 5);
    // An objective with a few infeasible regions, to exercise those paths.
    let f = |x: &[f64]| {
        if x[0] > 3.0 {
            None
        } else if x[1] > 3.5 {
            Some(f64::NAN)
        } else {
            rosenbrock3(x)
        }
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| pso_minimize(f, &b, &s, None).unwrap())
    };
    let one = run(1);
    let two = run(2);
    let four = run(4);
    let ambient = pso_minimize(f, &b, &s, None).unwrap();
    for other in [&two, &four, &ambient] {
        assert_eq!(one.best_value.to_bits(), other.best_value.to_bits());
        assert_eq!(one.best_position.len(), other.best_position.len());
        for (p, q) in one.best_position.iter().zip(&other.best_position) {
            assert_eq!(p.to_bits(), q.to_bits());
        }
        let h1: Vec<u64> = one.history.iter().map(|v| v.to_bits()).collect();
        let h2: Vec<u64> = other.history.iter().map(|v| v.to_bits()).collect();
        assert_eq!(h1, h2);
        assert_eq!(one.evaluations, other.evaluations);
    }
}

#[test]
fn infeasible_half_domain_is_avoided() {
    // Minimum of the unconstrained function at (-1, 0) is infeasible; the
    // feasible minimum is (0, 0) with value 1, on the feasibility edge.
    let f = |x: &[f64]| {
        if x[0] < 0.0 {
            None
        } else {
            Some((x[0] + 1.0).powi(2) + x[1] * x[1])
        }
    };
    let r = pso_minimize(f, &cube(2, -2.0, 2.0), &small(20, 200, 9), None).unwrap();
    assert!(r.best_position[0] >= 0.0);
    assert!((r.best_value - 1.0).abs() < 1e-6, "best {}", r.best_value);
    assert!(r.best_position[1].abs() < 1e-3);
    assert_non_increasing(&r.history);
}

#[test]
fn interior_feasible_minimum_with_nan_region() {
    // NaN on half the domain: treated as infeasible, never a best.
    let f = |x: &[f64]| {
        if x[1] < 0.0 {
            Some(f64::NAN)
        } else {
            Some((x[0] - 0.5).powi(2) + (x[1] - 1.0).powi(2))
        }
    };
    let r = pso_minimize(f, &cube(2, -3.0, 3.0), &small(20, 150, 2), None).unwrap();
    assert!(r.best_value < 1e-8, "best {}", r.best_value);
    assert!(r.best_value.is_finite());
}

#[test]
fn minimum_on_the_bound_is_reached() {
    // Minimum outside the box: the optimum is the corner (1, 1).
    let f = |x: &[f64]| Some((x[0] - 3.0).powi(2) + (x[1] - 3.0).powi(2));
    let r = pso_minimize(f, &cube(2, 0.0, 1.0), &small(10, 50, 4), None).unwrap();
    assert_eq!(r.best_position, vec![1.0, 1.0]);
    assert_eq!(r.best_value, 8.0);
}

#[test]
fn positions_stay_inside_the_bounds() {
    let b = Bounds::new(vec![0.0, 10.0], vec![1e-3, 20.0]).unwrap();
    let f = |x: &[f64]| {
        assert!((0.0..=1e-3).contains(&x[0]), "x0 = {}", x[0]);
        assert!((10.0..=20.0).contains(&x[1]), "x1 = {}", x[1]);
        Some(-x[0] * x[1])
    };
    let r = pso_minimize(f, &b, &small(8, 30, 1), None).unwrap();
    assert!(r.best_value < 0.0);
}

#[test]
fn all_infeasible_is_an_error() {
    let err =
        pso_minimize(|_: &[f64]| None, &cube(2, 0.0, 1.0), &small(5, 4, 1), None).unwrap_err();
    assert!(matches!(err, Error::Numerical { .. }), "{err}");
}

#[test]
fn progress_is_reported_every_iteration() {
    let seen = RefCell::new(Vec::new());
    let report = |k: usize, best: f64| seen.borrow_mut().push((k, best));
    let r = pso_minimize(sphere, &cube(2, -1.0, 1.0), &small(6, 12, 8), Some(&report)).unwrap();
    let seen = seen.into_inner();
    assert_eq!(seen.len(), 12);
    for (j, (k, best)) in seen.iter().enumerate() {
        assert_eq!(*k, j + 1);
        assert_eq!(*best, r.history[j]);
    }
}

#[test]
fn zero_iterations_returns_the_initial_best() {
    let r = pso_minimize(sphere, &cube(2, -1.0, 1.0), &small(6, 0, 8), None).unwrap();
    assert!(r.history.is_empty());
    assert_eq!(r.evaluations, 6);
    assert!(r.best_value.is_finite());
}

#[test]
fn invalid_bounds_are_rejected() {
    let cases = [
        (vec![0.0, 1.0], vec![1.0]),
        (vec![], vec![]),
        (vec![1.0], vec![1.0]),
        (vec![2.0], vec![1.0]),
        (vec![f64::NAN], vec![1.0]),
        (vec![0.0], vec![f64::INFINITY]),
        (vec![-f64::MAX], vec![f64::MAX]),
    ];
    for (lower, upper) in cases {
        let err = Bounds::new(lower.clone(), upper.clone()).unwrap_err();
        assert!(
            matches!(
                err,
                Error::InvalidParameter { .. } | Error::InvalidSetting { .. }
            ),
            "{err}"
        );
        // The optimiser validates public-field bounds too.
        let b = Bounds { lower, upper };
        assert!(pso_minimize(sphere, &b, &small(4, 2, 1), None).is_err());
    }
}

#[test]
fn invalid_settings_are_rejected() {
    let b = cube(2, -1.0, 1.0);
    let bad = [
        PsoSettings {
            particles: 0,
            ..PsoSettings::default()
        },
        PsoSettings {
            inertia_start: f64::NAN,
            ..PsoSettings::default()
        },
        PsoSettings {
            social: -1.0,
            ..PsoSettings::default()
        },
        PsoSettings {
            max_velocity_fraction: 0.0,
            ..PsoSettings::default()
        },
    ];
    for s in bad {
        assert!(s.validate().is_err());
        assert!(pso_minimize(sphere, &b, &s, None).is_err());
    }
}
