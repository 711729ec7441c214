//! The slave's behaviour, called directly as a front-end calls it (after
//! its state table allowed the call): values and their checks, stepping,
//! divergence, FMU states, the input over a step, partials, logging and the
//! tire's contact. Its length is the slave's whole surface, kept in one
//! file over one set of helpers (a slave in each phase, its values read
//! back).

use super::*;
use crate::variables::{
    Access, COMMON_VARIABLES, Causality, FmiVersion, VarType, Variable, by_name,
};
use std::cell::RefCell;
use std::rc::Rc;
use tdvass::model::V_S;

/// What a slave logged: `(status, category, message)`.
pub(crate) type Log = Rc<RefCell<Vec<(Status, String, String)>>>;

/// The names of a made-up front-end: the slave's messages use whatever its
/// dialect says (the variables are the ones both FMI versions have).
pub(crate) const TEST_DIALECT: Dialect = Dialect {
    version: FmiVersion::Fmi2,
    prefix: "test",
    last_successful_time: "testLastSuccessfulTime",
    terminate_flag: "testTerminated",
    set_float: "SetReal",
    set_input_derivatives: "SetRealInputDerivatives",
    fmu_state: "FMUstate",
    deserialize_state: "DeSerializeFMUstate",
    input_slope_remedy: "call testSetRealInputDerivatives",
    instantiate: "Instantiate",
    update_discrete_states: "NewDiscreteStates",
    token_argument: "testToken",
    given_token: "token",
    own_token: "token",
};

/// A slave speaking [`TEST_DIALECT`] and the log it writes to.
pub(crate) fn new_slave(logging_on: bool) -> (Slave, Log) {
    let log: Log = Rc::default();
    let sink = log.clone();
    let logger = Logger::new(
        Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
        logging_on,
    );
    (
        Slave::new(
            TEST_DIALECT,
            Model::QuarterCar,
            crate::variables::guid(Model::QuarterCar),
            logger,
        ),
        log,
    )
}

fn vr(name: &str) -> u32 {
    by_name(Model::QuarterCar, FmiVersion::Fmi3, name)
        .unwrap()
        .vr
}

/// The value reference of `model`'s FMI 2.0 variable `name`.
fn vr_of(model: Model, name: &str) -> u32 {
    by_name(model, FmiVersion::Fmi2, name)
        .unwrap_or_else(|| panic!("{model:?} has no `{name}`"))
        .vr
}

/// The Real `name` of `s`'s model.
fn get_of(s: &mut Slave, name: &str) -> f64 {
    let mut v = [0.0];
    s.get_real(&[vr_of(s.model(), name)], &mut v).unwrap();
    v[0]
}

fn start(s: &mut Slave) {
    s.enter_initialization_mode().unwrap();
    s.exit_initialization_mode().unwrap();
}

/// A slave in `stepComplete` at t = 0 (stop time 15 s).
pub(crate) fn initialized() -> (Slave, Log) {
    let (mut s, log) = new_slave(false);
    s.setup_experiment(None, 0.0, Some(15.0)).unwrap();
    start(&mut s);
    (s, log)
}

fn get(s: &mut Slave, name: &str) -> f64 {
    let mut v = [0.0];
    s.get_real(&[vr(name)], &mut v).unwrap();
    v[0]
}

/// The message of a refused call, which must be an Error.
fn refusal<T: std::fmt::Debug>(result: Result<T, FmiError>) -> String {
    let e = result.unwrap_err();
    assert_eq!(e.status, Status::Error, "{}", e.message);
    e.message
}

