//! The corner and the chassis in Model Exchange: their FMU states restore
//! a run to the bit, and bad states, times and inputs are refused by name.

use super::*;
use crate::variables::guid;

fn slave_of(model: Model) -> Slave {
    let logger = Logger::new(Box::new(|_, _, _| {}), false);
    Slave::new(TEST_DIALECT, model, guid(model), logger)
}

fn vr_of(model: Model, name: &str) -> u32 {
    by_name(model, FmiVersion::Fmi2, name)
        .unwrap_or_else(|| panic!("{model:?} has no `{name}`"))
        .vr
}

fn set_of(s: &mut Slave, name: &str, value: f64) -> Result<Status, FmiError> {
    s.set_real(&[vr_of(s.model(), name)], &[value])
}

fn get_of(s: &mut Slave, name: &str) -> f64 {
    let mut v = [0.0];
    s.get_real(&[vr_of(s.model(), name)], &mut v).unwrap();
    v[0]
}

/// A Model Exchange slave of `model` in Continuous-Time Mode at t = 0.
fn exchange_of(model: Model) -> Slave {
    let mut s = slave_of(model);
    s.use_model_exchange();
    s.setup_experiment(None, 0.0, None).unwrap();
    start(&mut s);
    assert_eq!(s.phase(), Phase::EventMode);
    s.update_discrete_states().unwrap();
    s.enter_continuous_time_mode().unwrap();
    s
}

fn count(s: &Slave) -> usize {
    s.model().continuous_states().len()
}

fn states(s: &mut Slave) -> Vec<f64> {
    let mut x = vec![0.0; count(s)];
    s.get_continuous_states(&mut x).unwrap();
    x
}

fn derivatives(s: &mut Slave) -> Vec<f64> {
    let mut dx = vec![0.0; count(s)];
    s.get_derivatives(&mut dx).unwrap();
    dx
}

const H: f64 = 1e-4;

/// Sets the inputs of step `k` (the corner's body attachment and road, the
/// chassis's forces), each a smooth function of the step.
fn inputs(s: &mut Slave, k: usize) {
    let t = k as f64 * H;
    match s.model() {
        Model::Chassis => {
            for (i, name) in ["force_fl", "force_fr", "force_rl", "force_rr"]
                .iter()
                .enumerate()
            {
                let f = 400.0 * (9.0 * t + i as f64).sin();
                set_of(s, name, f).unwrap();
            }
        }
        _ => {
            let z = 2e-3 * (11.0 * t).sin();
            let v = 2.2e-2 * (11.0 * t).cos();
            s.set_real(
                &[
                    vr_of(s.model(), "body_displacement"),
                    vr_of(s.model(), "body_velocity"),
                ],
                &[z, v],
            )
            .unwrap();
        }
    }
}

/// Explicit Euler steps `from..to` of [`H`], each completed; returns the
/// bits of the last derivatives and of the outputs `read`.
fn euler(s: &mut Slave, from: usize, to: usize, read: &[&str]) -> Vec<u64> {
    for k in from..to {
        inputs(s, k);
        let (x, dx) = (states(s), derivatives(s));
        s.set_time((k + 1) as f64 * H).unwrap();
        let next: Vec<f64> = x.iter().zip(&dx).map(|(a, b)| a + H * b).collect();
        s.set_continuous_states(&next).unwrap();
        let done = s.completed_integrator_step().unwrap();
        assert!(!done.terminate_simulation && !done.enter_event_mode);
    }
    inputs(s, to);
    let mut out: Vec<u64> = derivatives(s).iter().map(|v| v.to_bits()).collect();
    out.extend(states(s).iter().map(|v| v.to_bits()));
    out.extend(read.iter().map(|n| get_of(s, n).to_bits()));
    out
}

const CHASSIS_OUTPUTS: [&str; 7] = [
    "heave",
    "roll_rate",
    "displacement_rr",
    "seat_acceleration",
    "rms_pitch_acceleration",
    "rms_weighted_seat_acceleration",
    "seat_vibration_dose_value",
];

