//! Section 3.3: the six verification points A1*..A6* (notes.md section 3),
//! by the spectrum of the delay equation and by a time simulation from
//! X0 = [0.01, 0, 0, 0, 0, 0] without road input.

use tdvass::Error;
use tdvass::analysis::spectrum::spectral_abscissa;
use tdvass::model::{Params, State, Variant};
use tdvass::road::RoadSpec;
use tdvass::solver::{SimulationConfig, Simulator};

const POINTS: [(&str, f64, f64, bool); 6] = [
    ("A1*", 40000.0, 0.03, true),
    ("A2*", -40000.0, 0.11, false),
    ("A3*", 40000.0, 0.15, false),
    ("A4*", -40000.0, 0.25, true),
    ("A5*", 40000.0, 0.3, true),
    ("A6*", -40000.0, 0.4, false),
];

/// Largest |x_s| over [from, to) sampled every 10 ms, or the divergence.
fn peak_body_displacement(sim: &mut Simulator, from: f64, to: f64) -> Result<f64, Error> {
    let mut peak = 0.0f64;
    let mut t = from;
    while t < to {
        t += 0.01;
        sim.advance_to(t)?;
        peak = peak.max(sim.state()[0].abs());
    }
    Ok(peak)
}

#[test]
fn six_points_by_spectrum_and_by_simulation() {
    for (label, g, tau, stable) in POINTS {
        let params = Params::with_controller(g, tau);
        let abscissa = spectral_abscissa(&params, Variant::Tdvass).unwrap();
        assert_eq!(
            abscissa < 0.0,
            stable,
            "{label}: spectral abscissa {abscissa}"
        );

        let mut sim = Simulator::new(SimulationConfig {
            params,
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
            road: RoadSpec::Harmonic {
                amplitude: 0.0,
                angular_frequency: 5.0,
            },
            max_internal_step: 1e-3,
            ..SimulationConfig::default()
        })
        .unwrap();
        let early = peak_body_displacement(&mut sim, 0.0, 3.0).unwrap();
        match peak_body_displacement(&mut sim, 3.0, 40.0) {
            Ok(_) => {
                let late = peak_body_displacement(&mut sim, 40.0, 43.0).unwrap();
                // The envelope follows e^{σ t}: over ~40 s a stable point
                // decays by far more than 10x, an unstable one grows.
                if stable {
                    assert!(late < 0.1 * early, "{label}: {early} -> {late}");
                } else {
                    assert!(late > 10.0 * early, "{label}: {early} -> {late}");
                }
            }
            Err(Error::Diverged { time, .. }) => {
                assert!(!stable, "{label} diverged at {time} s");
                assert!(sim.state().iter().all(|v| v.is_finite()));
            }
            Err(other) => panic!("{label}: {other}"),
        }
    }
}
