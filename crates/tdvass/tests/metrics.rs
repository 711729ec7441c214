//! The metrics beyond Eq. (6): ISO 2631-1 comfort (a_w, RMS a_w, VDV), road
//! holding (dynamic tire load, its RMS ratio, contact loss) and working
//! space (max |SDD|), against independent computations.

mod common;

use common::{harmonic, iso};
use tdvass::analysis::frf::body_acceleration_gain;
use tdvass::comfort::wk_response;
use tdvass::model::State;
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::{Metrics, Outputs, SimulationConfig, Simulator, simulate};
use tdvass::{Params, Variant};

/// `∫_{t_0}^{t} a_w²` and `∫ a_w⁴` from the outputs at t.
fn weighted_integrals(o: &Outputs) -> (f64, f64) {
    let c = o.comfort.expect("comfort on");
    (
        c.rms_weighted_body_acceleration.powi(2) * o.time,
        c.vibration_dose_value.powi(4),
    )
}

/// Harmonic road, long run: the RMS of a_w over whole periods of the
/// steady state is `|W_k(jω)| × |BA| / √2`, with the steady-state BA
/// amplitude `|A_s/X_g| × amplitude` from the frequency response of
/// Eq. (5), and `∫ a_w⁴` per unit time is `3/8 (|W_k| |BA|)⁴`.
/// Tolerance 1e-7 relative: the transients from rest have decayed by
/// e^-30 after 40 s, and the integrals are exact to ~1e-12.
#[test]
fn harmonic_weighted_acceleration_matches_the_frequency_responses() {
    for (variant, omega) in [
        (Variant::Tdvass, 5.0),
        (Variant::Pvass, 2.0 * std::f64::consts::PI * 4.0),
        (Variant::Cs, 2.0 * std::f64::consts::PI * 1.5),
    ] {
        let amplitude = 0.01; // m
        let params = Params::default();
        let config = SimulationConfig {
            variant,
            params,
            road: harmonic(amplitude, omega),
            metrics: Metrics::Comfort,
            ..SimulationConfig::default()
        };
        let period = 2.0 * std::f64::consts::PI / omega;
        let (t1, periods) = (40.0, (20.0 / period).ceil());
        let t2 = t1 + periods * period;
        let mut sim = Simulator::new(config).unwrap();
        sim.advance_to(t1).unwrap();
        let (square1, fourth1) = weighted_integrals(&sim.outputs());
        sim.advance_to(t2).unwrap();
        let (square2, fourth2) = weighted_integrals(&sim.outputs());
        let rms = ((square2 - square1) / (t2 - t1)).sqrt();
        let body = body_acceleration_gain(&params, variant, omega).unwrap() * amplitude;
        let weighted = wk_response(omega / (2.0 * std::f64::consts::PI)).norm() * body;
        let expected = weighted / 2f64.sqrt();
        let error = (rms - expected).abs() / expected;
        println!(
            "{variant:?} at {omega:.3} rad/s: RMS a_w {rms:.9} m/s², |W_k| |BA| / √2 = {expected:.9} m/s², relative {error:.1e}"
        );
        assert!(
            error < 1e-7,
            "{variant:?}, {omega}: {rms} against {expected}"
        );
        let fourth = (fourth2 - fourth1) / (t2 - t1);
        let expected_fourth = 0.375 * weighted.powi(4);
        let error = (fourth - expected_fourth).abs() / expected_fourth;
        println!(
            "  mean a_w⁴ {fourth:.6e} against 3/8 (|W_k| |BA|)⁴ = {expected_fourth:.6e}, relative {error:.1e}"
        );
        assert!(error < 1e-7);
    }
}

/// A road far below the W_k band (0.05 Hz, where |W_k| ≈ 0.0078 from the
/// band-limiting high pass): over two whole periods of the steady state
/// (40 s to 80 s), RMS a_w / RMS BA is |W_k(0.05 Hz)| to 1e-6 relative.
#[test]
fn weighting_removes_what_w_k_removes() {
    let frequency = 0.05; // Hz
    let mut sim = Simulator::new(SimulationConfig {
        road: harmonic(0.5, 2.0 * std::f64::consts::PI * frequency),
        metrics: Metrics::Comfort,
        ..SimulationConfig::default()
    })
    .unwrap();
    let window = |sim: &mut Simulator, t: f64| {
        sim.advance_to(t).unwrap();
        let o = sim.outputs();
        let (square, _) = weighted_integrals(&o);
        (square, o.rms.body_acceleration.powi(2) * t)
    };
    let (a1, b1) = window(&mut sim, 40.0);
    let (a2, b2) = window(&mut sim, 80.0);
    let ratio = ((a2 - a1) / (b2 - b1)).sqrt();
    let expected = wk_response(frequency).norm();
    println!("0.05 Hz road: RMS a_w / RMS BA = {ratio:.9}, |W_k(0.05 Hz)| = {expected:.9}");
    assert!(expected < 0.01);
    assert!((ratio - expected).abs() < 1e-6 * expected, "{ratio}");
}

