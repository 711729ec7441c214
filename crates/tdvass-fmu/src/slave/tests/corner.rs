//! The corner model ([`Model::Corner`]): its variables, its body inputs
//! and force, and the quarter car as a corner under a point mass driven by
//! a master's loop.

use super::*;
use crate::variables::{by_vr, guid, variables_of};

/// A corner slave speaking [`TEST_DIALECT`], at its start values.
fn corner() -> Slave {
    let logger = Logger::new(Box::new(|_, _, _| {}), false);
    Slave::new(TEST_DIALECT, Model::Corner, guid(Model::Corner), logger)
}

fn corner_vr(name: &str) -> u32 {
    by_name(Model::Corner, FmiVersion::Fmi2, name)
        .unwrap_or_else(|| panic!("the corner has no `{name}`"))
        .vr
}

fn corner_get(s: &mut Slave, name: &str) -> f64 {
    let mut v = [0.0];
    s.get_real(&[corner_vr(name)], &mut v).unwrap();
    v[0]
}

/// A corner initialized at t = 0 with the Real settings `set`.
fn started_corner(set: &[(&str, f64)]) -> Slave {
    let mut s = corner();
    s.setup_experiment(None, 0.0, None).unwrap();
    for (name, value) in set {
        s.set_real(&[corner_vr(name)], &[*value]).unwrap();
    }
    start(&mut s);
    s
}

#[test]
fn the_corner_has_the_suspension_and_the_body_attachment_not_the_body() {
    for version in [FmiVersion::Fmi2, FmiVersion::Fmi3] {
        let names: Vec<&str> = variables_of(Model::Corner, version)
            .iter()
            .map(|v| v.name)
            .collect();
        for present in [
            "variant",
            "k_s",
            "g",
            "tau",
            "static_load",
            "road_delay",
            "road_phase",
            "body_displacement",
            "body_velocity",
            "x_g",
            "body_force",
            "suspension_deflection",
            "rms_dynamic_tire_load_ratio",
            "lift_off_count",
        ] {
            assert!(names.contains(&present), "{version:?} lacks {present}");
        }
        for absent in ["m_s", "x_s", "body_acceleration", "objective", "w_ba"] {
            assert!(!names.contains(&absent), "{version:?} has {absent}");
        }
        // Model Exchange's locals: the integrals of SDD^2 and TDD^2, the
        // derivatives of the 7 states, the event indicator.
        let locals: Vec<&str> = variables_of(Model::Corner, version)
            .iter()
            .filter(|v| v.causality == Causality::Local)
            .map(|v| v.name)
            .collect();
        assert_eq!(locals.len(), 2 + 7 + 1, "{locals:?}");
        assert!(!locals.contains(&"der(x_s)") && !locals.contains(&"wk_filter_1"));
        let mut vrs: Vec<u32> = variables_of(Model::Corner, version)
            .iter()
            .map(|v| v.vr)
            .collect();
        vrs.sort_unstable();
        vrs.dedup();
        assert_eq!(
            vrs.len(),
            names.len(),
            "{version:?}: value references unique"
        );
    }
    let force = by_name(Model::Corner, FmiVersion::Fmi2, "body_force").unwrap();
    assert_eq!(force.feedthrough, ["body_displacement", "body_velocity"]);
    assert_ne!(guid(Model::Corner), guid(Model::QuarterCar));
    // The quarter car's interface, and so its GUID, is what it was.
    assert_eq!(
        guid(Model::QuarterCar),
        "{40312ba9-eb4d-4d03-8758-3a880f72b572}"
    );
}

#[test]
fn the_body_force_is_the_suspension_on_the_displaced_body() {
    // From rest with the body's attachment 1 cm up and moving at 0.1 m/s:
    // the spring and damper pull it down, k_s z + c_s v (absorber and
    // wheel at rest); the static load does not count (zero at equilibrium).
    for variant in [1, 3] {
        let mut s = corner();
        s.set_integer(&[corner_vr("variant")], &[variant]).unwrap();
        s.set_real(
            &[corner_vr("body_displacement"), corner_vr("body_velocity")],
            &[0.01, 0.1],
        )
        .unwrap();
        s.setup_experiment(None, 0.0, None).unwrap();
        start(&mut s);
        let p = s.settings().params;
        let expected = -(p.k_s * 0.01 + p.c_s * 0.1);
        let force = corner_get(&mut s, "body_force");
        assert!(
            (force - expected).abs() <= 1e-12 * expected.abs(),
            "variant {variant}: {force} vs {expected}"
        );
        assert_eq!(corner_get(&mut s, "suspension_deflection"), 0.01);
    }
    let mut s = started_corner(&[]);
    assert_eq!(corner_get(&mut s, "body_force"), 0.0);
}

