use super::*;

#[test]
fn with_the_default_pitch_inertia_front_and_rear_decouple() {
    let p = ChassisParams::default();
    // A force at the front axle, the same on both sides (no roll).
    let accelerations = p.accelerations(&[100.0, 100.0, 0.0, 0.0]);
    let at = |corner| {
        let (x, y) = p.position(corner);
        accelerations[0] + x * accelerations[1] + y * accelerations[2]
    };
    assert!(at(Corner::RearLeft).abs() < 1e-15 && at(Corner::RearRight).abs() < 1e-15);
    // Each front corner carries a quarter of the mass: 345 kg.
    assert!((at(Corner::FrontLeft) - 100.0 / 345.0).abs() < 1e-15);
    // A force on one side rolls the body.
    let one_side = p.accelerations(&[100.0, 0.0, 0.0, 0.0]);
    assert!(one_side[2] > 0.0);
}

#[test]
fn the_step_is_exact_for_forces_linear_in_time_however_it_is_split() {
    let p = ChassisParams::default();
    let (forces, rates) = ([120.0, -40.0, 75.0, 10.0], [300.0, 0.0, -50.0, 20.0]);
    let mut whole = Chassis::new(p, 0.0).unwrap();
    whole.set_forces(forces, rates).unwrap();
    whole.advance_to(0.4).unwrap();
    let mut split = Chassis::new(p, 0.0).unwrap();
    split.set_forces(forces, rates).unwrap();
    for i in 1..=37 {
        split.advance_to(0.4 * i as f64 / 37.0).unwrap();
    }
    let alpha0 = p.accelerations(&forces);
    let alpha1 = p.accelerations(&rates);
    let t = 0.4;
    for k in 0..3 {
        let exact = alpha0[k] * t * t / 2.0 + alpha1[k] * t * t * t / 6.0;
        let (a, b) = (whole.outputs().position[k], split.outputs().position[k]);
        assert!(
            (a - exact).abs() <= 1e-15 * exact.abs().max(1e-12),
            "{k}: {a} {exact}"
        );
        assert!(
            (b - exact).abs() <= 1e-13 * exact.abs().max(1e-12),
            "{k}: {b} {exact}"
        );
        // ∫ (α0 + α1 s)² over [0, t], as an RMS.
        let integral = alpha0[k] * alpha0[k] * t
            + alpha0[k] * alpha1[k] * t * t
            + alpha1[k] * alpha1[k] * t * t * t / 3.0;
        let rms = (integral / t).sqrt();
        let got = split.outputs().rms_acceleration[k];
        assert!((got - rms).abs() <= 1e-13 * rms, "{k}: {got} {rms}");
    }
    // The forces went on along their rates.
    assert!((whole.forces[0] - (120.0 + 300.0 * 0.4)).abs() < 1e-12);
    let (z, v) = whole.attachment(Corner::RearRight);
    let (x, y) = p.position(Corner::RearRight);
    let o = whole.outputs();
    assert!((z - (o.position[0] + x * o.position[1] + y * o.position[2])).abs() < 1e-15);
    assert!((v - (o.rate[0] + x * o.rate[1] + y * o.rate[2])).abs() < 1e-15);
}