#[test]
fn values_are_checked_at_set_time_and_at_initialization() {
    let (mut s, _) = new_slave(false);
    let message = refusal(s.set_real(&[vr("m_s"), vr("m_h")], &[300.0, -1.0]));
    assert!(message.contains("`m_h`"), "{message}");
    assert_eq!(s.settings().params.m_s, 345.0, "nothing applied");
    let message = refusal(s.set_integer(&[vr("road_class")], &[9]));
    assert!(message.contains("road_class"), "{message}");
    for (name, bad) in [("tau", -1.0), ("g", f64::NAN), ("max_internal_step", -1e-4)] {
        let message = s.set_real(&[vr(name)], &[bad]).unwrap_err().message;
        assert!(
            message.contains(name) && message.contains(&format!("{bad}")),
            "{message}"
        );
    }
    // A delay needing too many history nodes passes the range check and
    // is refused when the simulation starts; the slave can be fixed.
    s.set_real(&[vr("tau")], &[1e4]).unwrap();
    s.enter_initialization_mode().unwrap();
    let message = s.exit_initialization_mode().unwrap_err().message;
    assert!(message.contains("`tau`"), "{message}");
    assert_eq!(s.phase(), Phase::InitializationMode);
    s.set_real(&[vr("tau")], &[2e-4]).unwrap();
    s.exit_initialization_mode().unwrap();
    // Fixed after initialization, outputs and calculated never.
    let refused = [
        ("m_s", "fixed parameter"),
        ("x_s", "output"),
        ("spectral_abscissa", "calculated"),
    ];
    for (name, why) in refused {
        let message = s.set_real(&[vr(name)], &[1.0]).unwrap_err().message;
        assert!(message.contains(name) && message.contains(why), "{message}");
    }
    assert!(s.set_boolean(&[vr("stable")], &[true]).is_err());
    assert!(s.set_real(&[vr("g")], &[1000.0]).is_ok());
    let message = s.set_real(&[vr("variant")], &[1.0]).unwrap_err().message;
    assert!(message.contains("Integer, not a Real"), "{message}");
}

#[test]
fn default_experiment_reproduces_table2() {
    let (mut s, _) = initialized();
    let mut t = 0.0;
    for k in 1..=15000 {
        let next = k as f64 * 1e-3;
        s.do_step(t, next - t).unwrap();
        t = next;
    }
    let ba = get(&mut s, "rms_body_acceleration");
    let sdd = get(&mut s, "rms_suspension_deflection");
    let tdd = get(&mut s, "rms_tire_deflection");
    assert!((ba - 0.3068).abs() < 1.5e-4, "{ba}");
    assert!((sdd - 0.0388).abs() < 1.5e-4, "{sdd}");
    assert!((tdd * 1e3 - 0.6251).abs() < 1.5e-4, "{tdd}");
    // Past the stop time.
    assert!(s.do_step(15.0, 0.1).is_err());
}

/// An unstable (g, tau): a warning at initialization, then a step that
/// diverges is a Discard; the slave stays at the last good node, asks for
/// termination, keeps its outputs finite, and a reset brings back the
/// start values.
#[test]
fn divergence_is_a_discard_with_last_successful_time() {
    let (mut s, log) = new_slave(false);
    s.set_real(
        &[vr("g"), vr("tau"), vr("x_s_start")],
        &[-40000.0, 0.11, 0.01],
    )
    .unwrap();
    s.enter_initialization_mode().unwrap();
    assert_eq!(s.exit_initialization_mode(), Ok(Status::Warning));
    assert!(log.borrow().iter().any(|(s, c, m)| *s == Status::Warning
        && c == "logStatusWarning"
        && m.contains("-40000")
        && m.contains("0.11")));
    let mut t = 0.0;
    let e = loop {
        match s.do_step(t, 1.0) {
            Ok(_) => t += 1.0,
            Err(e) => break e,
        }
        assert!(t < 1e4, "never diverged");
    };
    assert_eq!(e.status, Status::Discard);
    assert!(
        e.message.starts_with("simulation diverged at t ="),
        "{}",
        e.message
    );
    assert_eq!(s.phase(), Phase::StepFailed);
    let last = s.last_successful_time();
    assert!(last >= t && last < t + 1.0, "{last}");
    assert_eq!(s.time(), last);
    assert!(s.terminate_requested());
    for name in [
        "x_s",
        "x_t",
        "body_acceleration",
        "objective",
        "control_force",
    ] {
        assert!(get(&mut s, name).is_finite());
    }
    s.terminate().unwrap();
    s.reset().unwrap();
    assert_eq!(s.phase(), Phase::Instantiated);
    assert_eq!(s.settings().params.g, 5386.0);
}

