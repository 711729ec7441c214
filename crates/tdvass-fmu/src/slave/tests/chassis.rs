//! The chassis model ([`Model::Chassis`]): its variables, its exact step
//! under held and ramped forces, its states, its refusals, and a car of
//! four corners on it that, decoupled, rides as the quarter car.

use super::*;
use crate::variables::{guid, variables_of};
use tdvass::chassis::ChassisParams;

/// A slave of `model` speaking [`TEST_DIALECT`], at its start values.
fn slave_of(model: Model) -> Slave {
    let logger = Logger::new(Box::new(|_, _, _| {}), false);
    Slave::new(TEST_DIALECT, model, guid(model), logger)
}

fn set_of(s: &mut Slave, name: &str, value: f64) {
    s.set_real(&[vr_of(s.model(), name)], &[value]).unwrap();
}

/// A slave of `model` initialized at t = 0 with the Real settings `set`.
fn started(model: Model, set: &[(&str, f64)]) -> Slave {
    let mut s = slave_of(model);
    s.setup_experiment(None, 0.0, None).unwrap();
    for &(name, value) in set {
        set_of(&mut s, name, value);
    }
    start(&mut s);
    s
}

const FORCES: [&str; 4] = ["force_fl", "force_fr", "force_rl", "force_rr"];

#[test]
fn the_chassis_has_its_parameters_forces_and_motion() {
    for version in [FmiVersion::Fmi2, FmiVersion::Fmi3] {
        let variables = variables_of(Model::Chassis, version);
        let names: Vec<&str> = variables.iter().map(|v| v.name).collect();
        for present in [
            "mass",
            "pitch_inertia",
            "roll_inertia",
            "force_fl",
            "force_rr",
            "displacement_fl",
            "velocity_rr",
            "heave",
            "roll_rate",
            "seat_acceleration",
            "rms_weighted_seat_acceleration",
            "seat_vibration_dose_value",
        ] {
            assert!(names.contains(&present), "{version:?} lacks {present}");
        }
        assert_eq!(
            names.contains(&"time"),
            version == FmiVersion::Fmi3,
            "{version:?}"
        );
        for absent in ["variant", "k_s", "x_g", "body_force"] {
            assert!(!names.contains(&absent), "{version:?} has {absent}");
        }
        let mut vrs: Vec<u32> = variables.iter().map(|v| v.vr).collect();
        vrs.sort_unstable();
        vrs.dedup();
        assert_eq!(vrs.len(), names.len(), "{version:?}: references unique");
        // The attachment points depend on the states alone: a car of
        // corners and chassis has no algebraic loop.
        for v in variables
            .iter()
            .filter(|v| v.name.starts_with("displacement_"))
        {
            let knowns = v.output_dependencies(Model::Chassis, version);
            assert_eq!(knowns.len(), 3, "{}", v.name);
            assert!(knowns.iter().all(|(k, _)| k.state_index().is_some()));
        }
        let heave_acceleration = by_name(Model::Chassis, version, "heave_acceleration").unwrap();
        assert_eq!(
            heave_acceleration
                .output_dependencies(Model::Chassis, version)
                .len(),
            4
        );
    }
    // The defaults are the library's: the paper's car.
    let s = slave_of(Model::Chassis);
    assert_eq!(s.settings().chassis, ChassisParams::default());
    assert_ne!(guid(Model::Chassis), guid(Model::Corner));
}