#[test]
fn the_seat_filter_and_its_integrals_agree_with_a_fine_integration() {
    // A seat acceleration that is a sum of held steps: the W_k filter
    // stepped exactly, against RK4 at a hundredth of the step.
    let p = ChassisParams::default();
    let mut chassis = Chassis::new(p, 0.0).unwrap();
    let wk = wk_state_space();
    let mut w = SVector::<f64, WK_STATES>::zeros();
    let (mut square, mut fourth) = (0.0, 0.0);
    let h = 1e-3;
    let sub = 100;
    for step in 0..2000 {
        let phase = step as f64 * h;
        let f = 400.0 * (7.0 * phase).sin() + 150.0 * (31.0 * phase).cos();
        chassis
            .set_forces([f, 0.5 * f, -0.3 * f, 0.2 * f], [0.0; 4])
            .unwrap();
        chassis.advance_to((step + 1) as f64 * h).unwrap();
        let seat = {
            let a = p.accelerations(&[f, 0.5 * f, -0.3 * f, 0.2 * f]);
            a[0] + p.seat_x * a[1] + p.seat_y * a[2]
        };
        let dt = h / sub as f64;
        let rate = |w: &SVector<f64, WK_STATES>| wk.derivative(w, seat);
        for _ in 0..sub {
            let aw0 = wk.weighted_acceleration(&w, seat);
            let k1 = rate(&w);
            let k2 = rate(&(w + k1 * (dt / 2.0)));
            let k3 = rate(&(w + k2 * (dt / 2.0)));
            let k4 = rate(&(w + k3 * dt));
            w += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
            let aw1 = wk.weighted_acceleration(&w, seat);
            // Trapezoid on the fine grid.
            square += 0.5 * dt * (aw0 * aw0 + aw1 * aw1);
            fourth += 0.5 * dt * (aw0.powi(4) + aw1.powi(4));
        }
    }
    let o = chassis.outputs();
    let rms = (square / 2.0).sqrt();
    let dose = fourth.sqrt().sqrt();
    assert!(
        (o.rms_weighted_seat_acceleration - rms).abs() < 1e-6 * rms,
        "{} {rms}",
        o.rms_weighted_seat_acceleration
    );
    assert!(
        (o.seat_vibration_dose_value - dose).abs() < 1e-6 * dose,
        "{} {dose}",
        o.seat_vibration_dose_value
    );
    let fine = wk.weighted_acceleration(&w, o.seat_acceleration);
    assert!((o.weighted_seat_acceleration - fine).abs() < 1e-9 * fine.abs().max(1.0));
}

