use super::*;
use crate::model::Performance;
use crate::model::TireContact;
use crate::model::{Params, State, Variant};
use crate::road::RandomRoad;
use crate::road::RoadSpec;
use crate::solver::stepping::stepping;

fn bits(sim: &mut Simulator) -> Vec<u64> {
    let o = sim.outputs();
    let mut v = o.core_values().to_vec();
    v.push(o.time);
    v.extend(sim.trajectory.committed_state.iter().copied());
    v.extend(sim.observers.rms.sums_of_squares);
    v.push(sim.observers.rms.samples as f64);
    v.into_iter().map(f64::to_bits).collect()
}

fn configs() -> Vec<SimulationConfig> {
    let base = SimulationConfig::default();
    vec![
        base.clone(),
        SimulationConfig {
            variant: Variant::Pvass,
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(40000.0, 0.03),
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(2528.0, 1.28e-4),
            road: RoadSpec::Iso8608(RandomRoad::default()),
            ..base.clone()
        },
        SimulationConfig {
            road: RoadSpec::PaperCompatible {
                road: RandomRoad::default(),
                sample_interval: 0.1,
            },
            ..base.clone()
        },
        // Delays inside one step, on the harmonic and a linear road.
        SimulationConfig {
            params: Params::with_controller(40000.0, 3.7e-5),
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
            ..base.clone()
        },
        SimulationConfig {
            params: Params::with_controller(6000.0, 2e-6),
            road: RoadSpec::Iso8608(RandomRoad::default()),
            ..base
        },
    ]
}

#[test]
fn any_split_gives_bit_identical_results() {
    // Splits that cut the whole-step loop at phase anchors, before the
    // history starts, in the middle of anchor segments, and step by step.
    for cfg in configs() {
        let stops: Vec<f64> = (1..=40).map(|i| i as f64 * 0.0517).collect();
        let mut reference = Vec::new();
        let mut sim = Simulator::new(cfg.clone()).unwrap();
        for &t in &stops {
            sim.advance_to(t).unwrap();
            reference.push(bits(&mut sim));
        }
        let mut one_by_one = Simulator::new(cfg.clone()).unwrap();
        let h = one_by_one.grid().step;
        let mut i = 0;
        for (stop, expected) in stops.iter().zip(&reference) {
            loop {
                let t = (i + 1) as f64 * h * 0.73;
                if t >= *stop {
                    break;
                }
                one_by_one.advance_to(t).unwrap();
                i += 1;
            }
            one_by_one.advance_to(*stop).unwrap();
            assert_eq!(&bits(&mut one_by_one), expected, "{:?}", cfg.road);
        }
        let mut cut = Simulator::new(cfg.clone()).unwrap();
        for t in [h * 1023.0, h * 1024.0, h * 1025.5, h * 3000.0] {
            if t < stops[39] {
                cut.advance_to(t).unwrap();
            }
        }
        cut.advance_to(stops[39]).unwrap();
        assert_eq!(&bits(&mut cut), reference.last().unwrap());
    }
}

#[test]
fn restored_simulator_continues_bit_identically_inside_a_segment() {
    for cfg in configs() {
        let mut sim = Simulator::new(cfg).unwrap();
        let h = sim.grid().step;
        // Node 1500 lies inside the second phase-anchor segment.
        sim.advance_to(1500.3 * h).unwrap();
        let mut restored = Simulator::from_bytes(&sim.to_bytes()).unwrap();
        for t in [2047.0 * h, 2048.0 * h, 5000.5 * h, 5000.5 * h + 0.9] {
            sim.advance_to(t).unwrap();
            restored.advance_to(t).unwrap();
            assert_eq!(bits(&mut sim), bits(&mut restored));
        }
    }
}

