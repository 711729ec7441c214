//! `input_extrapolation` of the vehicle's bonds: a corner continues its
//! body attachment, the chassis its forces, from the last two values set.

use super::*;
use crate::variables::guid;

/// A slave of `model` at t = 0 with `input_extrapolation = mode`.
fn started_with(model: Model, mode: i32) -> Slave {
    let logger = Logger::new(Box::new(|_, _, _| {}), false);
    let mut s = Slave::new(TEST_DIALECT, model, guid(model), logger);
    s.setup_experiment(None, 0.0, None).unwrap();
    s.set_integer(&[vr_of(model, "input_extrapolation")], &[mode])
        .unwrap();
    start(&mut s);
    s
}

fn set_body(s: &mut Slave, displacement: f64, velocity: f64) {
    let vrs = [
        vr_of(Model::Corner, "body_displacement"),
        vr_of(Model::Corner, "body_velocity"),
    ];
    s.set_real(&vrs, &[displacement, velocity]).unwrap();
}

const STEP: f64 = 1e-3;
/// The body's acceleration (m/s²) in the corner's tests.
const ACCELERATION: f64 = 2.0;

/// The body accelerating uniformly from rest: its attachment at `t`.
fn body_at(t: f64) -> (f64, f64) {
    (0.5 * ACCELERATION * t * t, ACCELERATION * t)
}

#[test]
fn the_corner_moves_its_attachment_on_the_extrapolated_velocity() {
    let mut extrapolating = started_with(Model::Corner, 1);
    let mut held = started_with(Model::Corner, 0);
    // The first step holds (one value): both alike to the bit.
    for s in [&mut extrapolating, &mut held] {
        set_body(s, 0.0, 0.0);
        s.do_step(0.0, STEP).unwrap();
    }
    assert_eq!(
        get_of(&mut extrapolating, "body_force").to_bits(),
        get_of(&mut held, "body_force").to_bits()
    );
    let (x1, v1) = body_at(STEP);
    set_body(&mut extrapolating, x1, v1);
    extrapolating.do_step(STEP, STEP).unwrap();
    // What extrapolation does, by hand on a holding corner: the step at
    // the line's mean velocity, then the attachment at its end.
    let slope = (v1 - 0.0) / STEP;
    set_body(&mut held, x1, v1 + 0.5 * slope * STEP);
    held.do_step(STEP, STEP).unwrap();
    let (x2, v2) = (x1 + (v1 + 0.5 * slope * STEP) * STEP, v1 + slope * STEP);
    set_body(&mut held, x2, v2);
    let (by_hand, extrapolated) = (
        get_of(&mut held, "body_force"),
        get_of(&mut extrapolating, "body_force"),
    );
    assert!(
        (by_hand - extrapolated).abs() <= 1e-12 * by_hand.abs(),
        "{by_hand} {extrapolated}"
    );
    // The exact attachment of the uniformly accelerating body.
    assert_eq!((x2, v2), body_at(2.0 * STEP));
    // Held instead, the force differs by the damper on the lost velocity.
    let mut plain = started_with(Model::Corner, 0);
    for k in 0..2 {
        let (x, v) = body_at(k as f64 * STEP);
        set_body(&mut plain, x, v);
        plain.do_step(k as f64 * STEP, STEP).unwrap();
    }
    let lag = (get_of(&mut plain, "body_force") - extrapolated).abs();
    assert!(lag > 1.0, "{lag}");
}

/// Sets the chassis's forces `forces` and steps from `t`.
fn chassis_step(s: &mut Slave, t: f64, forces: [f64; 4], rates: Option<[f64; 4]>) {
    let vrs = ["force_fl", "force_fr", "force_rl", "force_rr"].map(|n| vr_of(Model::Chassis, n));
    s.set_real(&vrs, &forces).unwrap();
    if let Some(rates) = rates {
        s.set_real_input_derivatives(&vrs, &[1; 4], &rates).unwrap();
    }
    s.do_step(t, STEP).unwrap();
}

fn chassis_motion(s: &mut Slave) -> [u64; 4] {
    [
        "heave",
        "pitch_rate",
        "roll",
        "rms_weighted_seat_acceleration",
    ]
    .map(|n| get_of(s, n).to_bits())
}

#[test]
fn the_chassis_ramps_each_force_along_its_last_two_values() {
    let (first, second) = ([300.0, -120.0, 80.0, 0.0], [310.0, -100.0, 80.0, 5.0]);
    let rates: [f64; 4] = std::array::from_fn(|i| (second[i] - first[i]) / STEP);
    let mut extrapolating = started_with(Model::Chassis, 1);
    let mut given = started_with(Model::Chassis, 0);
    chassis_step(&mut extrapolating, 0.0, first, None);
    chassis_step(&mut given, 0.0, first, None);
    assert_eq!(
        chassis_motion(&mut extrapolating),
        chassis_motion(&mut given)
    );
    chassis_step(&mut extrapolating, STEP, second, None);
    chassis_step(&mut given, STEP, second, Some(rates));
    let ramped = chassis_motion(&mut extrapolating);
    assert_eq!(ramped, chassis_motion(&mut given));
    // Held, the motion differs.
    let mut held = started_with(Model::Chassis, 0);
    chassis_step(&mut held, 0.0, first, None);
    chassis_step(&mut held, STEP, second, None);
    assert_ne!(chassis_motion(&mut held), ramped);
    // An input derivative given takes precedence.
    let other = [1.0, 2.0, 3.0, 4.0];
    chassis_step(&mut extrapolating, 2.0 * STEP, first, Some(other));
    chassis_step(&mut given, 2.0 * STEP, first, Some(other));
    assert_eq!(
        chassis_motion(&mut extrapolating),
        chassis_motion(&mut given)
    );
}

/// The history the extrapolation continues from is part of the FMU state:
/// a restored corner or chassis, in its own or a fresh instance, continues
/// to the bit.
#[test]
fn the_bond_history_is_saved_with_the_state() {
    for model in [Model::Corner, Model::Chassis] {
        let mut s = started_with(model, 1);
        let inputs = |k: usize| {
            let t = k as f64 * STEP;
            (body_at(t), [300.0 + 1e4 * t, -120.0, 80.0 * t, 0.0])
        };
        let step = |s: &mut Slave, k: usize| {
            let ((x, v), forces) = inputs(k);
            match model {
                Model::Chassis => chassis_step(s, k as f64 * STEP, forces, None),
                _ => {
                    set_body(s, x, v);
                    s.do_step(k as f64 * STEP, STEP).unwrap();
                }
            }
        };
        step(&mut s, 0);
        step(&mut s, 1);
        let saved = s.get_fmu_state(None).unwrap();
        let bytes = s.serialize_fmu_state(saved).unwrap();
        let run = |s: &mut Slave| {
            step(s, 2);
            step(s, 3);
            let name = if model == Model::Chassis {
                "heave"
            } else {
                "body_force"
            };
            get_of(s, name).to_bits()
        };
        let first = run(&mut s);
        s.set_fmu_state(saved).unwrap();
        assert_eq!(run(&mut s), first, "{model:?}");
        let mut fresh = started_with(model, 1);
        let restored = fresh.deserialize_fmu_state(&bytes, None).unwrap();
        fresh.set_fmu_state(restored).unwrap();
        assert_eq!(run(&mut fresh), first, "{model:?}");
    }
}