const CORNER_OUTPUTS: [&str; 5] = [
    "body_force",
    "suspension_deflection",
    "rms_suspension_deflection",
    "rms_dynamic_tire_load_ratio",
    "x_t",
];

fn outputs_of(model: Model) -> &'static [&'static str] {
    match model {
        Model::Chassis => &CHASSIS_OUTPUTS,
        _ => &CORNER_OUTPUTS,
    }
}

#[test]
fn a_model_exchange_state_of_the_corner_or_the_chassis_restores_the_run_to_the_bit() {
    for model in [Model::Corner, Model::Chassis] {
        let read = outputs_of(model);
        let mut s = exchange_of(model);
        euler(&mut s, 0, 300, read);
        let saved = s.get_fmu_state(None).unwrap();
        let bytes = s.serialize_fmu_state(saved).unwrap();
        let first = euler(&mut s, 300, 600, read);
        // Set back: the same bits.
        s.set_fmu_state(saved).unwrap();
        assert_eq!(s.phase(), Phase::ContinuousTimeMode);
        assert_eq!(s.time(), 300.0 * H);
        assert_eq!(euler(&mut s, 300, 600, read), first, "{model:?}");
        // Through bytes, into a fresh instance: the same bits.
        let mut other = slave_of(model);
        other.use_model_exchange();
        let restored = other.deserialize_fmu_state(&bytes, None).unwrap();
        other.set_fmu_state(restored).unwrap();
        assert_eq!(other.phase(), Phase::ContinuousTimeMode);
        assert_eq!(euler(&mut other, 300, 600, read), first, "{model:?}");
        // And serialized again, the same bytes.
        let again = other.deserialize_fmu_state(&bytes, None).unwrap();
        assert_eq!(other.serialize_fmu_state(again).unwrap(), bytes);
        // Not into a Co-Simulation instance of the model.
        let mut cs = slave_of(model);
        let e = refusal(cs.deserialize_fmu_state(&bytes, None));
        assert!(
            e.contains("a Model Exchange state cannot be restored into a Co-Simulation instance"),
            "{e}"
        );
    }
}

#[test]
fn a_model_exchange_state_in_event_mode_restores_to_event_mode() {
    for model in [Model::Corner, Model::Chassis] {
        let read = outputs_of(model);
        let mut s = exchange_of(model);
        euler(&mut s, 0, 50, read);
        s.enter_event_mode().unwrap();
        let saved = s.get_fmu_state(None).unwrap();
        let bytes = s.serialize_fmu_state(saved).unwrap();
        s.update_discrete_states().unwrap();
        s.enter_continuous_time_mode().unwrap();
        let first = euler(&mut s, 50, 100, read);
        let mut other = slave_of(model);
        other.use_model_exchange();
        let restored = other.deserialize_fmu_state(&bytes, None).unwrap();
        other.set_fmu_state(restored).unwrap();
        assert_eq!(other.phase(), Phase::EventMode, "{model:?}");
        other.update_discrete_states().unwrap();
        other.enter_continuous_time_mode().unwrap();
        assert_eq!(euler(&mut other, 50, 100, read), first, "{model:?}");
    }
}