#[test]
fn whole_steps_match_the_general_step_closely() {
    // The whole-step loop (node form of the delayed input, rotated road
    // phase) against one general step per node (Hermite form, sin/cos).
    // With the W_k filter, its state and a_w integrals too (the filter's
    // grid step against its general step), also with the delay inside
    // the step.
    let displaced = SimulationConfig {
        params: Params::with_controller(40000.0, 0.03),
        initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
        ..SimulationConfig::default()
    };
    let inner = SimulationConfig {
        params: Params::with_controller(40000.0, 3.7e-5),
        initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
        ..SimulationConfig::default()
    };
    for (cfg, comfort) in [(displaced.clone(), false), (displaced, true), (inner, true)] {
        let metrics = if comfort {
            Metrics::Comfort
        } else {
            Metrics::RoadHolding
        };
        let cfg = SimulationConfig { metrics, ..cfg }.at_fixed_step();
        let mut fast = Simulator::new(cfg.clone()).unwrap();
        let mut general = Simulator::new(cfg).unwrap();
        for k in 0..3000u64 {
            let to = general.grid_time(k + 1);
            let from = (
                general.trajectory.committed_time,
                general.trajectory.committed_state,
            );
            let x = stepping!(general).integrate_within_step(k, from.0, from.1, to);
            let w_from = general.trajectory.committed_filter;
            let w = stepping!(general).filter_within_step(k, from, &w_from, to);
            let anchor = general.observers.integral.anchor;
            let mut holding = general.observers.holding;
            let (step_integral, at_end, piece) = stepping!(general).integral_within_step(
                k,
                from,
                &w_from,
                anchor,
                to,
                (&x, &w),
                &mut holding,
            );
            general.observers.holding = holding;
            general.commit_node(k + 1, (to, x, w), step_integral, (at_end, piece));
        }
        fast.advance_to(general.trajectory.committed_time).unwrap();
        let scale = general.trajectory.committed_state.amax();
        let difference =
            (fast.trajectory.committed_state - general.trajectory.committed_state).amax();
        assert!(difference < 1e-12 * scale, "{difference:e} of {scale:e}");
        let (a, b) = (fast.rms(), general.rms());
        assert!((a.body_acceleration - b.body_acceleration).abs() < 1e-12 * b.body_acceleration);
        assert!((a.tire_deflection - b.tire_deflection).abs() < 1e-12 * b.tire_deflection);
        let (a, b) = (fast.outputs(), general.outputs());
        let (u, v) = (
            a.road_holding.unwrap().max_suspension_deflection,
            b.road_holding.unwrap().max_suspension_deflection,
        );
        assert!((u - v).abs() < 1e-12 * v, "{u} {v}");
        if comfort {
            let filter_scale = general.trajectory.committed_filter.amax();
            assert!(filter_scale > 0.0);
            let difference =
                (fast.trajectory.committed_filter - general.trajectory.committed_filter).amax();
            assert!(difference < 1e-12 * filter_scale, "{difference:e}");
            let (a, b) = (a.comfort.unwrap(), b.comfort.unwrap());
            let (u, v) = (
                a.rms_weighted_body_acceleration,
                b.rms_weighted_body_acceleration,
            );
            assert!((u - v).abs() < 1e-12 * v, "{u} {v}");
            let (u, v) = (a.vibration_dose_value, b.vibration_dose_value);
            assert!((u - v).abs() < 1e-12 * v, "{u} {v}");
        } else {
            assert_eq!(a.comfort, None);
        }
    }
}

