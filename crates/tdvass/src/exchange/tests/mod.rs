use super::*;
use crate::model::{Params, TireContact, Variant};
use crate::road::{RandomRoad, RoadClass, RoadSpec};
use crate::solver::Simulator;

/// Integrates `model` to `t_end` with the classical Runge–Kutta method at
/// step `h`, completing every step (or none) and handling the events at
/// step ends (located by bisection on the indicator to `1e-12` s).
fn integrate(model: &mut ModelExchange, t_end: f64, h: f64, complete: bool) -> Vec<f64> {
    let mut lift_offs = Vec::new();
    let rhs = |m: &mut ModelExchange, t: f64, x: &[f64]| {
        m.set_time(t).unwrap();
        m.set_states(x).unwrap();
        m.derivatives().unwrap()
    };
    let step = |m: &mut ModelExchange, t: f64, x: &[f64; CONTINUOUS_STATES], h: f64| {
        let k1 = rhs(m, t, x);
        let add = |a: &[f64; CONTINUOUS_STATES], k: &[f64; CONTINUOUS_STATES], c: f64| {
            std::array::from_fn::<f64, CONTINUOUS_STATES, _>(|i| a[i] + c * k[i])
        };
        let k2 = rhs(m, t + h / 2.0, &add(x, &k1, h / 2.0));
        let k3 = rhs(m, t + h / 2.0, &add(x, &k2, h / 2.0));
        let k4 = rhs(m, t + h, &add(x, &k3, h));
        std::array::from_fn::<f64, CONTINUOUS_STATES, _>(|i| {
            x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        })
    };
    let mut t = model.time();
    while t < t_end - 1e-12 {
        let x = *model.states();
        let before = model.event_indicators().unwrap()[0];
        let mut next = step(model, t, &x, h);
        model.set_time(t + h).unwrap();
        model.set_states(&next).unwrap();
        if model.event_indicators().unwrap()[0].signum() != before.signum() {
            let (mut low, mut high) = (0.0, h);
            while high - low > 1e-12 {
                let mid = 0.5 * (low + high);
                let y = step(model, t, &x, mid);
                model.set_time(t + mid).unwrap();
                model.set_states(&y).unwrap();
                if model.event_indicators().unwrap()[0].signum() != before.signum() {
                    high = mid;
                } else {
                    low = mid;
                }
            }
            next = step(model, t, &x, high);
            model.set_time(t + high).unwrap();
            model.set_states(&next).unwrap();
            if let Some(ContactEvent::LiftOff { time, .. }) = model.update_discrete_states() {
                lift_offs.push(time);
            }
            t += high;
            continue;
        }
        if complete {
            model.complete_step();
        }
        t += h;
    }
    lift_offs
}

/// ISO 8608 `class` at 20 m/s.
fn iso(class: RoadClass) -> RoadSpec {
    RoadSpec::Iso8608(RandomRoad {
        class,
        speed: 20.0,
        ..RandomRoad::default()
    })
}