#[test]
fn fmu_states_belong_to_their_slave() {
    let (mut a, _) = initialized();
    let (mut b, _) = initialized();
    let s = a.get_fmu_state(None).unwrap();
    let message = refusal(b.set_fmu_state(s));
    assert!(
        message.contains("not created by this instance"),
        "{message}"
    );
    a.do_step(0.0, 0.5).unwrap();
    let x = get(&mut a, "x_s");
    a.set_fmu_state(s).unwrap();
    assert_eq!(a.time(), 0.0);
    a.do_step(0.0, 0.5).unwrap();
    assert_eq!(get(&mut a, "x_s"), x);
    // Re-use overwrites in place.
    let again = a.get_fmu_state(Some(s)).unwrap();
    assert_eq!(again, s);
    assert_eq!(a.fmu_state_count(), 1);
    // Moving through bytes works across slaves, parameters included.
    let bytes = a.serialize_fmu_state(s).unwrap();
    let t = b.deserialize_fmu_state(&bytes, None).unwrap();
    b.set_fmu_state(t).unwrap();
    assert_eq!(b.time(), 0.5);
    assert_eq!(get(&mut b, "x_s"), x);
    a.free_fmu_state(s).unwrap();
    assert!(a.free_fmu_state(s).is_err(), "double free");
}

#[test]
fn extrapolation_slopes() {
    // x = 1 + 2 t − 3 t², sampled at uneven times; the next step is 0.004 s.
    let x = |t: f64| 1.0 + 2.0 * t - 3.0 * t * t;
    let times = [0.010, 0.012, 0.015];
    let values: Vec<(f64, f64)> = times.iter().map(|&t| (t, x(t))).collect();
    let h = 0.004;
    assert_eq!(extrapolation_slope(&values[2..], h), 0.0);
    let chord = (x(0.015) - x(0.012)) / 0.003;
    assert!((extrapolation_slope(&values[1..], h) - chord).abs() < 1e-12);
    // Of the lines through (t_k, x_k), the one closest to the parabola
    // over the step: the mean-square error is smallest at its slope.
    let best = extrapolation_slope(&values, h);
    let mean_square = |slope: f64| {
        (0..=1000)
            .map(|i| {
                let s = h * i as f64 / 1000.0;
                let e = x(0.015) + slope * s - x(0.015 + s);
                e * e
            })
            .sum::<f64>()
    };
    assert!((best - (2.0 - 6.0 * 0.015 - 3.0 * 0.375 * 2.0 * h)).abs() < 1e-9);
    assert!(mean_square(best) < mean_square(best + 1e-3));
    assert!(mean_square(best) < mean_square(best - 1e-3));
    // Times that do not increase hold the input.
    assert_eq!(extrapolation_slope(&[(0.1, 1.0), (0.1, 2.0)], h), 0.0);
}