/// A force held at the front left corner: heave, pitch and roll follow in
/// closed form, the accelerations at once (feedthrough), and the
/// attachment points' motion is the body's.
#[test]
fn a_held_force_moves_the_body_in_closed_form() {
    let force = 1000.0;
    // Set at the start of the run, the force reaches the accelerations at
    // once, before any step.
    let mut s = started(Model::Chassis, &[]);
    assert_eq!(get_of(&mut s, "heave_acceleration"), 0.0);
    set_of(&mut s, "force_fl", force);
    let p = ChassisParams::default();
    let accelerations = [
        force / p.mass,
        p.a * force / p.pitch_inertia,
        0.5 * p.track_front * force / p.roll_inertia,
    ];
    for (name, expected) in [
        "heave_acceleration",
        "pitch_acceleration",
        "roll_acceleration",
    ]
    .iter()
    .zip(accelerations)
    {
        assert!((get_of(&mut s, name) - expected).abs() <= 1e-13 * expected);
    }
    assert_eq!(get_of(&mut s, "heave"), 0.0);
    let t = 0.25;
    for k in 0..250 {
        s.do_step(k as f64 * 1e-3, 1e-3).unwrap();
    }
    let positions: Vec<f64> = ["heave", "pitch", "roll"]
        .iter()
        .map(|n| get_of(&mut s, n))
        .collect();
    for (got, a) in positions.iter().zip(accelerations) {
        let exact = a * t * t / 2.0;
        assert!((got - exact).abs() <= 1e-12 * exact, "{got} {exact}");
    }
    let fl = get_of(&mut s, "displacement_fl");
    let expected = positions[0] + p.a * positions[1] + 0.5 * p.track_front * positions[2];
    assert!((fl - expected).abs() <= 1e-15);
    // With m a b as the pitch inertia the rear axle's middle does not
    // move (the roll tilts it).
    let rear = get_of(&mut s, "displacement_rl") + get_of(&mut s, "displacement_rr");
    assert!(rear.abs() < 1e-15, "{rear}");
    assert!(get_of(&mut s, "displacement_rl") > 0.0);
    assert!(get_of(&mut s, "rms_heave_acceleration") > 0.0);
    assert!(get_of(&mut s, "seat_vibration_dose_value") > 0.0);
}

/// A force's order-1 input derivative ramps it over the step: the heave
/// grows as r t³ / (6 m); setting the force again holds it.
#[test]
fn an_input_derivative_ramps_a_force() {
    let mut s = started(Model::Chassis, &[]);
    let rate = 4000.0;
    let vrs: Vec<u32> = FORCES.iter().map(|n| vr_of(Model::Chassis, n)).collect();
    assert_eq!(
        s.set_real_input_derivatives(&vrs, &[1; 4], &[rate; 4])
            .unwrap(),
        Status::Ok
    );
    s.do_step(0.0, 0.1).unwrap();
    let m = ChassisParams::default().mass;
    let exact = 4.0 * rate * 0.1f64.powi(3) / (6.0 * m);
    let heave = get_of(&mut s, "heave");
    assert!((heave - exact).abs() <= 1e-13 * exact, "{heave} {exact}");
    assert!(get_of(&mut s, "roll").abs() < 1e-18);
    // Higher orders are ignored with a warning; a non-input is refused.
    assert_eq!(
        s.set_real_input_derivatives(&vrs[..1], &[2], &[1.0])
            .unwrap(),
        Status::Warning
    );
    let heave_vr = vr_of(Model::Chassis, "heave");
    assert!(refusal(s.set_real_input_derivatives(&[heave_vr], &[1], &[1.0])).contains("heave"));
}

