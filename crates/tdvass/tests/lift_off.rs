//! The unilateral tire: against an independent fine-step integration of
//! the switched delay equation, unchanged where the wheel never lifts off,
//! the closed form of a free flight, independent of how a run is split or
//! saved, and bad or hard input.

mod common;

use common::{Lcg, harmonic, iso, rk4_unilateral};
use std::sync::Arc;
use tdvass::model::{Params, Plant, State, V_T, X_T};
use tdvass::road::{RoadClass, RoadSpec};
use tdvass::solver::{Metrics, SimulationConfig, Simulator};
use tdvass::{TireContact, Variant};

fn unilateral(variant: Variant, road: RoadSpec) -> SimulationConfig {
    SimulationConfig {
        variant,
        road,
        tire_contact: TireContact::Unilateral,
        metrics: Metrics::Comfort,
        ..SimulationConfig::default()
    }
}

/// A rough road as samples every 10 ms: a seeded random walk with the
/// displacement spread of an ISO 8608 class D road at 20 m/s (some 2 cm).
fn rough_samples(duration: f64, seed: u64) -> Arc<Vec<(f64, f64)>> {
    let mut random = Lcg(seed);
    let mut x = 0.0;
    let n = (duration / 0.01).round() as usize + 1;
    let samples = (0..=n)
        .map(|i| {
            let sample = (i as f64 * 0.01, x);
            x = 0.97 * x + 0.03 * (random.next_f64() - 0.5);
            sample
        })
        .collect();
    Arc::new(samples)
}

fn road_value(samples: &[(f64, f64)], t: f64) -> f64 {
    let i = samples
        .partition_point(|&(s, _)| s <= t)
        .clamp(1, samples.len() - 1);
    let ((t0, x0), (t1, x1)) = (samples[i - 1], samples[i]);
    x0 + (x1 - x0) * (t - t0) / (t1 - t0)
}

#[test]
fn unilateral_tdvass_agrees_with_a_fine_step_integration_of_the_switched_delay_equation() {
    let duration = 2.0;
    let samples = rough_samples(duration, 11);
    // tau = 2e-4 s lies inside the internal step, 0.02 s spans whole
    // steps; 2.6 ms puts the road breakpoints inside steps.
    for (g, tau) in [(5386.0, 2e-4), (20000.0, 0.02), (5386.0, 0.0026)] {
        let params = Params {
            g,
            tau,
            ..Params::default()
        };
        let plant = Plant::new(params, Variant::Tdvass).unwrap();
        let weight = params.static_load(Variant::Tdvass);
        type RoadFunction<'a> = Box<dyn Fn(f64) -> f64 + 'a>;
        let roads: [(RoadSpec, RoadFunction); 2] = [
            (
                harmonic(0.01, 70.0),
                Box::new(|t: f64| 0.01 * (70.0 * t).sin()),
            ),
            (
                RoadSpec::Samples(samples.clone()),
                Box::new(|t: f64| road_value(&samples, t)),
            ),
        ];
        for (road, road_fn) in roads {
            let label = format!("g {g}, tau {tau}, {}", road.kind());
            let reference = rk4_unilateral(&plant, tau, weight, road_fn, 1e-5, duration);
            let mut sim = Simulator::new(SimulationConfig {
                params,
                ..unilateral(Variant::Tdvass, road)
            })
            .unwrap();
            let summary = sim.run_for(duration).unwrap();
            let holding = summary.road_holding.unwrap();
            assert!(reference.lift_offs >= 3, "{label}: {reference:?}");
            assert_eq!(holding.lift_off_count, reference.lift_offs, "{label}");
            let rms = [
                summary.rms.body_acceleration,
                summary.rms.suspension_deflection,
                summary.rms.tire_deflection,
            ];
            for (i, (value, expected)) in rms.iter().zip(reference.rms).enumerate() {
                let error = (value - expected).abs() / expected;
                println!(
                    "{label}: RMS {i} off by {error:e}, {} lift-offs",
                    reference.lift_offs
                );
                assert!(error < 1e-6, "{label}: RMS {i} off by {error:e}");
            }
            let error = (holding.contact_loss_time - reference.flight_time).abs();
            println!("{label}: flight time off by {error:e} s");
            assert!(
                error < 1e-6 * duration,
                "{label}: flight time {} against {} s",
                holding.contact_loss_time,
                reference.flight_time
            );
        }
    }
}