#[test]
fn input_derivative_semantics() {
    let (mut s, _) = new_slave(false);
    s.set_integer(&[vr("road")], &[0]).unwrap();
    start(&mut s);
    s.set_real(&[vr("x_g")], &[0.01]).unwrap();
    assert_eq!(
        s.set_real_input_derivatives(&[vr("x_g"), vr("x_g")], &[1, 2], &[0.5, 3.0]),
        Ok(Status::Warning)
    );
    s.do_step(0.0, 0.1).unwrap();
    assert!((get(&mut s, "road_displacement") - 0.06).abs() < 1e-15);
    // Not set again: the same line continues.
    s.do_step(0.1, 0.1).unwrap();
    assert!((get(&mut s, "road_displacement") - 0.11).abs() < 1e-15);
    // Setting the value resets the slope.
    s.set_real(&[vr("x_g")], &[0.02]).unwrap();
    s.do_step(0.2, 0.1).unwrap();
    assert_eq!(get(&mut s, "road_displacement"), 0.02);
    let mut d = [0.0];
    s.get_real_output_derivatives(&[vr("road_displacement")], &[1], &mut d)
        .unwrap();
    assert_eq!(d[0], 0.0);
    assert!(
        s.get_real_output_derivatives(&[vr("x_s")], &[2], &mut d)
            .is_err()
    );
}

#[test]
fn model_structure_dependencies_are_the_nonzero_partials() {
    // One declaration: an output lists `x_g` among its dependencies in
    // the description exactly when its partial with respect to `x_g`
    // is not zero, for every variant with the road fed through `x_g`.
    for variant in [1, 2, 3] {
        let (mut s, _) = new_slave(false);
        s.setup_experiment(None, 0.0, Some(1.0)).unwrap();
        s.enter_initialization_mode().unwrap();
        s.set_integer(&[vr("variant"), vr("road")], &[variant, 0])
            .unwrap();
        s.exit_initialization_mode().unwrap();
        for v in COMMON_VARIABLES
            .iter()
            .filter(|v| v.causality == Causality::Output && v.var_type() == VarType::Real)
        {
            let mut partial = [f64::NAN];
            s.directional_derivative(&[v.vr], &[vr("x_g")], &[1.0], &mut partial)
                .unwrap();
            assert_eq!(
                partial[0] != 0.0,
                v.feedthrough.contains(&"x_g"),
                "variant {variant}, `{}`: partial {} against the declared dependencies {:?}",
                v.name,
                partial[0],
                v.feedthrough
            );
        }
        // The counts are Integers: no partials, and no dependencies.
        let mut partial = [f64::NAN];
        let e = s
            .directional_derivative(&[vr("lift_off_count")], &[vr("x_g")], &[1.0], &mut partial)
            .unwrap_err();
        assert!(
            e.message.contains("`lift_off_count` is an Integer output"),
            "{}",
            e.message
        );
        assert!(
            by_name(Model::QuarterCar, FmiVersion::Fmi3, "lift_off_count")
                .unwrap()
                .feedthrough
                .is_empty()
        );
    }
}

#[test]
fn directional_derivatives_are_exact() {
    let (mut s, _) = initialized();
    s.do_step(0.0, 0.3).unwrap();
    let states = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"].map(vr);
    let mut x = [0.0; 6];
    s.get_real(&states, &mut x).unwrap();
    let mut ba = [0.0];
    let seed = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
    s.directional_derivative(&[vr("body_acceleration")], &states, &seed, &mut ba)
        .unwrap();
    let a = s.simulator().unwrap().plant().a;
    let expected: f64 = (0..6).map(|j| a[(V_S, j)] * seed[j]).sum();
    assert_eq!(ba[0], expected);
    // BA is linear in the state: the partials reproduce it exactly.
    let ba_now = get(&mut s, "body_acceleration");
    let mut lin = [0.0];
    s.directional_derivative(&[vr("body_acceleration")], &states, &x, &mut lin)
        .unwrap();
    assert!((lin[0] - ba_now).abs() <= 1e-12 * ba_now.abs().max(1.0));
    let mut tdd = [0.0];
    s.directional_derivative(
        &[vr("tire_deflection")],
        &[vr("x_g"), vr("x_t")],
        &[1.0, 1.0],
        &mut tdd,
    )
    .unwrap();
    assert_eq!(tdd[0], 1.0, "road = 1: x_g is not applied");
    assert!(
        s.directional_derivative(&[vr("m_s")], &[vr("x_g")], &[1.0], &mut tdd)
            .is_err()
    );
}