#[test]
fn the_chassis_in_model_exchange_refuses_bad_states_times_and_forces_by_name() {
    let mut s = exchange_of(Model::Chassis);
    euler(&mut s, 0, 20, &[]);
    let saved = s.get_fmu_state(None).unwrap();
    let before = s.serialize_fmu_state(saved).unwrap();
    let unchanged = |s: &mut Slave| {
        let now = s.get_fmu_state(None).unwrap();
        assert_eq!(s.serialize_fmu_state(now).unwrap(), before);
    };
    let x = states(&mut s);
    for (i, bad) in [(0, f64::NAN), (7, f64::INFINITY), (18, f64::NEG_INFINITY)] {
        let mut values = x.clone();
        values[i] = bad;
        let e = refusal(s.set_continuous_states(&values));
        let name = tdvass::chassis::CHASSIS_STATE_NAMES[i];
        assert!(
            e.contains(&format!(
                "continuous state {i} (`{name}`) = {bad} is not finite"
            )),
            "{e}"
        );
        unchanged(&mut s);
    }
    let e = refusal(s.set_continuous_states(&x[..18]));
    assert!(
        e.contains("18 continuous states given, the model has 19"),
        "{e}"
    );
    for bad in [f64::NAN, f64::INFINITY, -1.0] {
        let e = refusal(s.set_time(bad));
        assert!(
            e.contains(&format!("invalid time {bad} s for `time`")),
            "{e}"
        );
        unchanged(&mut s);
    }
    for (name, bad) in [("force_fl", f64::NAN), ("force_rr", f64::NEG_INFINITY)] {
        let e = refusal(set_of(&mut s, name, bad));
        assert!(e.contains(name) && e.contains(&bad.to_string()), "{e}");
        unchanged(&mut s);
    }
    let e = refusal(set_of(&mut s, "mass", 1000.0));
    assert!(e.contains("mass"), "{e}");
    // A force too large for the chassis: its derivatives are refused,
    // naming the first that is not finite; a smaller force goes on.
    set_of(&mut s, "force_fl", 1e300).unwrap();
    let e = refusal(s.get_derivatives(&mut [0.0; 19]));
    assert!(
        e.contains("the derivative of `integral_heave_acceleration_squared` is inf at t = 0.002 s"),
        "{e}"
    );
    let e = refusal(s.get_real(
        &[vr_of(
            Model::Chassis,
            "der(integral_heave_acceleration_squared)",
        )],
        &mut [0.0],
    ));
    assert!(e.contains("is inf"), "{e}");
    set_of(&mut s, "force_fl", 100.0).unwrap();
    assert!(derivatives(&mut s).iter().all(|v| v.is_finite()));
}

#[test]
fn the_chassis_refuses_a_non_positive_mass_or_inertia_in_model_exchange() {
    for (name, bad) in [
        ("mass", 0.0),
        ("mass", -1.0),
        ("pitch_inertia", 0.0),
        ("roll_inertia", f64::NAN),
        ("roll_inertia", -400.0),
    ] {
        let mut s = slave_of(Model::Chassis);
        s.use_model_exchange();
        s.setup_experiment(None, 0.0, None).unwrap();
        let e = refusal(set_of(&mut s, name, bad));
        assert!(e.contains(name) && e.contains(&bad.to_string()), "{e}");
        // The start values stay, and the model starts.
        start(&mut s);
        assert_eq!(s.phase(), Phase::EventMode);
        assert!(derivatives(&mut s).iter().all(|v| v.is_finite()));
    }
}

#[test]
fn a_negative_integral_set_by_a_master_s_solver_saves_and_restores() {
    // A solver may set an integral a rounding below 0: the state
    // restores (the outputs take it as 0).
    let mut s = exchange_of(Model::Chassis);
    euler(&mut s, 0, 10, &[]);
    let mut x = states(&mut s);
    x[tdvass::chassis::CHASSIS_INTEGRALS_AT] = -1e-30;
    s.set_continuous_states(&x).unwrap();
    let saved = s.get_fmu_state(None).unwrap();
    let bytes = s.serialize_fmu_state(saved).unwrap();
    let mut other = slave_of(Model::Chassis);
    other.use_model_exchange();
    let restored = other.deserialize_fmu_state(&bytes, None).unwrap();
    other.set_fmu_state(restored).unwrap();
    assert_eq!(states(&mut other), x);
    assert_eq!(get_of(&mut other, "rms_heave_acceleration"), 0.0);
}

