//! The exact partials agree with central differences of the derivatives
//! and outputs, in both tire modes and the three delay regimes.

use super::order::explicit_rk4;
use super::*;
use crate::exchange::{Gradient, OutputPartials};
use crate::model::Body;

/// The Real outputs of `o` in the order of [`partials_of`].
fn output_values(o: &Outputs) -> Vec<f64> {
    let c = o.comfort.unwrap();
    let r = o.road_holding.unwrap();
    vec![
        o.performance.body_acceleration,
        o.performance.suspension_deflection,
        o.performance.tire_deflection,
        o.road_displacement,
        o.control_force,
        o.rms.body_acceleration,
        o.rms.suspension_deflection,
        o.rms.tire_deflection,
        o.objective,
        c.weighted_body_acceleration,
        c.rms_weighted_body_acceleration,
        c.vibration_dose_value,
        o.dynamic_tire_load,
        o.rms_dynamic_tire_load_ratio,
        r.contact_loss_time,
        r.max_suspension_deflection,
        o.body_force,
    ]
}

fn partials_of(p: &OutputPartials) -> Vec<Gradient> {
    vec![
        p.body_acceleration,
        p.suspension_deflection,
        p.tire_deflection,
        p.road_displacement,
        p.control_force,
        p.rms_body_acceleration,
        p.rms_suspension_deflection,
        p.rms_tire_deflection,
        p.objective,
        p.weighted_body_acceleration,
        p.rms_weighted_body_acceleration,
        p.vibration_dose_value,
        p.dynamic_tire_load,
        p.rms_dynamic_tire_load_ratio,
        p.contact_loss_time,
        p.max_suspension_deflection,
        p.body_force,
    ]
}

/// A known of the partials.
#[derive(Debug, Clone, Copy)]
enum Known {
    State(usize),
    /// The road input `x_g`.
    Road,
    /// An input that prescribes coordinates (a corner's body attachment),
    /// and which of its values: 0 the position, 1 the velocity.
    Prescribed(usize, usize),
}

/// The knowns of `model`: the states, x_g where the road is the input, a
/// corner's body attachment. An integral still at 0 (a corner's of BA,
/// which is 0) is left out: the square root of the time averages has its
/// kink there, where the partial is taken as 0.
fn knowns_of(model: &ModelExchange) -> Vec<Known> {
    let at_kink = |j: usize| j >= INTEGRALS_AT && model.states()[j] == 0.0;
    let mut knowns: Vec<Known> = (0..CONTINUOUS_STATES)
        .filter(|&j| !at_kink(j))
        .map(Known::State)
        .collect();
    if model.road.is_input() {
        knowns.push(Known::Road);
    }
    for (i, value) in model.prescribed.iter().enumerate() {
        if value.is_some() {
            knowns.extend([Known::Prescribed(i, 0), Known::Prescribed(i, 1)]);
        }
    }
    knowns
}

/// The rates and outputs of `model` with `known` moved by `delta` (x_g
/// from `x_g`), on a copy: nothing is recorded.
fn evaluate(model: &ModelExchange, known: Known, delta: f64, x_g: f64) -> (Vec<f64>, Vec<f64>) {
    let mut copy = model.clone();
    match known {
        Known::State(j) => {
            let mut x = *copy.states();
            x[j] += delta;
            copy.set_states(&x).unwrap();
        }
        Known::Road => copy.set_road_input(x_g + delta).unwrap(),
        Known::Prescribed(i, k) => {
            let mut values = copy.prescribed(i).unwrap();
            values[k] += delta;
            copy.set_prescribed(i, values).unwrap();
        }
    }
    let outputs = output_values(&copy.outputs());
    (copy.derivatives().unwrap().to_vec(), outputs)
}

/// The partial of `g` with respect to `known`.
fn partial(g: &Gradient, known: Known) -> f64 {
    match known {
        Known::State(j) => g.states[j],
        Known::Road => g.road_input,
        Known::Prescribed(i, k) => g.prescribed[i][k],
    }
}

fn close(exact: f64, difference: f64, scale: f64) -> bool {
    (exact - difference).abs() <= 1e-6 * exact.abs().max(difference.abs()).max(1e-6 * scale)
}