#[test]
fn debug_logging_categories() {
    let (mut s, log) = new_slave(false);
    let message = refusal(s.logger_mut().set_categories(true, &["logNothing"]));
    assert!(message.contains("logNothing"), "{message}");
    s.logger_mut().set_categories(true, &["logEvents"]).unwrap();
    let before = log.borrow().len();
    s.reset().unwrap();
    assert_eq!(log.borrow().len(), before + 1);
    s.logger_mut().set_categories(false, &[]).unwrap();
    s.reset().unwrap();
    assert_eq!(log.borrow().len(), before + 1);
    // Errors are always reported.
    let refused = FmiError::error("not allowed in state instantiated");
    assert_eq!(s.report_failure("testTerminate", &refused), Status::Error);
    assert_eq!(log.borrow().len(), before + 2);
    assert_eq!(
        log.borrow().last().unwrap().2,
        "testTerminate: not allowed in state instantiated"
    );
    assert_eq!(s.phase(), Phase::Instantiated);
}

/// Sets PVASS on an ISO 8608 road of `class` at 30 m/s with the tire
/// model `tire_contact`, and initializes.
fn pvass_at_30(s: &mut Slave, class: i32, tire_contact: i32) {
    s.set_integer(
        &[
            vr("variant"),
            vr("road"),
            vr("road_class"),
            vr("tire_contact"),
        ],
        &[2, 2, class, tire_contact],
    )
    .unwrap();
    s.set_real(&[vr("vehicle_speed")], &[30.0]).unwrap();
    start(s);
}

/// PVASS on an ISO 8608 road at 30 m/s for 2 s: class H loses the tire
/// contact (one warning, naming time, variable and value, and a growing
/// `contact_loss_time`), class A does not.
#[test]
fn a_loss_of_tire_contact_is_logged_once() {
    for (class, loses) in [(8, true), (1, false)] {
        let (mut s, log) = new_slave(false);
        pvass_at_30(&mut s, class, 0);
        let mut t = 0.0;
        for _ in 0..200 {
            s.do_step(t, 0.01).unwrap();
            t += 0.01;
        }
        let warnings: Vec<_> = log
            .borrow()
            .iter()
            .filter(|(s, _, m)| *s == Status::Warning && m.contains("leaves the road"))
            .map(|(_, _, m)| m.clone())
            .collect();
        let lost = get(&mut s, "contact_loss_time");
        if loses {
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(
                warnings[0].starts_with("testDoStep: the tire leaves the road at t = ")
                    && warnings[0].contains("`dynamic_tire_load` = -"),
                "{}",
                warnings[0]
            );
            assert!(lost > 0.0 && lost < 2.0, "{lost}");
        } else {
            assert!(warnings.is_empty(), "{warnings:?}");
            assert_eq!(lost, 0.0);
        }
    }
}

fn lift_off_count(s: &mut Slave) -> i32 {
    let mut n = [-1];
    s.get_integer(&[vr("lift_off_count")], &mut n).unwrap();
    n[0]
}