#[test]
fn the_static_load_sets_the_tire_load_ratio() {
    // The tire's static load W = static_load + (m_h + m_t) g0 divides the
    // RMS dynamic tire load k_t RMS(TDD).
    let ratio = |load: f64| {
        let mut s = started_corner(&[("static_load", load)]);
        s.do_step(0.0, 1.0).unwrap();
        let tdd = corner_get(&mut s, "rms_tire_deflection");
        let p = s.settings().params;
        (corner_get(&mut s, "rms_dynamic_tire_load_ratio"), tdd, p)
    };
    let g0 = tdvass::model::STANDARD_GRAVITY;
    for load in [3383.29, 5000.0] {
        let (ratio, tdd, p) = ratio(load);
        let w = load + (p.m_h + p.m_t) * g0;
        assert!(
            (ratio - p.k_t * tdd / w).abs() <= 1e-12 * ratio,
            "{load}: {ratio} vs {}",
            p.k_t * tdd / w
        );
    }
}

#[test]
fn bad_body_inputs_are_refused() {
    let mut s = started_corner(&[]);
    for (name, bad) in [
        ("body_displacement", f64::NAN),
        ("body_velocity", f64::INFINITY),
        ("body_displacement", 1e9),
    ] {
        let message = refusal(s.set_real(&[corner_vr(name)], &[bad]));
        assert!(message.contains(name), "{message}");
    }
    // A body input's derivative is ignored (the attachment moves at
    // body_velocity), and is not taken for the road's.
    let status = s
        .set_real_input_derivatives(&[corner_vr("body_displacement")], &[1], &[0.5])
        .unwrap();
    assert_eq!(status, Status::Warning);
    assert_eq!(s.state.input_slope, 0.0);
    let message = refusal(s.set_real(&[corner_vr("static_load")], &[-1.0]));
    assert!(message.contains("static_load"), "{message}");
    // The quarter car's body variables are no variables of the corner.
    let m_s = by_name(Model::QuarterCar, FmiVersion::Fmi2, "m_s")
        .unwrap()
        .vr;
    assert!(by_vr(Model::Corner, FmiVersion::Fmi2, m_s).is_none());
    assert!(refusal(s.set_real(&[m_s], &[300.0])).contains("unknown value reference"));
}

#[test]
fn a_corner_state_restores_and_continues_to_the_bit() {
    let mut s = started_corner(&[("road_delay", 0.05), ("road_phase", 0.3)]);
    let (z, v) = (corner_vr("body_displacement"), corner_vr("body_velocity"));
    s.set_real(&[z, v], &[0.002, -0.01]).unwrap();
    s.do_step(0.0, 0.1).unwrap();
    let saved = s.get_fmu_state(None).unwrap();
    let bytes = s.serialize_fmu_state(saved).unwrap();
    let run = |s: &mut Slave| {
        s.set_real(&[z, v], &[0.001, 0.02]).unwrap();
        s.do_step(0.1, 0.05).unwrap();
        [
            corner_get(s, "body_force"),
            corner_get(s, "rms_suspension_deflection"),
            corner_get(s, "x_t"),
        ]
    };
    let first = run(&mut s);
    s.set_fmu_state(saved).unwrap();
    assert_eq!(run(&mut s), first);
    let mut other = corner();
    let restored = other.deserialize_fmu_state(&bytes, None).unwrap();
    other.set_fmu_state(restored).unwrap();
    assert_eq!(run(&mut other), first);
    // A quarter car's slave does not take a corner's state.
    let (mut quarter_car, _) = new_slave(false);
    let message = refusal(quarter_car.deserialize_fmu_state(&bytes, None));
    assert!(message.contains("GUID"), "{message}");
}

/// The quarter car is the corner under a body that is a point mass m_s
/// driven by the corner's force: a master's explicit loop (the body by the
/// semi-implicit Euler rule, the corner by its exact integration with the
/// attachment moving at the body's velocity over each step) comes to the
/// quarter car's RMS values as the step shrinks, at least linearly.
#[test]
fn the_quarter_car_is_a_corner_under_a_point_mass() {
    let mut quarter_car = initialized().0;
    quarter_car.do_step(0.0, 2.0).unwrap();
    let names = [
        "rms_suspension_deflection",
        "rms_tire_deflection",
        "rms_dynamic_tire_load_ratio",
    ];
    let reference: Vec<f64> = names.iter().map(|n| get(&mut quarter_car, n)).collect();
    let error_at = |h: f64| {
        let mut s = started_corner(&[]);
        let m_s = s.settings().params().m_s;
        let (z_vr, v_vr) = (corner_vr("body_displacement"), corner_vr("body_velocity"));
        let (mut z, mut v) = (0.0, 0.0);
        let steps = (2.0 / h).round() as usize;
        for k in 0..steps {
            s.set_real(&[z_vr, v_vr], &[z, v]).unwrap();
            let force = corner_get(&mut s, "body_force");
            s.do_step(k as f64 * h, h).unwrap();
            v += h * force / m_s;
            z += h * v;
        }
        names
            .iter()
            .zip(&reference)
            .map(|(n, r)| ((corner_get(&mut s, n) - r) / r).abs())
            .fold(0.0, f64::max)
    };
    let (coarse, fine) = (error_at(1e-3), error_at(2.5e-4));
    assert!(fine < 1e-2, "{fine}");
    assert!(fine < coarse / 3.0, "{coarse} -> {fine}");
}