#[test]
fn the_corner_in_model_exchange_refuses_bad_body_inputs_states_and_times_by_name() {
    let mut s = exchange_of(Model::Corner);
    euler(&mut s, 0, 20, &[]);
    let saved = s.get_fmu_state(None).unwrap();
    let before = s.serialize_fmu_state(saved).unwrap();
    let unchanged = |s: &mut Slave| {
        let now = s.get_fmu_state(None).unwrap();
        assert_eq!(s.serialize_fmu_state(now).unwrap(), before);
    };
    for (name, bad) in [
        ("body_displacement", f64::NAN),
        ("body_displacement", 1e9),
        ("body_velocity", f64::INFINITY),
        ("x_g", f64::NAN),
        ("x_g", f64::NEG_INFINITY),
    ] {
        let e = refusal(set_of(&mut s, name, bad));
        assert!(e.contains(name) && e.contains(&bad.to_string()), "{e}");
        unchanged(&mut s);
    }
    let x = states(&mut s);
    for (i, name) in ["x_h", "v_h", "x_t", "v_t"].iter().enumerate() {
        let mut values = x.clone();
        values[i] = f64::NAN;
        let e = refusal(s.set_continuous_states(&values));
        assert!(
            e.contains(&format!(
                "continuous state {i} (`{name}`) = NaN is not finite"
            )),
            "{e}"
        );
        unchanged(&mut s);
    }
    let e = refusal(s.set_continuous_states(&x[..6]));
    assert!(
        e.contains("6 continuous states given, the model has 7"),
        "{e}"
    );
    // Back before the last completed step: refused naming both times.
    let e = refusal(s.set_time(1e-3));
    assert!(
        e.contains("time 0.001 s is before 0.002 s, the last completed integrator step"),
        "{e}"
    );
    let e = refusal(s.set_time(f64::NAN));
    assert!(e.contains("time NaN s is not finite"), "{e}");
    unchanged(&mut s);
    // Still usable.
    euler(&mut s, 20, 30, &[]);
}

#[test]
fn the_chassis_s_model_exchange_partials_are_exact_and_bad_calls_are_named() {
    let model = Model::Chassis;
    // Before initialization there is no model to differentiate.
    let mut s = slave_of(model);
    s.use_model_exchange();
    s.setup_experiment(None, 0.0, None).unwrap();
    let e = refusal(s.partials(
        &[vr_of(model, "der(heave_velocity)")],
        &[vr_of(model, "force_fl")],
    ));
    assert!(e.contains("not initialized"), "{e}");
    let mut s = exchange_of(model);
    inputs(&mut s, 3);
    let mass = get_of(&mut s, "mass");
    let heave_rate = vr_of(model, "der(heave_velocity)");
    let forces: Vec<u32> = ["force_fl", "force_fr", "force_rl", "force_rr"]
        .iter()
        .map(|n| vr_of(model, n))
        .collect();
    // m z'' = Σ f: each force moves the heave acceleration by 1/m.
    let row = s.partials(&[heave_rate], &forces).unwrap();
    assert_eq!(row.len(), 4);
    for value in row {
        assert!((value - 1.0 / mass).abs() <= 1e-15 / mass, "{value}");
    }
    // The heave is the integral of its velocity.
    let partial = s
        .partials(
            &[vr_of(model, "der(heave)")],
            &[vr_of(model, "heave_velocity")],
        )
        .unwrap();
    assert_eq!(partial, [1.0]);
    let e = refusal(s.partials(&[heave_rate], &[vr_of(model, "mass")]));
    assert!(e.contains("`mass` is not a known"), "{e}");
    let e = refusal(s.partials(&[vr_of(model, "mass")], &forces));
    assert!(e.contains("`mass` is not an unknown"), "{e}");
    // Co-Simulation provides none.
    let mut cs = slave_of(model);
    cs.setup_experiment(None, 0.0, None).unwrap();
    start(&mut cs);
    let e = refusal(cs.partials(&[vr_of(model, "heave")], &forces));
    assert!(e.contains("Model Exchange only"), "{e}");
}