#[test]
fn bad_parameters_and_inputs_are_refused_by_name() {
    for (params, name) in [
        (
            ChassisParams {
                mass: 0.0,
                ..ChassisParams::default()
            },
            "mass",
        ),
        (
            ChassisParams {
                pitch_inertia: -1.0,
                ..ChassisParams::default()
            },
            "pitch_inertia",
        ),
        (
            ChassisParams {
                roll_inertia: f64::NAN,
                ..ChassisParams::default()
            },
            "roll_inertia",
        ),
        (
            ChassisParams {
                track_rear: 0.0,
                ..ChassisParams::default()
            },
            "track_rear",
        ),
        (
            ChassisParams {
                a: -0.1,
                ..ChassisParams::default()
            },
            "a",
        ),
        (
            ChassisParams {
                seat_y: f64::INFINITY,
                ..ChassisParams::default()
            },
            "seat_y",
        ),
    ] {
        let e = Chassis::new(params, 0.0).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
    let mut chassis = Chassis::new(ChassisParams::default(), 0.0).unwrap();
    let e = chassis
        .set_forces([0.0, f64::NAN, 0.0, 0.0], [0.0; 4])
        .unwrap_err();
    assert!(e.to_string().contains("force_fr"), "{e}");
    let e = chassis
        .set_forces([0.0; 4], [0.0, 0.0, 0.0, f64::INFINITY])
        .unwrap_err();
    assert!(e.to_string().contains("force_rr"), "{e}");
    chassis.advance_to(0.1).unwrap();
    assert!(
        chassis
            .advance_to(0.05)
            .unwrap_err()
            .to_string()
            .contains("t_end")
    );
    assert_eq!(chassis.outputs().position, [0.0; 3]);
}

#[test]
fn a_saved_motion_restores_and_continues_bit_for_bit() {
    let p = ChassisParams::default();
    let mut chassis = Chassis::new(p, 0.5).unwrap();
    chassis
        .set_forces([120.0, -40.0, 75.0, 10.0], [300.0, 0.0, -50.0, 20.0])
        .unwrap();
    for i in 1..=20 {
        chassis.advance_to(0.5 + 1e-3 * i as f64).unwrap();
    }
    let mut w = ByteWriter::default();
    chassis.write_motion(&mut w);
    let mut r = ByteReader::new(&w.bytes);
    let mut restored = Chassis::read_motion(p, &mut r).unwrap();
    assert!(r.is_empty());
    for c in [&mut chassis, &mut restored] {
        c.set_forces([10.0, 20.0, 30.0, 40.0], [0.0; 4]).unwrap();
        c.advance_to(0.6).unwrap();
    }
    assert_eq!(
        format!("{:?}", chassis.outputs()),
        format!("{:?}", restored.outputs())
    );
    // Truncated or non-finite bytes are refused.
    assert!(Chassis::read_motion(p, &mut ByteReader::new(&w.bytes[..40])).is_err());
    let mut bad = w.bytes.clone();
    bad[16..24].copy_from_slice(&f64::NAN.to_bits().to_le_bytes());
    assert!(Chassis::read_motion(p, &mut ByteReader::new(&bad)).is_err());
}

/// A chassis at `t0` in a state away from rest (every state nonzero), the
/// forces `forces` held.
fn moving(forces: [f64; 4], t0: f64) -> Chassis {
    let mut chassis = Chassis::new(ChassisParams::default(), 0.0).unwrap();
    chassis.set_forces(forces, [0.0; 4]).unwrap();
    chassis.set_time(t0).unwrap();
    let x: [f64; CHASSIS_STATES] = std::array::from_fn(|i| match i {
        0..3 => 1e-3 * (i as f64 + 1.0),
        3..6 => -2e-2 * (i as f64 - 2.5),
        FILTER_AT..INTEGRALS_AT => 3e-2 * ((i as f64).sin()),
        _ => 1e-3 * i as f64,
    });
    chassis.set_states(&x).unwrap();
    chassis
}

#[test]
fn the_model_exchange_rates_are_the_derivatives_of_the_exact_motion() {
    let forces = [420.0, -130.0, 260.0, 75.0];
    let p = ChassisParams::default();
    let chassis = moving(forces, 0.3);
    let dx = chassis.rates();
    // The positions' rates are the rates, theirs the accelerations of the
    // forces, to the bit.
    assert_eq!(dx[..3], chassis.states()[3..6]);
    assert_eq!(dx[3..6], p.accelerations(&forces));
    // Each state's rate is the slope of Co-Simulation's exact step under
    // the same held forces: a forward difference over h and h/2,
    // extrapolated (error O(h²)).
    let after = |h: f64| {
        let mut c = chassis.clone();
        c.advance_to(0.3 + h).unwrap();
        c.states()
    };
    let (h, x0) = (1e-7, chassis.states());
    let (full, half) = (after(h), after(h / 2.0));
    for i in 0..CHASSIS_STATES {
        let slope = 2.0 * (half[i] - x0[i]) / (h / 2.0) - (full[i] - x0[i]) / h;
        let scale = dx[i].abs().max(1e-3);
        assert!(
            (slope - dx[i]).abs() <= 1e-6 * scale,
            "{}: {slope} {}",
            CHASSIS_STATE_NAMES[i],
            dx[i]
        );
    }
}

#[test]
fn model_exchange_integrated_by_rk4_follows_the_exact_step() {
    // Held forces, changed every 0.1 s: the classical Runge–Kutta method
    // on `rates` against `advance_to` over 0.5 s, all 19 states.
    let p = ChassisParams::default();
    let mut exact = Chassis::new(p, 0.0).unwrap();
    let mut me = Chassis::new(p, 0.0).unwrap();
    let h = 1e-4;
    let rates_at = |c: &mut Chassis, x: &[f64; CHASSIS_STATES]| {
        c.set_states(x).unwrap();
        c.rates()
    };
    for segment in 0..5 {
        let s = segment as f64;
        let forces = [
            300.0 * (1.0 + s).sin(),
            -150.0 + 40.0 * s,
            200.0 * (2.0 * s).cos(),
            90.0 - 35.0 * s,
        ];
        exact.set_forces(forces, [0.0; 4]).unwrap();
        me.set_forces(forces, [0.0; 4]).unwrap();
        for k in 1..=1000 {
            let t = 0.1 * s + h * k as f64;
            exact.advance_to(t).unwrap();
            let x = me.states();
            let add = |a: &[f64; CHASSIS_STATES], b: &[f64; CHASSIS_STATES], c: f64| {
                std::array::from_fn::<f64, CHASSIS_STATES, _>(|i| a[i] + c * b[i])
            };
            let k1 = rates_at(&mut me, &x);
            let k2 = rates_at(&mut me, &add(&x, &k1, h / 2.0));
            let k3 = rates_at(&mut me, &add(&x, &k2, h / 2.0));
            let k4 = rates_at(&mut me, &add(&x, &k3, h));
            let next: [f64; CHASSIS_STATES] = std::array::from_fn(|i| {
                x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
            me.set_time(t).unwrap();
            me.set_states(&next).unwrap();
        }
    }
    let (a, b) = (exact.states(), me.states());
    for i in 0..CHASSIS_STATES {
        assert!(
            (a[i] - b[i]).abs() <= 1e-9 * a[i].abs().max(1e-6),
            "{}: {} {}",
            CHASSIS_STATE_NAMES[i],
            a[i],
            b[i]
        );
    }
    // The outputs built from them agree as closely.
    let (oa, ob) = (exact.outputs(), me.outputs());
    assert_eq!(oa.time, ob.time);
    assert_eq!(oa.acceleration, ob.acceleration);
    for (x, y) in [
        (
            oa.rms_weighted_seat_acceleration,
            ob.rms_weighted_seat_acceleration,
        ),
        (oa.seat_vibration_dose_value, ob.seat_vibration_dose_value),
        (oa.rms_acceleration[1], ob.rms_acceleration[1]),
    ] {
        assert!((x - y).abs() <= 1e-9 * x, "{x} {y}");
    }
}

#[test]
fn the_model_exchange_states_round_trip_and_refusals_name_the_value() {
    let mut chassis = moving([100.0, 200.0, -300.0, 50.0], 0.25);
    let x = chassis.states();
    // Set as they are read: the same bits, states, rates and outputs.
    let (rates, outputs) = (chassis.rates(), format!("{:?}", chassis.outputs()));
    chassis.set_states(&x).unwrap();
    assert_eq!(chassis.states().map(f64::to_bits), x.map(f64::to_bits));
    assert_eq!(chassis.rates(), rates);
    assert_eq!(format!("{:?}", chassis.outputs()), outputs);
    let o = chassis.outputs();
    assert_eq!(o.position[..], x[..3]);
    assert_eq!(o.rate[..], x[3..6]);
    // Through the saved motion too.
    let mut w = ByteWriter::default();
    chassis.write_motion(&mut w);
    let copy = Chassis::read_motion(*chassis.params(), &mut ByteReader::new(&w.bytes)).unwrap();
    assert_eq!(copy.states().map(f64::to_bits), x.map(f64::to_bits));
    assert_eq!(copy.rates(), rates);
    // Refused, by index, name and value, changing nothing.
    for (i, bad) in [(0, f64::NAN), (7, f64::INFINITY), (18, f64::NEG_INFINITY)] {
        let mut values = x;
        values[i] = bad;
        let e = chassis.set_states(&values).unwrap_err().to_string();
        let expected = format!(
            "continuous state {i} (`{}`) = {bad} is not finite",
            CHASSIS_STATE_NAMES[i]
        );
        assert!(e.contains(&expected), "{e}");
    }
    let e = chassis.set_states(&x[..18]).unwrap_err().to_string();
    assert!(
        e.contains("18 continuous states given, the chassis has 19"),
        "{e}"
    );
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.5] {
        let e = chassis.set_time(bad).unwrap_err().to_string();
        assert!(
            e.contains(&format!("invalid time {bad} s for `time`")),
            "{e}"
        );
    }
    assert_eq!(chassis.states().map(f64::to_bits), x.map(f64::to_bits));
    assert_eq!(chassis.time(), 0.25);
    // Back to the start time is allowed (the chassis keeps no history).
    chassis.set_time(0.0).unwrap();
    assert_eq!(chassis.outputs().rms_acceleration, [0.0; 3]);
}

/// The outputs the partials are of, in the order of [`partials_in_order`].
fn output_values(c: &Chassis) -> Vec<f64> {
    let o = c.outputs();
    let mut values: Vec<f64> = Corner::ALL.iter().map(|k| c.attachment(*k).0).collect();
    values.extend(Corner::ALL.iter().map(|k| c.attachment(*k).1));
    values.extend(o.acceleration);
    values.push(o.seat_acceleration);
    values.extend(o.rms_acceleration);
    values.extend([
        o.weighted_seat_acceleration,
        o.rms_weighted_seat_acceleration,
        o.seat_vibration_dose_value,
    ]);
    values
}

fn partials_in_order(p: &ChassisOutputPartials) -> Vec<ChassisGradient> {
    let mut g: Vec<ChassisGradient> = p.displacement.to_vec();
    g.extend(p.velocity);
    g.extend(p.acceleration);
    g.push(p.seat_acceleration);
    g.extend(p.rms_acceleration);
    g.extend([
        p.weighted_seat_acceleration,
        p.rms_weighted_seat_acceleration,
        p.seat_vibration_dose_value,
    ]);
    g
}

#[test]
fn each_corner_s_index_is_its_place_among_all() {
    for (i, corner) in Corner::ALL.iter().enumerate() {
        assert_eq!(corner.index(), i);
    }
}

#[test]
fn the_model_exchange_partials_agree_with_central_differences() {
    let mut c = moving([900.0, -400.0, 650.0, 300.0], 0.0);
    c.set_time(0.7).unwrap();
    let forces = [1200.0, -350.0, 500.0, 80.0];
    c.set_forces(forces, [0.0; 4]).unwrap();
    let rows = c.jacobian();
    let outputs = partials_in_order(&c.output_partials());
    let x = c.states();
    let nominals = chassis_nominals();
    let evaluate = |j: usize, delta: f64| {
        let mut copy = c.clone();
        if j < CHASSIS_STATES {
            let mut y = x;
            y[j] += delta;
            copy.set_states(&y).unwrap();
        } else {
            let mut f = forces;
            f[j - CHASSIS_STATES] += delta;
            copy.set_forces(f, [0.0; 4]).unwrap();
        }
        (copy.rates().to_vec(), output_values(&copy))
    };
    let close = |exact: f64, difference: f64, scale: f64| {
        (exact - difference).abs() <= 1e-6 * exact.abs().max(difference.abs()).max(1e-6 * scale)
    };
    let mut nonzero_force_partials = 0;
    for j in 0..CHASSIS_STATES + 4 {
        let size = if j < CHASSIS_STATES {
            x[j].abs().max(nominals[j])
        } else {
            forces[j - CHASSIS_STATES].abs().max(1.0)
        };
        let delta = 1e-4 * size;
        let (up, out_up) = evaluate(j, delta);
        let (down, out_down) = evaluate(j, -delta);
        let exact_of = |g: &ChassisGradient| {
            if j < CHASSIS_STATES {
                g.states[j]
            } else {
                g.forces[j - CHASSIS_STATES]
            }
        };
        let scale_of = |g: &ChassisGradient| {
            g.states
                .iter()
                .chain(&g.forces)
                .fold(0.0f64, |m, v| m.max(v.abs()))
        };
        for (i, row) in rows.iter().enumerate() {
            let difference = (up[i] - down[i]) / (2.0 * delta);
            let exact = exact_of(row);
            assert!(
                close(exact, difference, scale_of(row) * size),
                "d rate {i} / d {j}: {exact} vs {difference}"
            );
            nonzero_force_partials += usize::from(j >= CHASSIS_STATES && exact != 0.0);
        }
        for (k, g) in outputs.iter().enumerate() {
            let difference = (out_up[k] - out_down[k]) / (2.0 * delta);
            let exact = exact_of(g);
            assert!(
                close(exact, difference, scale_of(g) * size),
                "d output {k} / d {j}: {exact} vs {difference}"
            );
        }
    }
    assert!(nonzero_force_partials > 20, "{nonzero_force_partials}");
}
