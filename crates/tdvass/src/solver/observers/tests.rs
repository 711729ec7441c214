use crate::metrics::RmsValues;
use crate::model::State;
use crate::model::{Params, Performance, Variant};
use crate::road::{RandomRoad, RoadSpec};
use crate::solver::Simulator;
use crate::solver::stepping::stepping;
use crate::solver::{DelayRegime, SimulationConfig, simulate};

/// Gauss–Legendre nodes on [0, 1] and weights (5 points: exact for
/// degree 9).
const GAUSS_LEGENDRE: [(f64, f64); 5] = [
    (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
    (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
    (0.5, 0.284_444_444_444_444_44),
    (0.769_234_655_052_841_6, 0.239_314_335_249_683_23),
    (0.953_089_922_969_332, 0.118_463_442_528_094_54),
];

/// `∫_{t_0}^{t_end} y²` by 5-point Gauss–Legendre on every grid step,
/// split at the road breakpoints inside it, from the dense output of a
/// separate simulator (an independent quadrature of the same solution).
fn reference_integral(cfg: &SimulationConfig, t_end: f64) -> [f64; 3] {
    let mut probe = Simulator::new(cfg.clone()).unwrap();
    let mut breaks = Simulator::new(cfg.clone()).unwrap();
    let h = probe.grid.step;
    let mut total = [0.0; 3];
    let mut k = 0u64;
    let mut a = cfg.start_time;
    while a < t_end {
        let b = probe.grid_time(k + 1).min(t_end);
        let mut start = a;
        while start < b {
            let piece = breaks.inputs.piece_from(start);
            let end = if piece.end() < b && !breaks.coincide(piece.end(), b) {
                piece.end()
            } else {
                b
            };
            for (x, w) in GAUSS_LEGENDRE {
                let t = start + x * (end - start);
                probe.advance_to(t).unwrap();
                let y = Performance::at(&probe.plant, &probe.state(), piece.value(t));
                let y = [
                    y.body_acceleration,
                    y.suspension_deflection,
                    y.tire_deflection,
                ];
                for i in 0..3 {
                    total[i] += w * (end - start) * y[i] * y[i];
                }
            }
            start = end;
        }
        assert!(b - a <= h * (1.0 + 1e-9));
        a = b;
        k += 1;
    }
    total
}

/// Configurations that reach the delay regimes, roads and states of
/// the tests of this file (and of `deferred`).
pub(in crate::solver) fn configs() -> Vec<(&'static str, SimulationConfig)> {
    let base = SimulationConfig::default();
    let iso = RoadSpec::Iso8608(RandomRoad {
        seed: 7,
        ..RandomRoad::default()
    });
    vec![
        ("TDVASS harmonic", base.clone()),
        (
            "CS ISO 8608 C seed 7",
            SimulationConfig {
                variant: Variant::Cs,
                road: iso.clone(),
                ..base.clone()
            },
        ),
        (
            "TDVASS paper road (kinks on grid nodes)",
            SimulationConfig {
                params: Params::with_controller(2528.0, 1.28e-4),
                road: RoadSpec::PaperCompatible {
                    road: RandomRoad::default(),
                    sample_interval: 0.1,
                },
                ..base.clone()
            },
        ),
        (
            "TDVASS tau = 0.03, g = 20000, from a displaced state",
            SimulationConfig {
                params: Params::with_controller(20000.0, 0.03),
                initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
                ..base.clone()
            },
        ),
        (
            "TDVASS delay inside the step, ISO road",
            SimulationConfig {
                params: Params::with_controller(6000.0, 3.7e-5),
                road: iso,
                ..base
            },
        ),
    ]
}

#[test]
fn time_average_matches_an_independent_quadrature() {
    for (name, cfg) in configs() {
        // An end time off the grid: the partial last step counts too.
        // The quadrature's own accuracy: a tolerance well below the
        // bound asked here.
        let cfg = SimulationConfig {
            tolerance: 1e-11,
            ..cfg
        };
        let t_end = 1.234_567;
        let mut sim = Simulator::new(cfg.clone()).unwrap();
        sim.advance_to(t_end).unwrap();
        let ours = sim.accumulated_now().integral;
        let reference = reference_integral(&cfg, t_end);
        for i in 0..3 {
            let error = (ours[i] - reference[i]).abs() / reference[i];
            eprintln!("{name}, output {i}: relative difference {error:.1e}");
            assert!(
                error < 1e-9,
                "{name}, output {i}: {} against {} ({error:e})",
                ours[i],
                reference[i]
            );
        }
        let rms = sim.rms();
        let expected = (reference[0] / t_end).sqrt();
        assert!((rms.body_acceleration - expected).abs() < 1e-9 * expected);
    }
}

#[test]
fn rms_is_zero_at_the_start_and_continuous_in_time() {
    let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
    assert_eq!(sim.rms(), RmsValues::default());
    sim.advance_to(0.5).unwrap();
    let h = sim.grid.step;
    // Across a grid node, from inside the step before to inside the next.
    let node = sim.grid_time(sim.trajectory.grid_index + 1);
    let mut previous = None;
    for offset in [-0.3, -1e-6, 0.0, 1e-6, 0.3] {
        sim.advance_to(node + offset * h).unwrap();
        let now = sim.rms().body_acceleration;
        if let Some(before) = previous {
            let change: f64 = now - before;
            assert!(change.abs() < 1e-4 * now, "{offset}: {before} -> {now}");
        }
        previous = Some(now);
    }
}

#[test]
fn objective_is_continuous_across_a_change_of_the_internal_grid() {
    // With the step bound 1e-3 s: tau just below 1e-3 lies inside the
    // step, 1e-3 is one whole step, 2e-3 two, and a hair more needs
    // three steps of 6.67e-4 s.
    let at = |tau: f64| {
        let cfg = SimulationConfig {
            params: Params::with_controller(5386.0, tau),
            max_internal_step: 1e-3,
            ..SimulationConfig::default()
        };
        let regime = Simulator::new(cfg.clone()).unwrap().grid().regime;
        (simulate(cfg, 15.0).unwrap().objective, regime)
    };
    let (j_inside, inside) = at(1e-3 * (1.0 - 1e-9));
    let (j_one, one) = at(1e-3);
    let (j_two, two) = at(2e-3);
    let (j_three, three) = at(2e-3 * (1.0 + 1e-9));
    assert!(
        matches!(inside, DelayRegime::InsideStep { .. }),
        "{inside:?}"
    );
    assert_eq!(one, DelayRegime::WholeSteps { m: 1 });
    assert_eq!(two, DelayRegime::WholeSteps { m: 2 });
    assert_eq!(three, DelayRegime::WholeSteps { m: 3 });
    for (a, b) in [(j_inside, j_one), (j_two, j_three)] {
        assert!((a - b).abs() < 1e-9 * a, "{a} against {b}");
    }
}

#[test]
fn taylor_dense_output_near_a_node_matches_the_exact_step() {
    for (name, cfg) in configs() {
        let mut sim = Simulator::new(cfg).unwrap();
        sim.advance_to(0.7).unwrap();
        let k = sim.trajectory.grid_index;
        let (t, x) = (
            sim.trajectory.committed_time,
            sim.trajectory.committed_state,
        );
        assert_eq!(t, sim.grid_time(k));
        let h = sim.grid.step;
        for delta in [1e-13, 3e-11, h / 1024.0] {
            let series = stepping!(sim).state_near(sim.trajectory.committed_point(), delta);
            let exact = stepping!(sim).integrate_within_step(k, t, x, t + delta);
            let scale = exact.amax();
            let error = (series - exact).amax();
            assert!(
                error < 1e-13 * scale,
                "{name}, offset {delta}: {error:e} of {scale:e}"
            );
        }
    }
}

#[test]
fn accumulated_communication_times_commit_the_same_nodes() {
    for (name, cfg) in configs() {
        for step in [1e-3, 1e-3 / 3.0, 7.3e-3] {
            let mut exact = Simulator::new(cfg.clone()).unwrap();
            let mut drifting = Simulator::new(cfg.clone()).unwrap();
            let mut t = 0.0;
            let mut worst_drift: f64 = 0.0;
            for i in 1..=(3.0 / step) as u64 {
                t += step;
                let t_exact = i as f64 * step;
                worst_drift = worst_drift.max((t - t_exact).abs());
                exact.advance_to(t_exact).unwrap();
                drifting.advance_to(t).unwrap();
                assert_eq!(
                    exact.trajectory.grid_index, drifting.trajectory.grid_index,
                    "{name}, step {step}, t = {t}"
                );
                let (a, b) = (exact.rms(), drifting.rms());
                let rates = exact.output_derivatives();
                for (u, v) in [
                    (a.body_acceleration, b.body_acceleration),
                    (a.suspension_deflection, b.suspension_deflection),
                    (a.tire_deflection, b.tire_deflection),
                ] {
                    assert!((u - v).abs() <= 1e-12 * u, "{name}, {step}, {t}: {u} {v}");
                }
                let drift = (t - t_exact).abs();
                let (x, y) = (exact.state(), drifting.state());
                for j in 0..6 {
                    let allowed = 1e-12 * x.amax() + 2.0 * drift * rates.state[j].abs();
                    assert!((x[j] - y[j]).abs() <= allowed, "{name}, {step}, {t}, {j}");
                }
            }
            assert!(worst_drift > 0.0 || step == 7.3e-3);
        }
    }
}
