//! Explicit Runge–Kutta masters at fixed steps keep their order when they
//! complete their steps, and converge when they do not.

use super::*;

/// An explicit Runge–Kutta method: nodes c, matrix a (lower triangular),
/// weights b.
struct Tableau {
    c: &'static [f64],
    a: &'static [&'static [f64]],
    b: &'static [f64],
}

const RK4: Tableau = Tableau {
    c: &[0.0, 0.5, 0.5, 1.0],
    a: &[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    b: &[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
};

const HEUN: Tableau = Tableau {
    c: &[0.0, 1.0],
    a: &[&[], &[1.0]],
    b: &[0.5, 0.5],
};

type States = [f64; CONTINUOUS_STATES];

/// Integrates `model` to `t_end` at the fixed step `h` (no events),
/// calling `complete_step` after every step when `complete`.
fn explicit(model: &mut ModelExchange, method: &Tableau, t_end: f64, h: f64, complete: bool) {
    let steps = ((t_end - model.time()) / h).round() as usize;
    let t0 = model.time();
    let mut x = *model.states();
    for n in 0..steps {
        let t = t0 + n as f64 * h;
        let mut k: Vec<States> = Vec::new();
        for (i, c) in method.c.iter().enumerate() {
            let stage: States = std::array::from_fn(|j| {
                x[j] + h * method.a[i]
                    .iter()
                    .zip(&k)
                    .map(|(a, k)| a * k[j])
                    .sum::<f64>()
            });
            model.set_time(t + c * h).unwrap();
            model.set_states(&stage).unwrap();
            k.push(model.derivatives().unwrap());
        }
        x = std::array::from_fn(|j| {
            x[j] + h * method.b.iter().zip(&k).map(|(b, k)| b * k[j]).sum::<f64>()
        });
        model.set_time(t0 + (n + 1) as f64 * h).unwrap();
        model.set_states(&x).unwrap();
        if complete {
            model.complete_step();
        }
    }
}

/// [`explicit`] with RK4.
pub(super) fn explicit_rk4(model: &mut ModelExchange, t_end: f64, h: f64, complete: bool) {
    explicit(model, &RK4, t_end, h, complete);
}

/// The six time averages of `o`.
fn averages(o: &Outputs) -> [f64; 6] {
    [
        o.rms.body_acceleration,
        o.rms.suspension_deflection,
        o.rms.tire_deflection,
        o.objective,
        o.comfort.unwrap().rms_weighted_body_acceleration,
        o.rms_dynamic_tire_load_ratio,
    ]
}

/// The exact co-simulation's time averages at `t_end` (tolerance 1e-12).
fn exact(c: &SimulationConfig, t_end: f64) -> [f64; 6] {
    let mut sim = Simulator::new(SimulationConfig {
        tolerance: 1e-12,
        ..c.clone()
    })
    .unwrap();
    sim.advance_to(t_end).unwrap();
    averages(&sim.outputs())
}

/// The largest relative error of the time averages of `method` at `h`.
fn error(
    c: &SimulationConfig,
    reference: &[f64; 6],
    method: &Tableau,
    t_end: f64,
    h: f64,
    complete: bool,
) -> f64 {
    let mut model = ModelExchange::new(c.clone()).unwrap();
    explicit(&mut model, method, t_end, h, complete);
    averages(&model.outputs())
        .iter()
        .zip(reference)
        .map(|(a, b)| relative(*a, *b))
        .fold(0.0, f64::max)
}

/// The errors at `steps` and the ratios of consecutive ones.
fn convergence(tau: f64, method: &Tableau, steps: &[f64], complete: bool) -> (Vec<f64>, Vec<f64>) {
    let c = config(Variant::Tdvass, tau, 5386.0, RoadSpec::paper_harmonic());
    let t_end = 1.0;
    let reference = exact(&c, t_end);
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| error(&c, &reference, method, t_end, h, complete))
        .collect();
    let ratios = errors.windows(2).map(|w| w[0] / w[1]).collect();
    (errors, ratios)
}

#[test]
fn rk4_completing_its_steps_converges_at_fourth_order_with_the_delay_beyond_the_step() {
    let (errors, ratios) = convergence(0.011, &RK4, &[1e-3, 5e-4, 2.5e-4], true);
    assert!(ratios.iter().all(|&r| r >= 11.0), "{errors:?} {ratios:?}");
}

#[test]
fn rk4_completing_its_steps_converges_at_fourth_order_with_a_short_delay() {
    let (errors, ratios) = convergence(2e-4, &RK4, &[1e-4, 5e-5, 2.5e-5], true);
    assert!(ratios.iter().all(|&r| r >= 11.0), "{errors:?} {ratios:?}");
}

#[test]
fn rk4_completing_its_steps_converges_at_fourth_order_with_the_delay_inside_the_step() {
    let (errors, ratios) = convergence(1e-4, &RK4, &[8e-4, 4e-4, 2e-4], true);
    assert!(ratios.iter().all(|&r| r >= 11.0), "{errors:?} {ratios:?}");
}

#[test]
fn heun_completing_its_steps_converges_at_second_order() {
    // Below 3e-5 s: at longer steps a higher-order term of Heun's own
    // error changes the sign of some averages' errors (measured without
    // the delay too).
    let (errors, ratios) = convergence(0.011, &HEUN, &[1.5625e-5, 7.8125e-6, 3.90625e-6], true);
    assert!(ratios.iter().all(|&r| r >= 3.4), "{errors:?} {ratios:?}");
}

#[test]
fn rk4_that_never_completes_a_step_stays_within_1e_5() {
    let (errors, _) = convergence(0.011, &RK4, &[1e-3], false);
    assert!(errors[0] < 1e-5, "{errors:?}");
}