/// The same PVASS run on class H as above with `tire_contact = 1`: no
/// warning; each lift-off is an event (time, TDD at W/k_t), as many as
/// `lift_off_count`; in flight the dynamic tire load is −W and does not
/// depend on `x_t`. A code that is none is refused by name.
#[test]
fn the_unilateral_tire_logs_each_lift_off_as_an_event() {
    let (mut s, log) = new_slave(true);
    let message = refusal(s.set_integer(&[vr("tire_contact")], &[2]));
    assert!(
        message.contains("`tire_contact`") && message.contains("invalid value 2"),
        "{message}"
    );
    pvass_at_30(&mut s, 8, 1);
    let static_load = (345.0 + 4.05) * 9.80665 + 40.5 * 9.80665;
    let limit = static_load / 190000.0;
    let (mut t, mut flights, mut contacts) = (0.0, 0, 0);
    for _ in 0..200 {
        s.do_step(t, 0.01).unwrap();
        t += 0.01;
        let mut partial = [f64::NAN];
        s.directional_derivative(
            &[vr("dynamic_tire_load")],
            &[vr("x_t")],
            &[1.0],
            &mut partial,
        )
        .unwrap();
        let load = get(&mut s, "dynamic_tire_load");
        if s.simulator().unwrap().in_flight() {
            flights += 1;
            assert_eq!(partial[0], 0.0);
            assert!((load + static_load).abs() <= 1e-9 * static_load, "{load}");
        } else {
            contacts += 1;
            assert_eq!(partial[0], -190000.0);
            assert!(load >= -static_load * (1.0 + 1e-9), "{load}");
        }
    }
    assert!(flights > 0 && contacts > 0, "{flights} {contacts}");
    let log = log.borrow();
    assert!(
        !log.iter()
            .any(|(s, _, m)| *s == Status::Warning && m.contains("the tire leaves the road")),
        "the bilateral tire's warning with the unilateral tire"
    );
    let events: Vec<&String> = log
        .iter()
        .filter(|(s, c, m)| *s == Status::Ok && c == "logEvents" && m.contains("lift-off at t = "))
        .map(|(_, _, m)| m)
        .collect();
    let count = lift_off_count(&mut s);
    assert!(count > 0);
    assert_eq!(events.len(), count as usize, "{events:?}");
    let mut last = 0.0;
    for e in events {
        let number = |after: &str| -> f64 {
            let rest = &e[e.find(after).unwrap() + after.len()..];
            rest[..rest.find(' ').unwrap()].parse().unwrap()
        };
        let (time, tdd, shown) = (number("t = "), number("TDD = "), number("W/k_t = "));
        assert!(time > last && time <= 2.0, "{e}");
        last = time;
        assert!((shown - limit).abs() <= 1e-12 * limit, "{e}");
        assert!((tdd - shown).abs() <= 1e-9 * shown, "{e}");
    }
    assert!(get(&mut s, "contact_loss_time") > 0.0);
}

/// With the bilateral tire `lift_off_count` counts the falls of the load
/// below −W (no events, the one warning of the test above).
#[test]
fn the_bilateral_tire_counts_its_would_be_lift_offs() {
    for (class, loses) in [(8, true), (1, false)] {
        let (mut s, log) = new_slave(true);
        pvass_at_30(&mut s, class, 0);
        s.do_step(0.0, 2.0).unwrap();
        let count = lift_off_count(&mut s);
        assert_eq!(count > 0, loses, "class {class}: {count}");
        assert!(
            !log.borrow()
                .iter()
                .any(|(_, _, m)| m.contains("lift-off at t = "))
        );
    }
}