#[test]
fn without_a_lift_off_the_unilateral_tire_changes_no_bit() {
    for ((variant, road), metrics) in [
        (Variant::Tdvass, RoadSpec::paper_harmonic()),
        (Variant::Pvass, iso(RoadClass::A, 20.0)),
        (Variant::Cs, iso(RoadClass::B, 10.0)),
    ]
    .into_iter()
    .zip([Metrics::Paper, Metrics::RoadHolding, Metrics::Comfort])
    {
        let with = |tire_contact| SimulationConfig {
            tire_contact,
            metrics,
            ..unilateral(variant, road.clone())
        };
        let mut a = Simulator::new(with(TireContact::Bilateral)).unwrap();
        let mut b = Simulator::new(with(TireContact::Unilateral)).unwrap();
        assert_eq!(a.grid(), b.grid());
        let mut t = 0.0;
        let mut random = Lcg(5);
        while t < 15.0 {
            t += 0.05 * random.next_f64();
            a.advance_to(t).unwrap();
            b.advance_to(t).unwrap();
            let (oa, ob) = (a.outputs(), b.outputs());
            assert_eq!(oa, ob, "{variant:?} at {t}");
            assert!(!b.in_flight());
        }
    }
}

#[test]
fn a_released_wheel_flies_the_closed_form_time_and_lands_at_its_take_off_speed() {
    // CS with no suspension forces: in flight the wheel falls at W/m_t
    // (the dynamic tire force is −W), so a wheel leaving the unloaded
    // height W/k_t at v0 upwards lands after 2 v0 m_t / W at −v0.
    let params = Params {
        k_s: 0.0,
        c_s: 0.0,
        ..Params::default()
    };
    let weight = params.static_load(Variant::Cs);
    let limit = weight / params.k_t;
    let v0 = 0.3;
    let mut initial = State::zeros();
    initial[X_T] = limit;
    initial[V_T] = v0;
    let config = SimulationConfig {
        params,
        road: harmonic(0.0, 1.0),
        initial_state: initial,
        tolerance: 1e-9,
        ..unilateral(Variant::Cs, harmonic(0.0, 1.0))
    };
    let flight = 2.0 * v0 * params.m_t / weight;
    let mut sim = Simulator::new(config).unwrap();
    // Just after the touchdown, before the next lift-off.
    sim.advance_to(flight * 1.01).unwrap();
    let outputs = sim.outputs();
    let holding = outputs.road_holding.unwrap();
    assert!(!sim.in_flight());
    assert_eq!(holding.lift_off_count, 1);
    assert!(
        (holding.contact_loss_time - flight).abs() < 1e-9,
        "flight {} s against {flight} s",
        holding.contact_loss_time
    );
    // Energy: the touchdown speed is the take-off speed (the first
    // contact's spring has acted only for 1 % of the flight since).
    let lift_off = holding.first_contact_loss.unwrap();
    assert!(
        lift_off.time.abs() < 1e-12,
        "lift-off at {} s",
        lift_off.time
    );
    let mut at_touchdown = Simulator::new(SimulationConfig {
        params,
        initial_state: initial,
        tolerance: 1e-9,
        ..unilateral(Variant::Cs, harmonic(0.0, 1.0))
    })
    .unwrap();
    at_touchdown.advance_to(flight).unwrap();
    let v = at_touchdown.state()[V_T];
    assert!(
        (v + v0).abs() < 1e-8,
        "touchdown speed {v} m/s against {}",
        -v0
    );
    // Elastic bounces, no damping: the contact is a half period of the
    // tire spring about its static point shifted by W/k_t; the wheel then
    // leaves again at v0, so each cycle repeats the first.
    sim.advance_to(1.0).unwrap();
    let cycle = flight
        + (std::f64::consts::PI + 2.0 * (limit * (params.k_t / params.m_t).sqrt() / v0).atan())
            / (params.k_t / params.m_t).sqrt();
    let expected = (1.0 / cycle).ceil() as u64;
    let count = sim.outputs().road_holding.unwrap().lift_off_count;
    assert!(
        count == expected || count + 1 == expected,
        "{count} lift-offs in 1 s, cycle {cycle} s"
    );
}