#[test]
fn cheap_readers_agree_with_the_outputs_to_the_bit() {
    // A harmonic road that takes the tire off the road, read at points on
    // and between the nodes: the time averages alone, the instantaneous
    // outputs alone and the contact-loss test (decided without a sine
    // where it can) give what the outputs give; with the unilateral tire
    // also in flight.
    // The amplitudes put the first loss at different points, or nowhere.
    let steps = [1e-3, 7e-4, 9.9e-5, 1.3e-3, 1e-7, 1.9e-3, 2.3e-4];
    let mut losses = 0;
    let bilateral = TireContact::Bilateral;
    for (tau, metrics, amplitude, tire_contact) in [
        (2e-4, Metrics::Comfort, 0.05, bilateral),
        (2e-4, Metrics::RoadHolding, 0.03, bilateral),
        (2e-4, Metrics::RoadHolding, 0.022, bilateral),
        (2e-4, Metrics::RoadHolding, 0.01, bilateral),
        (0.0, Metrics::RoadHolding, 0.04, bilateral),
        (0.03, Metrics::Comfort, 0.025, bilateral),
        (0.03, Metrics::Comfort, 0.05, TireContact::Unilateral),
        (2e-4, Metrics::Paper, 0.05, TireContact::Unilateral),
    ] {
        let cfg = SimulationConfig {
            params: Params::with_controller(5386.0, tau),
            road: RoadSpec::Harmonic {
                amplitude,
                angular_frequency: 40.0,
            },
            metrics,
            tire_contact,
            ..SimulationConfig::default()
        };
        let mut sim = Simulator::new(cfg).unwrap();
        let mut t = 0.0;
        for i in 0..2000 {
            t += steps[i % steps.len()];
            sim.advance_to(t).unwrap();
            let averages = sim.time_averages();
            // Each reader in turn sees the state before it is computed.
            let (instant, loss) = if i % 2 == 0 {
                let instant = sim.instantaneous();
                (instant, sim.first_contact_loss())
            } else {
                let loss = sim.first_contact_loss();
                (sim.instantaneous(), loss)
            };
            let o = sim.outputs();
            let now = |time, state: State, p: Performance, road, force, load| {
                let mut bits = vec![time, p.body_acceleration, p.suspension_deflection];
                bits.extend([p.tire_deflection, road, force, load]);
                bits.extend(state.iter());
                bits.iter().map(|v: &f64| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(
                now(
                    instant.time,
                    instant.state,
                    instant.performance,
                    instant.road_displacement,
                    instant.control_force,
                    instant.dynamic_tire_load
                ),
                now(
                    o.time,
                    o.state,
                    o.performance,
                    o.road_displacement,
                    o.control_force,
                    o.dynamic_tire_load
                ),
                "t = {t}"
            );
            assert_eq!(
                average_bits(&averages),
                average_bits(&o.time_averages()),
                "t = {t}"
            );
            if tire_contact.is_unilateral() {
                // The contact-loss test is the bilateral tire's (the FMU
                // asks it only then).
                continue;
            }
            let holding = o.road_holding.unwrap();
            assert_eq!(loss, holding.first_contact_loss, "t = {t}");
            if i == 1999 {
                losses += usize::from(loss.is_some());
            }
        }
    }
    assert!((1..6).contains(&losses), "{losses} of 6 runs lose contact");
}

/// The bits of the time averages: the three RMS values, J and the RMS
/// tire-load ratio.
fn average_bits(a: &TimeAverages) -> [u64; 5] {
    [
        a.rms.body_acceleration,
        a.rms.suspension_deflection,
        a.rms.tire_deflection,
        a.objective,
        a.rms_dynamic_tire_load_ratio,
    ]
    .map(f64::to_bits)
}

#[test]
fn time_averages_alone_agree_with_the_outputs_on_piecewise_linear_roads() {
    // Inside steps the time averages alone integrate from the committed
    // point without the W_k filter, here with the squares of linear road
    // pieces, and in the last case across their breakpoints.
    let steps = [7e-4, 9.9e-5, 1.3e-3, 1e-7, 2.3e-4, 1e-3];
    let mut inside = 0;
    // A delay longer than the step makes the grid tau/m: the ISO road's
    // breakpoints then fall inside steps.
    let long_delay = SimulationConfig {
        params: Params::with_controller(2528.0, 0.0026),
        road: RoadSpec::Iso8608(RandomRoad::default()),
        ..SimulationConfig::default()
    };
    for cfg in configs().into_iter().chain([long_delay]) {
        if matches!(cfg.road, RoadSpec::Harmonic { .. }) {
            continue;
        }
        for metrics in [Metrics::Comfort, Metrics::Paper] {
            let mut sim = Simulator::new(SimulationConfig {
                metrics,
                ..cfg.clone()
            })
            .unwrap();
            let mut t = 0.0;
            for i in 0..600 {
                t += steps[i % steps.len()];
                sim.advance_to(t).unwrap();
                inside += usize::from(!sim.snaps(t, sim.trajectory.committed_time));
                let averages = sim.time_averages();
                let o = sim.outputs();
                assert_eq!(
                    average_bits(&averages),
                    average_bits(&o.time_averages()),
                    "t = {t}"
                );
            }
        }
    }
    assert!(inside > 1000, "{inside} points inside steps");
}

#[test]
fn a_road_input_is_no_breakpoint_at_every_node() {
    // The input's piece never ends: the whole steps it covers form one RMS
    // run (a breakpoint closes the run at its node).
    let mut sim = Simulator::new(SimulationConfig {
        road: RoadSpec::Input,
        ..SimulationConfig::default()
    })
    .unwrap();
    sim.set_road_input(0.01, 0.2).unwrap();
    let h = sim.grid.step;
    assert!(!sim.coincide(f64::INFINITY, 10.0 * h));
    assert!(sim.coincide(f64::INFINITY, f64::INFINITY));
    sim.advance_to(10.0 * h).unwrap();
    assert_eq!(sim.trajectory.grid_index, 10);
    assert!(
        sim.observers.rms.samples >= 10,
        "{} nodes in the open run",
        sim.observers.rms.samples
    );
}