#[test]
fn getters_of_one_kind_of_output_give_what_all_outputs_give() {
    // One slave reads the instantaneous outputs alone, then the time
    // averages alone (each computes only its part); its twin reads every
    // Real output in one call (every output computed): the same bits, on
    // and between the internal nodes, with either tire and the wheel off
    // the road.
    let outputs: Vec<&Variable> = COMMON_VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output && v.var_type() == VarType::Real)
        .collect();
    let instantaneous: Vec<u32> = outputs
        .iter()
        .filter(|v| matches!(v.access, Access::Output(id) if id.is_instantaneous()))
        .map(|v| v.vr)
        .collect();
    let averages: Vec<u32> = outputs
        .iter()
        .filter(|v| matches!(v.access, Access::Output(id) if id.is_time_average()))
        .map(|v| v.vr)
        .collect();
    assert_eq!(instantaneous.len(), 12);
    assert_eq!(averages.len(), 5);
    let all: Vec<u32> = outputs.iter().map(|v| v.vr).collect();
    for tire_contact in [0, 1] {
        let (mut alone, _) = new_slave(false);
        let (mut together, _) = new_slave(false);
        for s in [&mut alone, &mut together] {
            s.set_integer(&[vr("tire_contact")], &[tire_contact])
                .unwrap();
            s.set_real(&[vr("road_amplitude")], &[0.05]).unwrap();
            s.setup_experiment(None, 0.0, None).unwrap();
            start(s);
        }
        let steps = [1e-3, 7e-4, 9.9e-5, 1.3e-3, 1e-7];
        let mut t = 0.0;
        for i in 0..1500 {
            let h = steps[i % steps.len()];
            alone.do_step(t, h).unwrap();
            together.do_step(t, h).unwrap();
            t += h;
            let mut now = vec![0.0; instantaneous.len()];
            alone.get_real(&instantaneous, &mut now).unwrap();
            let mut mean = vec![0.0; averages.len()];
            alone.get_real(&averages, &mut mean).unwrap();
            let mut every = vec![0.0; all.len()];
            together.get_real(&all, &mut every).unwrap();
            let by_vr = |vr: u32| every[all.iter().position(|&v| v == vr).unwrap()].to_bits();
            for (vrs, values) in [(&instantaneous, &now), (&averages, &mean)] {
                for (vr, value) in vrs.iter().zip(values.iter()) {
                    assert_eq!(value.to_bits(), by_vr(*vr), "vr {vr} at t = {t}");
                }
            }
        }
    }
}

#[test]
fn getter_lists_give_the_same_values_and_errors_whatever_was_read_before() {
    // The looked-up list of the last call is kept: a repeated list, a
    // shorter or longer one, a list longer than is kept and a list with a
    // reference that is no Real variable each read (or refuse) as alone.
    let (mut s, _) = initialized();
    s.do_step(0.0, 7e-4).unwrap();
    let ba = vr("body_acceleration");
    let rms = vr("rms_body_acceleration");
    let max = vr("max_suspension_deflection");
    let expected = [
        get(&mut s, "body_acceleration"),
        get(&mut s, "rms_body_acceleration"),
    ];
    let expected_max = get(&mut s, "max_suspension_deflection");
    for _ in 0..2 {
        for (vrs, values) in [
            (vec![ba, rms], expected.to_vec()),
            (vec![rms, ba], vec![expected[1], expected[0]]),
            (vec![ba], vec![expected[0]]),
            (
                vec![rms, ba, max],
                vec![expected[1], expected[0], expected_max],
            ),
            (vec![ba; 40], vec![expected[0]; 40]),
            (vec![rms; 32], vec![expected[1]; 32]),
        ] {
            let mut got = vec![0.0; vrs.len()];
            s.get_real(&vrs, &mut got).unwrap();
            assert_eq!(got, values, "{vrs:?}");
        }
        let message = refusal(s.get_real(&[ba, 9999], &mut [0.0; 2]));
        assert!(
            message.contains("unknown value reference 9999"),
            "{message}"
        );
        let message = refusal(s.get_real(&[ba, vr("variant")], &mut [0.0; 2]));
        assert!(message.contains("`variant`"), "{message}");
        let message = refusal(s.get_real(&[ba, rms], &mut [0.0; 1]));
        assert!(message.contains("1 values given"), "{message}");
    }
}

// ---------------------------------------------------------- Model Exchange

/// A Model Exchange slave in Continuous-Time Mode at t = 0.
fn model_exchange(logging_on: bool) -> (Slave, Log) {
    let (mut s, log) = new_slave(logging_on);
    s.use_model_exchange();
    s.setup_experiment(None, 0.0, Some(15.0)).unwrap();
    start(&mut s);
    assert_eq!(s.phase(), Phase::EventMode);
    s.update_discrete_states().unwrap();
    s.enter_continuous_time_mode().unwrap();
    (s, log)
}