#[test]
fn bad_chassis_input_is_refused_by_name() {
    let mut s = slave_of(Model::Chassis);
    s.setup_experiment(None, 0.0, None).unwrap();
    for (name, bad) in [
        ("mass", 0.0),
        ("mass", f64::NAN),
        ("roll_inertia", -400.0),
        ("pitch_inertia", f64::INFINITY),
        ("a", -1.0),
        ("force_fl", f64::NAN),
        ("force_rr", f64::INFINITY),
    ] {
        let message = refusal(s.set_real(&[vr_of(Model::Chassis, name)], &[bad]));
        assert!(message.contains(name), "{message}");
    }
    // A wheelbase of zero passes each value's check and is refused at
    // the end of initialization, naming b.
    set_of(&mut s, "a", 0.0);
    set_of(&mut s, "b", 0.0);
    s.enter_initialization_mode().unwrap();
    let message = refusal(s.exit_initialization_mode());
    assert!(
        message.contains("b") && message.contains("wheelbase"),
        "{message}"
    );
    set_of(&mut s, "b", 1.3);
    s.exit_initialization_mode().unwrap();
    let message = refusal(s.set_real(&[vr_of(Model::Chassis, "mass")], &[1000.0]));
    assert!(message.contains("fixed parameter"), "{message}");
    // The chassis offers no output or directional derivatives.
    let heave = vr_of(Model::Chassis, "heave");
    let mut out = [0.0];
    assert!(refusal(s.get_real_output_derivatives(&[heave], &[1], &mut out)).contains("chassis"));
    assert!(
        refusal(s.partials(&[heave], &[vr_of(Model::Chassis, "force_fl")])).contains("chassis")
    );
    // Forces large enough to overflow the motion are a discard, named.
    set_of(&mut s, "force_fl", 1e307);
    let e = s.do_step(0.0, 1e3).unwrap_err();
    assert_eq!(e.status, Status::Discard, "{}", e.message);
    assert!(s.terminate_requested());
}

#[test]
fn a_chassis_state_restores_and_continues_to_the_bit() {
    let mut s = started(Model::Chassis, &[("force_fl", 300.0), ("force_rr", -120.0)]);
    s.set_real_input_derivatives(&[vr_of(Model::Chassis, "force_fr")], &[1], &[50.0])
        .unwrap();
    for k in 0..7 {
        s.do_step(k as f64 * 1e-2, 1e-2).unwrap();
    }
    let saved = s.get_fmu_state(None).unwrap();
    let bytes = s.serialize_fmu_state(saved).unwrap();
    let run = |s: &mut Slave| {
        set_of(s, "force_rl", 80.0);
        s.do_step(0.07, 0.03).unwrap();
        [
            "heave",
            "roll_rate",
            "displacement_rr",
            "rms_weighted_seat_acceleration",
            "seat_vibration_dose_value",
        ]
        .map(|n| get_of(s, n))
    };
    let first = run(&mut s);
    s.set_fmu_state(saved).unwrap();
    assert_eq!(run(&mut s), first);
    let mut other = slave_of(Model::Chassis);
    let restored = other.deserialize_fmu_state(&bytes, None).unwrap();
    other.set_fmu_state(restored).unwrap();
    assert_eq!(run(&mut other), first);
    // A corner does not take a chassis's state.
    let mut corner = slave_of(Model::Corner);
    assert!(refusal(corner.deserialize_fmu_state(&bytes, None)).contains("GUID"));
    // Nor does a chassis take corrupted bytes.
    let mut cut = bytes.clone();
    cut.truncate(bytes.len() - 8);
    assert!(other.deserialize_fmu_state(&cut, None).is_err());
}