/// The dynamic tire load is `k_t (x_g − x_t)` of the reported state and
/// road, and its RMS ratio `k_t RMS(TDD) / W`, at every level of metrics.
#[test]
fn dynamic_tire_load_is_the_tire_spring_force_of_the_states() {
    for variant in Variant::ALL {
        for metrics in Metrics::ALL {
            let params = Params::default();
            let mut sim = Simulator::new(SimulationConfig {
                variant,
                metrics,
                road: iso(RoadClass::D, 20.0),
                ..SimulationConfig::default()
            })
            .unwrap();
            let static_load = params.static_load(variant);
            let masses = match variant {
                Variant::Cs => params.m_s + params.m_t,
                _ => params.m_s + params.m_h + params.m_t,
            };
            assert_eq!(static_load, masses * 9.80665);
            let mut largest: f64 = 0.0;
            for i in 1..=300 {
                sim.advance_to(i as f64 * 0.01237).unwrap();
                let o = sim.outputs();
                let x_t = o.state[4];
                let load = params.k_t * (o.road_displacement - x_t);
                assert_eq!(o.dynamic_tire_load, load);
                let from_tdd = -params.k_t * o.performance.tire_deflection;
                assert!((o.dynamic_tire_load - from_tdd).abs() <= 1e-12 * load.abs().max(1.0));
                assert_eq!(
                    o.rms_dynamic_tire_load_ratio,
                    params.k_t * o.rms.tire_deflection / static_load
                );
                largest = largest.max(load.abs());
            }
            assert!(largest > 100.0, "{variant:?}: {largest} N");
        }
    }
}

/// Contact loss: on an ISO 8608 class H road at 30 m/s the tire leaves the
/// road (dynamic tire load below −W), on class A it does not. The reported
/// first loss lies where the exact dense output crosses −W (to 1e-6 W), and
/// the time without contact agrees with a sampling of the dense output
/// every 1e-5 s to within 1e-3 s plus 1 % (the sampling's own error).
#[test]
fn contact_loss_on_class_h_at_30_m_s_and_not_on_class_a() {
    for variant in [Variant::Pvass, Variant::Cs] {
        let config = |class| SimulationConfig {
            variant,
            road: iso(class, 30.0),
            metrics: Metrics::RoadHolding,
            ..SimulationConfig::default()
        };
        let duration = 15.0;
        let smooth = simulate(config(RoadClass::A), duration).unwrap();
        let holding = smooth.road_holding.unwrap();
        println!("{variant:?} class A at 30 m/s: {holding:?}");
        assert_eq!(holding.contact_loss_time, 0.0);
        assert_eq!(holding.first_contact_loss, None);
        assert!(smooth.rms_dynamic_tire_load_ratio < 1.0 / 3.0);

        let rough = simulate(config(RoadClass::H), duration).unwrap();
        let holding = rough.road_holding.unwrap();
        println!(
            "{variant:?} class H at 30 m/s: contact lost for {:.4} s, first {:?}, RMS load ratio {:.3}",
            holding.contact_loss_time,
            holding.first_contact_loss,
            rough.rms_dynamic_tire_load_ratio
        );
        assert!(holding.contact_loss_time > 0.01);
        let first = holding.first_contact_loss.expect("a first loss");
        let static_load = Params::default().static_load(variant);
        assert_eq!(first.static_load, static_load);
        assert_eq!(first.dynamic_tire_load, -static_load);

        // The crossing against the exact dense output.
        let mut probe = Simulator::new(config(RoadClass::H)).unwrap();
        probe.advance_to(first.time).unwrap();
        let at = probe.outputs().dynamic_tire_load;
        println!(
            "  dynamic tire load at the reported first loss: {at:.9} N (−W = {:.9} N)",
            -static_load
        );
        assert!((at + static_load).abs() < 1e-6 * static_load);
        let before = first.time - 1e-6;
        let mut early = Simulator::new(config(RoadClass::H)).unwrap();
        early.advance_to(before).unwrap();
        assert!(early.outputs().dynamic_tire_load > -static_load);
        assert_eq!(early.first_contact_loss(), None);

        // Against a sampling of the dense output.
        let mut sampled = Simulator::new(config(RoadClass::H)).unwrap();
        let dt = 1e-5;
        let mut below = 0u64;
        let samples = (duration / dt) as u64;
        for i in 1..=samples {
            sampled.advance_to(i as f64 * dt).unwrap();
            if sampled.outputs().dynamic_tire_load < -static_load {
                below += 1;
            }
        }
        let estimate = below as f64 * dt;
        let reported = holding.contact_loss_time;
        println!("  sampled every 1e-5 s: {estimate:.5} s, reported {reported:.5} s");
        assert!((estimate - reported).abs() < 1e-3 + 0.01 * reported);
    }
}

