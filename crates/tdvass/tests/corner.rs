//! The corner of a vehicle ([`Body::Attached`]): the suspension with the
//! body outside the model, its attachment point an input and the
//! suspension's force on the body an output. Under a body that is a point
//! mass m_s it is the paper's quarter car: coupled to one in a loop that
//! exchanges the force and the attachment's motion every `dt`, it follows
//! the quarter car to within an error that shrinks with `dt`.

use tdvass::exchange::ModelExchange;
use tdvass::model::inputs::BODY_ATTACHMENT;
use tdvass::model::{Body, V_H, V_S, V_T, X_H, X_S, X_T};
use tdvass::road::{RandomRoad, RoadClass, RoadShift, RoadSpec};
use tdvass::solver::INTEGRALS_AT;
use tdvass::solver::{Metrics, SimulationConfig, Simulator};

const DURATION: f64 = 2.0;

fn quarter_car_config() -> SimulationConfig {
    SimulationConfig {
        metrics: Metrics::RoadHolding,
        ..SimulationConfig::default()
    }
}

/// The corner under a point mass m_s, exchanging every `dt` (a Jacobi
/// loop: the corner moves the attachment at its last velocity, the body
/// moves under the last force, exactly); the corner at the end.
fn corner_under_point_mass(dt: f64) -> Simulator {
    let config = quarter_car_config();
    let mass = config.params.m_s;
    let mut corner = Simulator::new(SimulationConfig {
        body: Body::Attached,
        communication_step: dt,
        ..config
    })
    .unwrap();
    let (mut z, mut v) = (0.0, 0.0);
    let steps = (DURATION / dt).round() as u64;
    for i in 1..=steps {
        let acceleration = corner.body_force() / mass;
        corner.advance_to(i as f64 * dt).unwrap();
        z += v * dt + 0.5 * acceleration * dt * dt;
        v += acceleration * dt;
        corner.set_body_input(z, v).unwrap();
    }
    corner
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn a_corner_under_a_point_mass_is_the_quarter_car() {
    let mut quarter = Simulator::new(quarter_car_config()).unwrap();
    quarter.advance_to(DURATION).unwrap();
    let reference = quarter.outputs();
    let errors: Vec<[f64; 4]> = [1e-4, 2.5e-5]
        .iter()
        .map(|&dt| {
            let mut corner = corner_under_point_mass(dt);
            let o = corner.outputs();
            [
                relative(
                    o.rms.suspension_deflection,
                    reference.rms.suspension_deflection,
                ),
                relative(o.rms.tire_deflection, reference.rms.tire_deflection),
                relative(o.state[X_S], reference.state[X_S]),
                relative(o.state[X_T], reference.state[X_T]),
            ]
        })
        .collect();
    for (coarse, fine) in errors[0].iter().zip(&errors[1]) {
        // First order in dt (the loop's explicit exchange): a quarter of
        // the step, a third of the error or less (measured: a quarter;
        // 5e-4 at most at dt = 1e-4).
        assert!(*coarse < 1e-3, "{errors:?}");
        assert!(*fine < coarse / 3.0, "{errors:?}");
    }
}

#[test]
fn the_body_force_is_the_sprung_mass_times_its_acceleration() {
    let mut quarter = Simulator::new(quarter_car_config()).unwrap();
    quarter.advance_to(0.3).unwrap();
    let o = quarter.outputs();
    let force = quarter.body_force();
    let expected = quarter.plant().params.m_s * o.performance.body_acceleration;
    assert!(
        (force - expected).abs() <= 1e-12 * expected.abs().max(1.0),
        "{force} {expected}"
    );
}

#[test]
fn the_attachment_moves_at_its_velocity_and_bad_input_is_refused_by_name() {
    let mut corner = Simulator::new(SimulationConfig {
        body: Body::Attached,
        ..quarter_car_config()
    })
    .unwrap();
    corner.set_body_input(0.01, 0.2).unwrap();
    corner.advance_to(0.25).unwrap();
    let x = corner.state();
    assert!((x[X_S] - (0.01 + 0.2 * 0.25)).abs() < 1e-15, "{}", x[X_S]);
    for (z, v, name) in [
        (f64::NAN, 0.0, "body_displacement"),
        (0.0, f64::INFINITY, "body_velocity"),
        (1e9, 0.0, "body_displacement"),
    ] {
        let e = corner.set_body_input(z, v).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
    // A refused value changes nothing.
    assert_eq!(corner.state(), x);
    let mut quarter = Simulator::new(quarter_car_config()).unwrap();
    let e = quarter.set_body_input(0.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("body"), "{e}");
}

#[test]
fn a_wheel_behind_another_runs_the_same_course_later() {
    // From rest on a random road that is 0 until the delayed profile
    // starts, the system is time-invariant: the rear wheel's state at
    // t + delay is the front wheel's at t. Both choose the same step (the
    // probe runs on the road as it is), the delay a multiple of it: to
    // rounding (measured 8e-15 of the largest state).
    let front_config = SimulationConfig {
        road: RoadSpec::Iso8608(RandomRoad {
            class: RoadClass::D,
            speed: 20.0,
            ..RandomRoad::default()
        }),
        ..quarter_car_config()
    };
    let delay = 0.125;
    let rear_config = SimulationConfig {
        road_shift: RoadShift { delay, phase: 0.0 },
        ..front_config.clone()
    };
    let mut front = Simulator::new(front_config).unwrap();
    let mut rear = Simulator::new(rear_config).unwrap();
    for t in [0.4, 1.1, 2.0] {
        front.advance_to(t).unwrap();
        rear.advance_to(t + delay).unwrap();
        let (a, b) = (front.state(), rear.state());
        let scale = a.amax();
        assert_eq!(front.grid().step, rear.grid().step);
        assert!((a - b).amax() <= 1e-12 * scale, "{t}: {a} {b}");
    }
}

/// A corner's Model Exchange and the quarter car's at the same plant
/// state `x` (the corner's body coordinates from its input, its own
/// `x_s`, `v_s` states something else).
fn exchange_pair(tau: f64, x: [f64; 6]) -> (ModelExchange, ModelExchange) {
    let mut params = quarter_car_config().params;
    params.tau = tau;
    let config = SimulationConfig {
        params,
        ..quarter_car_config()
    };
    let mut quarter = ModelExchange::new(config.clone()).unwrap();
    let mut corner = ModelExchange::new(SimulationConfig {
        body: Body::Attached,
        ..config
    })
    .unwrap();
    let mut states = *quarter.states();
    states[..6].copy_from_slice(&x);
    quarter.set_states(&states).unwrap();
    states[X_S] = -0.37;
    states[V_S] = 2.9;
    corner.set_states(&states).unwrap();
    corner.set_body_input(x[X_S], x[V_S]).unwrap();
    (quarter, corner)
}

#[test]
fn the_corner_s_model_exchange_is_the_quarter_car_s_under_a_point_mass() {
    let x = [0.012, -0.31, 0.004, 0.52, -0.002, 0.17];
    for tau in [0.0, 0.011] {
        let (mut quarter, mut corner) = exchange_pair(tau, x);
        let (dq, dc) = (
            quarter.derivatives().unwrap(),
            corner.derivatives().unwrap(),
        );
        // The absorber's and the wheel's rates, and the integrands of SDD
        // and TDD, are the quarter car's to the bit; the attachment moves
        // at its velocity; the body's acceleration is the force over m_s.
        for i in [X_S, X_H, V_H, X_T, V_T, INTEGRALS_AT + 1, INTEGRALS_AT + 2] {
            assert_eq!(dc[i].to_bits(), dq[i].to_bits(), "tau {tau}, state {i}");
        }
        assert_eq!(dc[V_S], 0.0);
        let m_s = quarter.config().params.m_s;
        let acceleration = corner.body_force() / m_s;
        assert!(
            (acceleration - dq[V_S]).abs() <= 1e-14 * dq[V_S].abs(),
            "{acceleration} {}",
            dq[V_S]
        );
        // The partials: the body's columns move to the attachment input.
        let (jq, jc) = (quarter.jacobian(), corner.jacobian());
        for i in [X_H, V_H, X_T, V_T, INTEGRALS_AT + 1] {
            assert_eq!(
                jc.prescribed[i][BODY_ATTACHMENT],
                [jq.states[i][X_S], jq.states[i][V_S]],
                "row {i}"
            );
            assert_eq!([jc.states[i][X_S], jc.states[i][V_S]], [0.0, 0.0]);
            assert_eq!(jc.states[i][X_T], jq.states[i][X_T]);
        }
        assert_eq!(jq.prescribed[V_T][BODY_ATTACHMENT], [0.0, 0.0]);
    }
}

#[test]
fn a_corner_s_model_exchange_state_keeps_its_attachment() {
    let (_, mut corner) = exchange_pair(0.011, [0.01, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let bytes = corner.to_bytes();
    let (_, mut copy) = exchange_pair(0.011, [0.0; 6]);
    copy.restore(&bytes).unwrap();
    assert_eq!(copy.body_force().to_bits(), corner.body_force().to_bits());
    assert_eq!(copy.derivatives().unwrap(), corner.derivatives().unwrap());
    // A quarter car's state does not restore into a corner, nor the
    // other way.
    let (mut quarter, _) = exchange_pair(0.011, [0.0; 6]);
    let e = quarter.restore(&bytes).unwrap_err().to_string();
    assert!(e.contains("body attachment"), "{e}");
    let e = copy.restore(&quarter.to_bytes()).unwrap_err().to_string();
    assert!(e.contains("body attachment"), "{e}");
    for (z, v, name) in [
        (f64::NAN, 0.0, "body_displacement"),
        (0.0, 1e9, "body_velocity"),
    ] {
        let e = corner.set_body_input(z, v).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
    let e = quarter.set_body_input(0.0, 0.0).unwrap_err().to_string();
    assert!(e.contains("body"), "{e}");
}