/// The full car as a master steps it: four corners on the chassis, joined
/// by force and motion at each communication step (Jacobi). With the
/// default chassis (front and rear decouple) and the same road under
/// every wheel, each corner carries a quarter of the body as the quarter
/// car's body: the car comes to the quarter car as the step shrinks.
#[test]
fn a_decoupled_car_of_four_corners_rides_as_the_quarter_car() {
    let mut quarter_car = initialized().0;
    quarter_car.do_step(0.0, 1.0).unwrap();
    let reference = get(&mut quarter_car, "rms_suspension_deflection");
    let reference_heave = get(&mut quarter_car, "x_s");
    let error_at = |h: f64| {
        let mut chassis = started(Model::Chassis, &[]);
        let mut corners: Vec<Slave> = (0..4).map(|_| started(Model::Corner, &[])).collect();
        let steps = (1.0 / h).round() as usize;
        for k in 0..steps {
            let t = k as f64 * h;
            for (i, corner) in corners.iter_mut().enumerate() {
                let suffix = ["fl", "fr", "rl", "rr"][i];
                let z = get_of(&mut chassis, &format!("displacement_{suffix}"));
                let v = get_of(&mut chassis, &format!("velocity_{suffix}"));
                set_of(corner, "body_displacement", z);
                set_of(corner, "body_velocity", v);
                let force = get_of(corner, "body_force");
                set_of(&mut chassis, FORCES[i], force);
            }
            for corner in corners.iter_mut() {
                corner.do_step(t, h).unwrap();
            }
            chassis.do_step(t, h).unwrap();
        }
        let deflections: Vec<f64> = corners
            .iter_mut()
            .map(|c| get_of(c, "rms_suspension_deflection"))
            .collect();
        // The car is symmetric: the four corners agree to rounding.
        for d in &deflections {
            assert!((d - deflections[0]).abs() <= 1e-12 * deflections[0]);
        }
        let heave = get_of(&mut chassis, "heave");
        assert!(get_of(&mut chassis, "roll").abs() < 1e-15);
        (
            ((deflections[0] - reference) / reference).abs(),
            (heave - reference_heave).abs(),
        )
    };
    let (coarse, fine) = (error_at(1e-3), error_at(2.5e-4));
    assert!(fine.0 < 1e-2, "{fine:?}");
    assert!(fine.0 < coarse.0 / 2.5, "{coarse:?} -> {fine:?}");
    assert!(fine.1 < coarse.1, "{coarse:?} -> {fine:?}");
}

/// A Co-Simulation state of the chassis written before it had Model
/// Exchange (format 6, commit 3920e17: the run of
/// [`a_chassis_state_restores_and_continues_to_the_bit`] saved after its 7
/// steps). Its GUID was that of the variables then; under this FMU's
/// header of format 6 (still read) its payload loads, and the run
/// continues as a fresh one.
#[test]
fn a_chassis_co_simulation_state_of_format_6_before_model_exchange_still_loads() {
    let old = include_bytes!("chassis_cs_state_3920e17.bin");
    assert_eq!(&old[..8], crate::snapshot::MAGIC);
    assert_eq!(u32::from_le_bytes(old[8..12].try_into().unwrap()), 6);
    let guid_len = u32::from_le_bytes(old[12..16].try_into().unwrap()) as usize;
    let payload = &old[16 + guid_len + 12..];
    let token = guid(Model::Chassis);
    let mut bytes = Vec::new();
    bytes.extend_from_slice(crate::snapshot::MAGIC);
    bytes.extend_from_slice(&crate::snapshot::OLDEST_READ.to_le_bytes());
    bytes.extend_from_slice(&(token.len() as u32).to_le_bytes());
    bytes.extend_from_slice(token.as_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crate::snapshot::crc32(payload).to_le_bytes());
    bytes.extend_from_slice(payload);
    let mut fresh = started(Model::Chassis, &[("force_fl", 300.0), ("force_rr", -120.0)]);
    fresh
        .set_real_input_derivatives(&[vr_of(Model::Chassis, "force_fr")], &[1], &[50.0])
        .unwrap();
    for k in 0..7 {
        fresh.do_step(k as f64 * 1e-2, 1e-2).unwrap();
    }
    let mut old_run = slave_of(Model::Chassis);
    let restored = old_run.deserialize_fmu_state(&bytes, None).unwrap();
    old_run.set_fmu_state(restored).unwrap();
    let run = |s: &mut Slave| {
        set_of(s, "force_rl", 80.0);
        s.do_step(0.07, 0.03).unwrap();
        [
            "heave",
            "roll_rate",
            "displacement_rr",
            "rms_weighted_seat_acceleration",
            "seat_vibration_dose_value",
        ]
        .map(|n| get_of(s, n).to_bits())
    };
    assert_eq!(run(&mut old_run), run(&mut fresh));
}