/// The largest |SDD| is located inside the steps (`solver::holding`): it
/// is at least the largest node value, within 1e-6 (the tolerance, and
/// what the sampling can miss) of the largest of a sampling fifty times
/// denser than the nodes, and the same to the bit whether the run goes in
/// one call or node by node.
#[test]
fn max_suspension_deflection_is_located_inside_the_steps() {
    for road in [RoadSpec::paper_harmonic(), iso(RoadClass::E, 20.0)] {
        for params in [Params::default(), Params::with_controller(2528.0, 1.28e-4)] {
            let config = SimulationConfig {
                params,
                road: road.clone(),
                metrics: Metrics::RoadHolding,
                ..SimulationConfig::default()
            };
            let mut sim = Simulator::new(config.clone()).unwrap();
            let h = sim.grid().step;
            let nodes = (2.0 / h).round() as u64;
            let end = nodes as f64 * h;
            let reported = {
                let mut whole = Simulator::new(config.clone()).unwrap();
                whole.advance_to(end).unwrap();
                whole
                    .outputs()
                    .road_holding
                    .unwrap()
                    .max_suspension_deflection
            };
            let mut node_largest: f64 = 0.0;
            for k in 1..=nodes {
                sim.advance_to(k as f64 * h).unwrap();
                let o = sim.outputs();
                node_largest = node_largest.max(o.performance.suspension_deflection.abs());
            }
            let node_by_node = sim
                .outputs()
                .road_holding
                .unwrap()
                .max_suspension_deflection;
            let mut dense = Simulator::new(config).unwrap();
            let mut sampled: f64 = 0.0;
            for i in 1..=50 * nodes {
                dense.advance_to(i as f64 * h / 50.0).unwrap();
                sampled = sampled.max(dense.outputs().performance.suspension_deflection.abs());
            }
            println!(
                "{}: max |SDD| {reported} m, nodes {node_largest} m, dense {sampled} m",
                road.kind()
            );
            assert_eq!(reported, node_by_node);
            assert!(reported >= node_largest && reported >= sampled * (1.0 - 1e-6));
            assert!(reported <= sampled * (1.0 + 1e-6), "{reported} {sampled}");
            assert!(reported > 1e-3);
        }
    }
}

/// Every level of metrics leaves the paper's outputs (state, BA, SDD, TDD,
/// x_g, u, RMS values, J and their derivatives) bit-identical, on every
/// kind of road and delay.
#[test]
fn metrics_levels_leave_the_paper_outputs_bit_identical() {
    let base = SimulationConfig::default();
    let configs = [
        base.clone(),
        SimulationConfig {
            variant: Variant::Cs,
            road: iso(RoadClass::C, 20.0),
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(2528.0, 1.28e-4),
            road: iso(RoadClass::H, 30.0),
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(40000.0, 3.7e-5),
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(6000.0, 0.0),
            road: RoadSpec::PaperCompatible {
                road: RandomRoad::default(),
                sample_interval: 0.1,
            },
            ..base
        },
    ];
    for config in configs {
        let bits = |metrics: Metrics| {
            let mut sim = Simulator::new(SimulationConfig {
                metrics,
                ..config.clone()
            })
            .unwrap();
            let mut v: Vec<u64> = Vec::new();
            for i in 1..=40 {
                sim.advance_to(i as f64 * 0.0731).unwrap();
                let o = sim.outputs();
                let d = sim.output_derivatives();
                let mut values = o.core_values().to_vec();
                values.extend(d.state.iter());
                values.extend([
                    o.dynamic_tire_load,
                    o.rms_dynamic_tire_load_ratio,
                    d.rms.body_acceleration,
                    d.objective,
                ]);
                v.extend(values.into_iter().map(f64::to_bits));
            }
            let run = simulate(
                SimulationConfig {
                    metrics,
                    ..config.clone()
                },
                3.0,
            )
            .unwrap();
            v.extend([run.objective.to_bits(), run.rms.tire_deflection.to_bits()]);
            v
        };
        let paper = bits(Metrics::Paper);
        assert_eq!(paper, bits(Metrics::RoadHolding), "{:?}", config.road);
        assert_eq!(paper, bits(Metrics::Comfort), "{:?}", config.road);
    }
}