#[test]
fn model_exchange_derivatives_match_the_cosimulation_at_the_start() {
    let (mut me, _) = model_exchange(false);
    let (mut cs, _) = initialized();
    let mut derivatives = [0.0; tdvass::solver::CONTINUOUS_STATES];
    me.get_derivatives(&mut derivatives).unwrap();
    let through_getter: Vec<f64> = COMMON_VARIABLES
        .iter()
        .filter_map(|v| match v.access {
            Access::StateDerivative(_) => {
                let mut value = [0.0];
                cs.get_real(&[v.vr], &mut value).unwrap();
                Some(value[0])
            }
            _ => None,
        })
        .collect();
    assert_eq!(derivatives.to_vec(), through_getter);
}

#[test]
fn model_exchange_refuses_bad_counts_states_and_times_naming_them() {
    let (mut s, _) = model_exchange(false);
    let n = tdvass::solver::CONTINUOUS_STATES;
    let mut states = vec![0.0; n];
    s.get_continuous_states(&mut states).unwrap();
    let e = s.get_derivatives(&mut vec![0.0; n - 1]).unwrap_err();
    assert_eq!(e.message, "19 derivatives asked for, the model has 20");
    let e = s.set_continuous_states(&states[..3]).unwrap_err();
    assert!(
        e.message.contains("3 continuous states given"),
        "{}",
        e.message
    );
    states[4] = f64::NAN;
    let e = s.set_continuous_states(&states).unwrap_err();
    assert!(
        e.message.contains("continuous state 4 (`x_t`) = NaN"),
        "{}",
        e.message
    );
    s.set_time(0.5).unwrap();
    s.completed_integrator_step().unwrap();
    let e = s.set_time(0.25).unwrap_err();
    assert!(e.message.contains("0.25 s is before"), "{}", e.message);
    assert_eq!(e.status, Status::Error);
    // Still usable.
    s.set_time(0.75).unwrap();
    s.get_derivatives(&mut vec![0.0; n]).unwrap();
}

#[test]
fn a_diverged_model_exchange_state_asks_to_terminate_naming_it() {
    let (mut s, log) = model_exchange(true);
    let mut states = vec![0.0; tdvass::solver::CONTINUOUS_STATES];
    states[0] = 1e9;
    s.set_continuous_states(&states).unwrap();
    assert!(s.completed_integrator_step().unwrap().terminate_simulation);
    let logged = log.borrow();
    assert!(
        logged
            .iter()
            .any(|(status, _, m)| *status == Status::Warning && m.contains("`x_s` = 1000000000")),
        "{logged:?}"
    );
}

#[test]
fn a_parameter_is_tuned_in_event_mode_only() {
    let (mut s, _) = model_exchange(false);
    let e = s.set_real(&[vr("g")], &[1000.0]).unwrap_err();
    assert!(e.message.contains("Event Mode only"), "{}", e.message);
    s.enter_event_mode().unwrap();
    s.set_real(&[vr("g")], &[1000.0]).unwrap();
}

#[test]
fn a_model_exchange_state_round_trips_and_stays_with_its_interface() {
    let (mut s, _) = model_exchange(false);
    s.set_time(0.1).unwrap();
    let mut derivatives = vec![0.0; tdvass::solver::CONTINUOUS_STATES];
    s.get_derivatives(&mut derivatives).unwrap();
    let handle = s.get_fmu_state(None).unwrap();
    let bytes = s.serialize_fmu_state(handle).unwrap();
    let restored = s.deserialize_fmu_state(&bytes, None).unwrap();
    s.set_fmu_state(restored).unwrap();
    assert_eq!(s.time(), 0.1);
    let (mut cs, _) = initialized();
    let e = cs.deserialize_fmu_state(&bytes, None).unwrap_err();
    assert!(
        e.message
            .contains("a Model Exchange state cannot be restored into a Co-Simulation instance")
    );
}

mod chassis;
mod component_exchange;
mod corner;
mod extrapolation;
