//! A master that goes back gets the value it would have got without the
//! excursion, or an error naming both times; far times are refused or
//! finite, never a silent wrong value.

use super::*;

fn roads() -> Vec<RoadSpec> {
    vec![
        RoadSpec::paper_harmonic(),
        iso(RoadClass::C),
        RoadSpec::PaperCompatible {
            road: RandomRoad::default(),
            sample_interval: 1e-3,
        },
        RoadSpec::Input,
    ]
}

/// RK4 at 1 ms to `at`, an optional look-ahead RK4 step of `excursion` s
/// then back to `at` with the states it had there, and on to `until`.
fn run(
    c: &SimulationConfig,
    complete: bool,
    at: f64,
    excursion: Option<f64>,
    until: f64,
) -> Result<[f64; CONTINUOUS_STATES]> {
    let mut model = ModelExchange::new(c.clone()).unwrap();
    let h = 1e-3;
    order::explicit_rk4(&mut model, at, h, complete);
    if let Some(length) = excursion {
        let x = *model.states();
        order::explicit_rk4(&mut model, at + length, length, false);
        model.set_time(at)?;
        model.set_states(&x)?;
    }
    order::explicit_rk4(&mut model, until, h, complete);
    Ok(*model.states())
}

#[test]
fn a_look_ahead_and_back_gives_the_same_bits() {
    for road in roads() {
        for variant in [Variant::Tdvass, Variant::Pvass] {
            let c = config(variant, 0.011, 5386.0, road.clone());
            for complete in [false, true] {
                let plain = run(&c, complete, 0.4, None, 0.8).unwrap();
                for length in [0.15, 0.3, 0.2, 0.95] {
                    let back = run(&c, complete, 0.4, Some(length), 0.8).unwrap();
                    assert_eq!(back, plain, "{road:?} {variant:?} {complete} {length}");
                }
            }
        }
    }
}

#[test]
fn going_back_beyond_the_reach_is_refused_naming_both_times() {
    let c = config(Variant::Tdvass, 0.011, 5386.0, iso(RoadClass::C));
    let e = run(&c, false, 0.4, Some(1.5), 0.8).unwrap_err().to_string();
    assert!(
        e.contains("time 0.4 s is before 0.89") && e.contains("CompletedIntegratorStep"),
        "{e}"
    );
    let mut model = ModelExchange::new(c).unwrap();
    order::explicit_rk4(&mut model, 0.5, 1e-3, true);
    let e = model.set_time(0.45).unwrap_err().to_string();
    assert!(e.contains("time 0.45 s is before 0.5"), "{e}");
}

#[test]
fn far_times_are_refused_or_finite_and_hold_little_memory() {
    for road in roads() {
        for variant in Variant::ALL {
            let c = config(variant, 0.011, 5386.0, road.clone());
            for far in [1e5, 1e9, 1e308] {
                let mut model = ModelExchange::new(c.clone()).unwrap();
                if model.set_time(far).is_err() {
                    continue;
                }
                let rates = model.derivatives().unwrap();
                assert!(rates.iter().all(|r| r.is_finite()));
                assert!(model.event_indicators().unwrap()[0].is_finite());
                let kept = model.road.node_work(model.earliest_time(), far).1;
                assert!(kept <= 2.0 * crate::limits::MAX_WORK_PER_CALL);
            }
        }
    }
    // ISO 8608 at 1e5 s: 1e8 nodes, refused naming the work.
    let mut model =
        ModelExchange::new(config(Variant::Pvass, 0.011, 0.0, iso(RoadClass::D))).unwrap();
    let e = model.set_time(1e5).unwrap_err().to_string();
    assert!(e.contains("road nodes"), "{e}");
    let e = model.set_time(1e308).unwrap_err().to_string();
    assert!(e.contains("resolves"), "{e}");
}