/// Split invariance and save/restore of the new accumulators: one
/// `advance_to` against many calls split anywhere (inside steps, on nodes,
/// a hair off nodes), and a simulator restored from its bytes midway.
#[test]
fn new_accumulators_do_not_depend_on_splits_or_restores() {
    let configs = [
        SimulationConfig {
            road: iso(RoadClass::H, 30.0),
            metrics: Metrics::Comfort,
            variant: Variant::Pvass,
            ..SimulationConfig::default()
        },
        SimulationConfig {
            params: Params::with_controller(2528.0, 1.28e-4),
            road: iso(RoadClass::G, 30.0),
            metrics: Metrics::Comfort,
            ..SimulationConfig::default()
        },
        SimulationConfig {
            params: Params::with_controller(40000.0, 3.7e-5),
            road: iso(RoadClass::H, 30.0),
            metrics: Metrics::Comfort,
            ..SimulationConfig::default()
        },
        SimulationConfig {
            metrics: Metrics::RoadHolding,
            ..SimulationConfig::default()
        },
    ];
    let values = |o: &Outputs| {
        let c = o.comfort.unwrap_or_default();
        let r = o.road_holding.unwrap();
        [
            c.weighted_body_acceleration,
            c.rms_weighted_body_acceleration,
            c.vibration_dose_value,
            r.contact_loss_time,
            r.max_suspension_deflection,
            r.first_contact_loss.map_or(-1.0, |f| f.time),
        ]
    };
    for config in configs {
        let end = 3.0;
        let mut whole = Simulator::new(config.clone()).unwrap();
        whole.advance_to(end).unwrap();
        let reference = values(&whole.outputs());
        if config.metrics == Metrics::Comfort {
            assert!(reference[1] > 0.0 && reference[2] > 0.0);
        }
        let mut split = Simulator::new(config.clone()).unwrap();
        let h = split.grid().step;
        let mut t = 0.0;
        let mut i = 0u64;
        while t < end {
            t = (t + h * [0.37, 1.0, 13.2, 0.999_999_999_9, 101.5][(i % 5) as usize]).min(end);
            split.advance_to(t).unwrap();
            if i == 2000 {
                // Midway: continue from a restored copy.
                split = Simulator::from_bytes(&split.to_bytes()).unwrap();
            }
            i += 1;
        }
        let got = values(&split.outputs());
        for (j, (a, b)) in got.iter().zip(&reference).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs(),
                "{:?}, value {j}: {a} against {b}",
                config.road
            );
        }
    }
}

/// A run summary carries the new metrics at the levels that keep them.
#[test]
fn run_summary_carries_the_metrics_of_its_level() {
    let config = |metrics| SimulationConfig {
        metrics,
        ..SimulationConfig::default()
    };
    let paper = simulate(config(Metrics::Paper), 1.0).unwrap();
    assert!(paper.comfort.is_none() && paper.road_holding.is_none());
    assert!(paper.rms_dynamic_tire_load_ratio > 0.0);
    let holding = simulate(config(Metrics::RoadHolding), 1.0).unwrap();
    assert!(holding.comfort.is_none());
    assert!(holding.road_holding.unwrap().max_suspension_deflection > 0.0);
    let comfort = simulate(config(Metrics::Comfort), 1.0).unwrap();
    assert!(comfort.comfort.unwrap().rms_weighted_body_acceleration > 0.0);
    assert_eq!(comfort.road_holding, holding.road_holding);
}