#[test]
fn the_token_picks_the_model_and_every_model_offers_model_exchange() {
    use crate::instantiation::Instantiation;
    let log: Log = Rc::default();
    let sink = log.clone();
    let instantiation = Instantiation::new(
        TEST_DIALECT,
        Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
    );
    for model in Model::ALL {
        assert_eq!(instantiation.model(Some(&guid(model))), Some(model));
    }
    for model in Model::ALL {
        assert_eq!(instantiation.interface(model, false), Some(()));
        assert_eq!(instantiation.interface(model, true), Some(()));
    }
    assert_eq!(instantiation.model(Some("{0}")), None);
    let messages: Vec<String> = log.borrow().iter().map(|(_, _, m)| m.clone()).collect();
    assert!(
        messages[0].contains(&guid(Model::QuarterCar))
            && messages[0].contains(&guid(Model::Corner)),
        "{messages:?}"
    );
}

/// Body inputs set once carry the attachment along their line over the
/// steps that follow, until they are set again; a body at rest stays put.
#[test]
fn the_attachment_follows_its_line_until_set_again() {
    let mut s = started_corner(&[("road_amplitude", 0.0)]);
    let (z, v) = (corner_vr("body_displacement"), corner_vr("body_velocity"));
    s.set_real(&[z, v], &[0.01, 0.2]).unwrap();
    let attachment = |s: &mut Slave| corner_get(s, "suspension_deflection") + corner_get(s, "x_t");
    for k in 1..=10 {
        s.do_step((k - 1) as f64 * 1e-3, 1e-3).unwrap();
        let expected = 0.01 + 0.2 * k as f64 * 1e-3;
        assert!((attachment(&mut s) - expected).abs() < 1e-15, "{k}");
    }
    s.set_real(&[v], &[0.0]).unwrap();
    let held = attachment(&mut s);
    for k in 10..20 {
        s.do_step(k as f64 * 1e-3, 1e-3).unwrap();
        assert_eq!(attachment(&mut s).to_bits(), held.to_bits(), "{k}");
    }
}

/// The warnings of ignored input derivatives name them as the call gave
/// them: the body inputs, the orders of `x_g` above 1, the chassis's
/// forces with their orders (listed while formatting, not collected).
#[test]
fn ignored_input_derivatives_are_named_in_the_order_given() {
    let log: Log = Rc::default();
    let sink = log.clone();
    let logger = Logger::new(
        Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
        true,
    );
    let mut s = Slave::new(TEST_DIALECT, Model::Corner, guid(Model::Corner), logger);
    s.setup_experiment(None, 0.0, None).unwrap();
    s.set_integer(&[corner_vr("road")], &[0]).unwrap();
    start(&mut s);
    let vrs = [
        corner_vr("x_g"),
        corner_vr("body_velocity"),
        corner_vr("x_g"),
        corner_vr("body_displacement"),
    ];
    let status = s
        .set_real_input_derivatives(&vrs, &[2, 1, 3, 1], &[0.1, 0.2, 0.3, 0.4])
        .unwrap();
    assert_eq!(status, Status::Warning);
    let warnings: Vec<String> = log
        .borrow()
        .iter()
        .filter(|(status, _, _)| *status == Status::Warning)
        .map(|(_, _, message)| message.clone())
        .collect();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        warnings[0]
            .contains(r#"the derivatives of ["body_velocity", "body_displacement"] are ignored"#),
        "{}",
        warnings[0]
    );
    assert!(
        warnings[1].contains("derivative orders [2, 3] of `x_g` ignored"),
        "{}",
        warnings[1]
    );

    let log: Log = Rc::default();
    let sink = log.clone();
    let logger = Logger::new(
        Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
        true,
    );
    let mut s = Slave::new(TEST_DIALECT, Model::Chassis, guid(Model::Chassis), logger);
    s.setup_experiment(None, 0.0, None).unwrap();
    start(&mut s);
    let force = |name| by_name(Model::Chassis, FmiVersion::Fmi2, name).unwrap().vr;
    let status = s
        .set_real_input_derivatives(
            &[force("force_rl"), force("force_fl"), force("force_rr")],
            &[2, 1, 4],
            &[1.0, 2.0, 3.0],
        )
        .unwrap();
    assert_eq!(status, Status::Warning);
    let last = log.borrow().last().unwrap().2.clone();
    assert!(
        last.contains(r#"derivatives [("force_rl", 2), ("force_rr", 4)] ignored"#),
        "{last}"
    );
}