fn config(variant: Variant, tau: f64, g: f64, road: RoadSpec) -> SimulationConfig {
    SimulationConfig {
        params: Params {
            tau,
            g,
            ..Params::default()
        },
        variant,
        road,
        metrics: Metrics::Comfort,
        ..SimulationConfig::default()
    }
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

fn agrees_with_the_co_simulation(config: SimulationConfig, duration: f64, h: f64, tolerance: f64) {
    let mut model = ModelExchange::new(config.clone()).unwrap();
    integrate(&mut model, config.start_time + duration, h, true);
    let mut sim = Simulator::new(config).unwrap();
    sim.advance_to(model.time()).unwrap();
    let (me, cs) = (model.outputs(), sim.outputs());
    let pairs = [
        (me.rms.body_acceleration, cs.rms.body_acceleration),
        (me.rms.suspension_deflection, cs.rms.suspension_deflection),
        (me.rms.tire_deflection, cs.rms.tire_deflection),
        (me.objective, cs.objective),
        (
            me.comfort.unwrap().rms_weighted_body_acceleration,
            cs.comfort.unwrap().rms_weighted_body_acceleration,
        ),
        (
            me.rms_dynamic_tire_load_ratio,
            cs.rms_dynamic_tire_load_ratio,
        ),
    ];
    for (i, (a, b)) in pairs.iter().enumerate() {
        assert!(relative(*a, *b) < tolerance, "output {i}: {a} vs {b}");
    }
}

#[test]
fn the_three_variants_agree_with_the_co_simulation() {
    for variant in Variant::ALL {
        agrees_with_the_co_simulation(
            config(variant, 0.011, 5386.0, RoadSpec::paper_harmonic()),
            2.0,
            1e-4,
            1e-7,
        );
    }
}

#[test]
fn a_delay_below_the_step_and_a_negative_gain_agree_with_the_co_simulation() {
    agrees_with_the_co_simulation(
        config(Variant::Tdvass, 2e-4, 5386.0, RoadSpec::paper_harmonic()),
        2.0,
        1e-3 / 3.0,
        1e-6,
    );
    agrees_with_the_co_simulation(
        config(Variant::Tdvass, 0.011, -2000.0, RoadSpec::paper_harmonic()),
        2.0,
        1e-4,
        1e-7,
    );
    agrees_with_the_co_simulation(
        config(Variant::Tdvass, 0.0, 5386.0, RoadSpec::paper_harmonic()),
        2.0,
        1e-4,
        1e-7,
    );
}

#[test]
fn a_random_road_agrees_with_the_co_simulation() {
    let road = iso(RoadClass::D);
    agrees_with_the_co_simulation(
        config(Variant::Tdvass, 0.011, 5386.0, road),
        1.0,
        5e-5,
        1e-6,
    );
}

#[test]
fn lift_offs_agree_with_the_located_switches_of_the_co_simulation() {
    let road = iso(RoadClass::D);
    let c = SimulationConfig {
        tire_contact: TireContact::Unilateral,
        ..config(Variant::Tdvass, 0.011, 5386.0, road)
    };
    let mut model = ModelExchange::new(c.clone()).unwrap();
    let lift_offs = integrate(&mut model, 3.0, 1e-4, true);
    let mut sim = Simulator::new(c).unwrap();
    sim.advance_to(model.time()).unwrap();
    let located: Vec<f64> = sim.lift_offs().events().iter().map(|e| e.time).collect();
    assert!(!located.is_empty());
    assert_eq!(lift_offs.len(), located.len(), "{lift_offs:?} {located:?}");
    for (a, b) in lift_offs.iter().zip(&located) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    assert_eq!(model.lift_off_count(), located.len() as u64);
}

#[test]
fn after_an_event_the_indicator_is_not_zero_and_has_the_modes_sign() {
    let c = SimulationConfig {
        tire_contact: TireContact::Unilateral,
        ..config(Variant::Cs, 0.0, 0.0, RoadSpec::paper_harmonic())
    };
    let mut model = ModelExchange::new(c).unwrap();
    let limit = model.switching.tire_limit;
    let mut x = *model.states();
    // Exactly at the margin's zero: in contact, still positive.
    x[X_T] = limit;
    model.set_states(&x).unwrap();
    assert!(model.event_indicators().unwrap()[0] > 0.0);
    x[X_T] = limit * (1.0 + 1e-9);
    model.set_states(&x).unwrap();
    assert!(matches!(
        model.update_discrete_states(),
        Some(ContactEvent::LiftOff { .. })
    ));
    assert!(model.event_indicators().unwrap()[0] < 0.0);
    assert!(!model.in_contact());
}

#[test]
fn a_saved_state_replays_exactly() {
    let c = config(Variant::Tdvass, 0.011, 5386.0, RoadSpec::paper_harmonic());
    let mut model = ModelExchange::new(c.clone()).unwrap();
    integrate(&mut model, 0.3, 1e-4, false);
    let bytes = model.to_bytes();
    let mut copy = ModelExchange::new(c).unwrap();
    copy.restore(&bytes).unwrap();
    integrate(&mut model, 0.6, 1e-4, false);
    integrate(&mut copy, 0.6, 1e-4, false);
    assert_eq!(model.states(), copy.states());
    let mut broken = bytes.clone();
    broken[4] = 9;
    assert!(
        copy.restore(&broken)
            .unwrap_err()
            .to_string()
            .contains("version")
    );
    assert!(copy.restore(&bytes[..bytes.len() - 3]).is_err());
}

#[test]
fn a_saved_state_on_a_random_road_replays_exactly_from_its_nodes() {
    let road = iso(RoadClass::D);
    let c = config(Variant::Tdvass, 0.011, 5386.0, road);
    let mut model = ModelExchange::new(c.clone()).unwrap();
    integrate(&mut model, 0.5, 1e-4, true);
    let bytes = model.to_bytes();
    let saved = model.road.node_state().unwrap();
    let road_bytes = 1 + 16 + 8 + 8 + 8 * saved.nodes.len();
    // Only the nodes from the last completed step on are kept and saved.
    assert!(saved.nodes.len() < 200, "{} nodes", saved.nodes.len());
    assert!(saved.first_node > 300, "first node {}", saved.first_node);
    let mut copy = ModelExchange::new(c).unwrap();
    copy.restore(&bytes).unwrap();
    assert_eq!(copy.road.node_state(), Some(saved));
    integrate(&mut model, 1.0, 1e-4, true);
    integrate(&mut copy, 1.0, 1e-4, true);
    assert_eq!(model.states(), copy.states());
    // Without the road's nodes the state is refused.
    // The road's bytes, then the count of the inputs that prescribe
    // coordinates and the body tag (0: no corner).
    let without = [&bytes[..bytes.len() - road_bytes - 2], &[0u8, 1, 0][..]].concat();
    let refused = copy.restore(&without).unwrap_err().to_string();
    assert!(refused.contains("without its nodes"), "{refused}");
}

#[test]
fn a_saved_state_on_a_random_road_replays_when_no_step_was_completed() {
    // The nodes of the start are released as the derivatives move on:
    // the restored model takes the window it was saved with.
    let road = iso(RoadClass::C);
    let c = config(Variant::Tdvass, 0.011, 5386.0, road);
    let mut model = ModelExchange::new(c.clone()).unwrap();
    integrate(&mut model, 1.5, 1e-4, false);
    assert!(model.road.node_state().unwrap().first_node > 300);
    let mut copy = ModelExchange::new(c).unwrap();
    copy.restore(&model.to_bytes()).unwrap();
    integrate(&mut model, 2.0, 1e-4, false);
    integrate(&mut copy, 2.0, 1e-4, false);
    assert_eq!(model.states(), copy.states());
}

#[test]
fn bad_states_and_times_are_refused_naming_them() {
    let c = config(Variant::Tdvass, 0.011, 5386.0, RoadSpec::paper_harmonic());
    let mut model = ModelExchange::new(c).unwrap();
    let mut x = *model.states();
    x[9] = f64::NAN;
    let e = model.set_states(&x).unwrap_err().to_string();
    assert!(e.contains("wk_filter_4"), "{e}");
    assert!(
        model
            .set_states(&x[..5])
            .unwrap_err()
            .to_string()
            .contains("5 continuous states")
    );
    model.set_time(0.5).unwrap();
    model.complete_step();
    assert!(
        model
            .set_time(0.4)
            .unwrap_err()
            .to_string()
            .contains("before")
    );
    assert!(model.set_time(f64::NAN).is_err());
}

mod going_back;
mod jacobian;
mod order;

/// The state of `model` in format version 1 (before the floor and the
/// completion habits, the count of switching elements and the body
/// attachment), rewritten from its current bytes.
fn version_1_bytes(model: &ModelExchange) -> Vec<u8> {
    use crate::bytes::{ByteReader, ByteWriter};
    let bytes = model.to_bytes();
    let mut r = ByteReader::new(&bytes);
    let mut w = ByteWriter::default();
    w.u32(r.u32().unwrap());
    assert_eq!(r.u32().unwrap(), EXCHANGE_FORMAT_VERSION);
    w.u32(1);
    w.f64(r.f64().unwrap());
    w.f64(r.f64().unwrap());
    // Version 2's floor, latest time and habits.
    r.f64().unwrap();
    r.f64().unwrap();
    r.u8().unwrap();
    r.u8().unwrap();
    w.f64s(&r.f64s(CONTINUOUS_STATES as u64).unwrap());
    // Version 3's count of switching elements (the tire's alone before).
    assert_eq!(r.u8().unwrap(), 1);
    w.u8(r.u8().unwrap());
    w.f64(r.f64().unwrap());
    w.u64(r.u64().unwrap());
    w.f64(r.f64().unwrap());
    let loss = r.u8().unwrap();
    w.u8(loss);
    if loss != 0 {
        w.f64(r.f64().unwrap());
        w.f64(r.f64().unwrap());
    }
    let count = r.u64().unwrap();
    w.u64(count);
    for _ in 0..count {
        for _ in 0..3 {
            w.f64(r.f64().unwrap());
        }
        w.u8(r.u8().unwrap() & 1);
        r.f64().unwrap();
    }
    // Without the count of the inputs that prescribe coordinates (version
    // 4) and the body tag (0: no corner) of version 3.
    let rest = r.rest();
    w.raw(&rest[..rest.len() - 2]);
    w.bytes
}

#[test]
fn a_state_of_format_version_1_still_loads() {
    let road = iso(RoadClass::C);
    let c = config(Variant::Tdvass, 0.011, 5386.0, road);
    let mut model = ModelExchange::new(c.clone()).unwrap();
    integrate(&mut model, 0.3, 1e-4, true);
    let mut copy = ModelExchange::new(c).unwrap();
    copy.restore(&version_1_bytes(&model)).unwrap();
    assert_eq!(copy.states(), model.states());
    assert_eq!(copy.accepted_time(), model.accepted_time());
    assert!(copy.earliest_time() >= copy.accepted_time());
    integrate(&mut model, 0.5, 1e-4, true);
    integrate(&mut copy, 0.5, 1e-4, true);
    // Version 1 kept no habits: the first completion after the restore
    // keeps the stages of the step before it, so the runs differ a little.
    for (a, b) in model.states().iter().zip(copy.states()) {
        assert!((a - b).abs() <= 1e-9 * a.abs().max(1e-6), "{a} {b}");
    }
}

/// Both engines' right-hand side of a mode is one function of the same
/// matrices: at random states, delayed inputs and road inputs, in both
/// tire modes, for every variant and delay regime (folded, resolved, none),
/// Model Exchange's equals the co-simulation's to the bit.
#[test]
fn both_engines_evaluate_the_same_right_hand_side() {
    use crate::model::dynamics::Mode;
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    for variant in Variant::ALL {
        for tau in [0.0, 1e-8, 2e-4, 0.011] {
            let c = SimulationConfig {
                tire_contact: TireContact::Unilateral,
                ..config(variant, tau, 5386.0, RoadSpec::paper_harmonic())
            };
            let model = ModelExchange::new(c.clone()).unwrap();
            let mut sim = Simulator::new(c).unwrap();
            sim.reserve();
            for _ in 0..50 {
                let x = State::from_fn(|_, _| rng.random_range(-0.1..0.1));
                let (u, r) = (rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
                for mode in Mode::all() {
                    let me = model.mode_rates(mode, &x, u, r);
                    let cs = sim.mode_rates(mode, &x, u, r);
                    assert_eq!(me, cs, "{variant:?} tau {tau} mode {mode:?}");
                }
            }
        }
    }
}

#[test]
fn a_state_with_more_switching_elements_than_the_model_has_is_refused() {
    let c = config(Variant::Tdvass, 0.011, 5386.0, iso(RoadClass::C));
    let mut model = ModelExchange::new(c).unwrap();
    integrate(&mut model, 0.05, 1e-4, true);
    let mut bytes = model.to_bytes();
    // Magic, version, four times, two flags, the states' count and values.
    let at = 4 + 4 + 4 * 8 + 2 + 8 + 8 * CONTINUOUS_STATES;
    assert_eq!(
        usize::from(bytes[at]),
        crate::model::dynamics::SWITCHES.len()
    );
    bytes[at] += 1;
    let e = model.restore(&bytes).unwrap_err().to_string();
    assert!(e.contains("switching elements"), "{e}");
}

#[test]
fn a_corner_s_state_of_format_version_3_still_loads_and_a_wrong_count_is_refused() {
    use crate::model::Body;
    use crate::model::inputs::{BODY_ATTACHMENT, PRESCRIBED};
    let c = SimulationConfig {
        body: Body::Attached,
        ..config(Variant::Tdvass, 0.011, 5386.0, RoadSpec::paper_harmonic())
    };
    let mut model = ModelExchange::new(c.clone()).unwrap();
    model.set_body_input(0.004, -0.03).unwrap();
    integrate(&mut model, 0.3, 1e-4, true);
    let bytes = model.to_bytes();
    // Version 4 ends with the count, then the body's tag and values.
    let tail = bytes.len() - 1 - 1 - 16;
    assert_eq!(usize::from(bytes[tail]), PRESCRIBED.len());
    let mut version_3 = [&bytes[..tail], &bytes[tail + 1..]].concat();
    version_3[4..8].copy_from_slice(&3u32.to_le_bytes());
    let mut copy = ModelExchange::new(c.clone()).unwrap();
    copy.restore(&version_3).unwrap();
    assert_eq!(copy.states(), model.states());
    assert_eq!(copy.prescribed(BODY_ATTACHMENT), Some([0.004, -0.03]));
    assert_eq!(copy.to_bytes(), bytes);
    // More inputs than this build knows: refused by name.
    let mut more = bytes.clone();
    more[tail] = PRESCRIBED.len() as u8 + 1;
    let e = copy.restore(&more).unwrap_err().to_string();
    assert!(e.contains("inputs that prescribe coordinates"), "{e}");
    // A quarter car's state (no attachment) into a corner: refused.
    let quarter = ModelExchange::new(config(
        Variant::Tdvass,
        0.011,
        5386.0,
        RoadSpec::paper_harmonic(),
    ))
    .unwrap();
    let e = copy.restore(&quarter.to_bytes()).unwrap_err().to_string();
    assert!(e.contains("the body attachment"), "{e}");
}