#[test]
fn unilateral_runs_do_not_depend_on_how_they_are_split_or_saved() {
    for (variant, metrics) in [
        (Variant::Cs, Metrics::Comfort),
        (Variant::Tdvass, Metrics::Paper),
    ] {
        let config = SimulationConfig {
            metrics,
            ..unilateral(variant, iso(RoadClass::D, 20.0))
        };
        let mut whole = Simulator::new(config.clone()).unwrap();
        whole.advance_to(3.0).unwrap();
        let expected = whole.outputs();

        let mut split = Simulator::new(config).unwrap();
        let mut random = Lcg(3);
        let mut t = 0.0;
        let mut saved_in_flight = false;
        while t < 3.0 {
            t = (t + 0.01 * random.next_f64()).min(3.0);
            split.advance_to(t).unwrap();
            if split.in_flight() && !saved_in_flight {
                // Through the byte form, in the middle of a flight.
                split = Simulator::from_bytes(&split.to_bytes()).unwrap();
                assert!(split.in_flight());
                saved_in_flight = true;
            }
        }
        assert!(saved_in_flight);
        assert_eq!(split.outputs(), expected, "{variant:?}");
    }
}

#[test]
fn hard_input_is_integrated_not_looped_on() {
    let stiff_tire = Params {
        k_t: 1e9,
        ..Params::default()
    };
    let mut airborne = State::zeros();
    airborne[X_T] = 0.1;
    let cases = [
        // W/k_t of 4 µm: the wheel lifts off at every ripple.
        (
            "tiny W/k_t",
            stiff_tire,
            harmonic(0.01, 70.0),
            State::zeros(),
        ),
        // A road frequency far above wheel hop.
        (
            "fast road",
            Params::default(),
            harmonic(0.05, 3000.0),
            State::zeros(),
        ),
        // A wheel 10 cm above the road at the start.
        (
            "airborne start",
            Params::default(),
            RoadSpec::paper_harmonic(),
            airborne,
        ),
    ];
    for (label, params, road, initial_state) in cases {
        let config = SimulationConfig {
            params,
            initial_state,
            ..unilateral(Variant::Tdvass, road)
        };
        // Each is integrated (the switch limit of one step is unit-tested
        // in `solver::contact`).
        let summary = Simulator::new(config)
            .and_then(|mut sim| sim.run_for(1.0))
            .unwrap_or_else(|e| panic!("{label}: {e}"));
        let holding = summary.road_holding.unwrap();
        println!("{label}: {} lift-offs", holding.lift_off_count);
        assert!(summary.objective.is_finite(), "{label}");
        assert!(holding.contact_loss_time.is_finite(), "{label}");
        assert!(holding.lift_off_count >= 1, "{label}");
        if label == "airborne start" {
            assert!(holding.first_contact_loss.unwrap().time < 1e-12);
        }
    }
}

#[test]
fn the_bilateral_lift_off_count_is_the_number_of_falls_below_minus_the_static_load() {
    let config = SimulationConfig {
        tire_contact: TireContact::Bilateral,
        ..unilateral(Variant::Pvass, iso(RoadClass::D, 20.0))
    };
    let mut sim = Simulator::new(config).unwrap();
    let weight = sim.static_load();
    // The load sampled every 10 µs (a crossing pair closer than that
    // would be missed; the cubic of the count sees it).
    let (mut falls, mut below) = (0, false);
    for i in 1..=300_000 {
        sim.advance_to(i as f64 * 1e-5).unwrap();
        let now = sim.outputs().dynamic_tire_load < -weight;
        falls += u64::from(now && !below);
        below = now;
    }
    let count = sim.outputs().road_holding.unwrap().lift_off_count;
    assert!(falls >= 5, "{falls}");
    assert_eq!(count, falls);
}