/// Checks every partial of `model` at its point against a central
/// difference (with respect to x_g where the road is the input, there
/// `x_g`, and to a corner's body attachment).
fn check(model: &mut ModelExchange, x_g: f64) {
    let jacobian = model.jacobian();
    let partials = partials_of(&model.output_partials());
    let nominals = nominals();
    let row_scale: Vec<f64> = jacobian
        .states
        .iter()
        .map(|r| r.iter().fold(0.0f64, |m, v| m.max(v.abs())))
        .collect();
    for known in knowns_of(model) {
        let size = match known {
            Known::State(j) => model.states()[j].abs().max(nominals[j]),
            Known::Road => x_g.abs().max(1e-3),
            Known::Prescribed(i, k) => model.prescribed(i).unwrap()[k].abs().max(1e-3),
        };
        // Most partials are of functions linear in the known: a step far
        // above the rounding of the values (1e-4) costs nothing there.
        let delta = 1e-4 * size;
        let (rates_up, out_up) = evaluate(model, known, delta, x_g);
        let (rates_down, out_down) = evaluate(model, known, -delta, x_g);
        for i in 0..CONTINUOUS_STATES {
            let difference = (rates_up[i] - rates_down[i]) / (2.0 * delta);
            let row = Gradient {
                states: jacobian.states[i],
                road_input: jacobian.road_input[i],
                prescribed: jacobian.prescribed[i],
            };
            let exact = partial(&row, known);
            assert!(
                close(exact, difference, row_scale[i] * size),
                "d rate {i} / d {known:?}: {exact} vs {difference}"
            );
        }
        for (k, g) in partials.iter().enumerate() {
            let difference = (out_up[k] - out_down[k]) / (2.0 * delta);
            let exact = partial(g, known);
            let scale = g
                .states
                .iter()
                .chain(g.prescribed.iter().flatten())
                .fold(g.road_input.abs(), |m, v| m.max(v.abs()));
            assert!(
                close(exact, difference, scale * size),
                "d output {k} / d {known:?}: {exact} vs {difference}"
            );
        }
    }
}

/// A model after 0.3 s of a never-completing RK4 master at 1 ms, its time
/// moved on by `ahead` s (a stage inside the next step).
fn running(c: SimulationConfig, ahead: f64) -> ModelExchange {
    let mut model = ModelExchange::new(c).unwrap();
    if model.road.is_input() {
        // A step of the road at the start: the integrals grow from 0.
        model.set_road_input(0.01).unwrap();
    }
    explicit_rk4(&mut model, 0.3, 1e-3, false);
    model.set_time(0.3 + ahead).unwrap();
    model
}

#[test]
fn the_partials_agree_with_central_differences_for_every_delay() {
    for tau in [0.0, 2e-4, 0.011] {
        for variant in Variant::ALL {
            let mut model = running(
                config(variant, tau, 5386.0, RoadSpec::paper_harmonic()),
                7e-4,
            );
            check(&mut model, 0.0);
            if variant == Variant::Tdvass && tau == 2e-4 {
                // The delay inside the step: the delayed value depends on
                // the current state.
                let row = model.jacobian().states[V_T];
                assert_ne!(row[X_T], model.plant.a[(V_T, X_T)]);
            }
        }
    }
}

#[test]
fn the_partials_agree_with_central_differences_in_flight_and_with_the_road_input() {
    let c = SimulationConfig {
        tire_contact: TireContact::Unilateral,
        ..config(Variant::Tdvass, 2e-4, 5386.0, RoadSpec::Input)
    };
    let mut model = running(c, 7e-4);
    let x_g = 0.01;
    model.set_road_input(x_g).unwrap();
    check(&mut model, x_g);
    // Lift the wheel off: in flight the road drops out.
    let mut x = *model.states();
    x[X_T] = x_g + 2.0 * model.switching.tire_limit;
    x[V_T] = 0.3;
    model.set_states(&x).unwrap();
    assert!(matches!(
        model.update_discrete_states(),
        Some(ContactEvent::LiftOff { .. })
    ));
    model.set_time(model.time() + 3e-4).unwrap();
    // Off the largest |SDD| the event just recorded (a kink of that output).
    x[X_S] += 0.1 * (x[X_T] - x[X_S]);
    model.set_states(&x).unwrap();
    check(&mut model, x_g);
    assert!(
        model
            .jacobian()
            .road_input
            .iter()
            .take(6)
            .all(|v| *v == 0.0)
    );
}

#[test]
fn a_corner_s_partials_with_respect_to_its_body_attachment_agree_with_central_differences() {
    for (variant, tau, contact) in [
        (Variant::Tdvass, 2e-4, TireContact::Unilateral),
        (Variant::Pvass, 0.0, TireContact::Bilateral),
        (Variant::Tdvass, 0.011, TireContact::Bilateral),
    ] {
        let c = SimulationConfig {
            tire_contact: contact,
            body: Body::Attached,
            ..config(variant, tau, 5386.0, RoadSpec::Input)
        };
        let mut model = ModelExchange::new(c).unwrap();
        model.set_body_input(0.004, -0.03).unwrap();
        model.set_road_input(0.01).unwrap();
        explicit_rk4(&mut model, 0.3, 1e-3, false);
        model.set_time(0.3 + 7e-4).unwrap();
        check(&mut model, 0.01);
        let force = model.output_partials().body_force;
        // The suspension pulls the body back: its force falls as the
        // attachment rises or moves up.
        assert!(
            force.prescribed[0][0] < 0.0 && force.prescribed[0][1] < 0.0,
            "{force:?}"
        );
        assert_eq!((force.states[X_S], force.states[X_S + 1]), (0.0, 0.0));
    }
}
