//! The tolerance sets the internal step (`solver::accuracy`): every
//! reported metric of a run at `tolerance` 1e-4, 1e-6 and 1e-8 lies within
//! that tolerance (relative) of a converged reference, a run at a fixed
//! internal step of 1e-5 s; the time without contact within
//! `tolerance × duration`. The cases cover the three variants, the
//! harmonic road up to 60 rad/s, ISO 8608 classes A–E at 5–30 m/s, the
//! paper-compatible road, tau from 0 to 0.05 s (folded, inside the step,
//! whole steps) and both signs of g.

mod common;

use common::{harmonic, iso};
use tdvass::model::{Params, Variant};
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::accuracy::{MAX_TOLERANCE, check_tolerance};
use tdvass::solver::{DelayRegime, Metrics, Outputs, SimulationConfig, Simulator};

/// Simulated time of every case (s).
const DURATION: f64 = 8.0;
/// The reference's fixed internal step (s).
const REFERENCE_STEP: f64 = 1e-5;

struct Case {
    name: &'static str,
    variant: Variant,
    road: RoadSpec,
    g: f64,
    tau: f64,
}

fn paper_road() -> RoadSpec {
    RoadSpec::PaperCompatible {
        road: RandomRoad::default(),
        sample_interval: 0.1,
    }
}

fn cases() -> Vec<Case> {
    use Variant::{Cs, Pvass, Tdvass};
    let case = |name, variant, road, g, tau| Case {
        name,
        variant,
        road,
        g,
        tau,
    };
    vec![
        case("CS harmonic 5", Cs, harmonic(0.05, 5.0), 0.0, 0.0),
        case("PVASS harmonic 30", Pvass, harmonic(0.01, 30.0), 0.0, 0.0),
        case(
            "TDVASS harmonic 5",
            Tdvass,
            harmonic(0.05, 5.0),
            5386.0,
            2e-4,
        ),
        case(
            "TDVASS harmonic 60",
            Tdvass,
            harmonic(0.005, 60.0),
            5386.0,
            2e-4,
        ),
        case(
            "TDVASS harmonic 60, tau 0.05",
            Tdvass,
            harmonic(0.005, 60.0),
            2000.0,
            0.05,
        ),
        case(
            "TDVASS harmonic, g < 0",
            Tdvass,
            harmonic(0.05, 5.0),
            -3000.0,
            0.01,
        ),
        case(
            "TDVASS harmonic, tau 0",
            Tdvass,
            harmonic(0.05, 5.0),
            5386.0,
            0.0,
        ),
        case("CS ISO A 5 m/s", Cs, iso(RoadClass::A, 5.0), 0.0, 0.0),
        case(
            "PVASS ISO C 20 m/s",
            Pvass,
            iso(RoadClass::C, 20.0),
            0.0,
            0.0,
        ),
        case(
            "TDVASS ISO B 10 m/s",
            Tdvass,
            iso(RoadClass::B, 10.0),
            5386.0,
            2e-4,
        ),
        case(
            "TDVASS ISO D 30 m/s",
            Tdvass,
            iso(RoadClass::D, 30.0),
            2528.0,
            1.28e-4,
        ),
        case(
            "TDVASS ISO E 20 m/s, tau 0.02",
            Tdvass,
            iso(RoadClass::E, 20.0),
            4000.0,
            0.02,
        ),
        case(
            "TDVASS ISO C, g < 0, tau 0.0123",
            Tdvass,
            iso(RoadClass::C, 20.0),
            -2000.0,
            0.0123,
        ),
        case("CS paper road", Cs, paper_road(), 0.0, 0.0),
        case("TDVASS paper road", Tdvass, paper_road(), 2528.0, 1.28e-4),
        case(
            "TDVASS paper road, tau 0.05",
            Tdvass,
            paper_road(),
            3000.0,
            0.05,
        ),
    ]
}

fn config(case: &Case) -> SimulationConfig {
    SimulationConfig {
        params: Params {
            g: case.g,
            tau: case.tau,
            ..Params::default()
        },
        variant: case.variant,
        road: case.road.clone(),
        metrics: Metrics::Comfort,
        ..SimulationConfig::default()
    }
}

/// The outputs at the end of a run of `config`.
fn run(config: SimulationConfig) -> (Outputs, Simulator) {
    let mut sim = Simulator::new(config).expect("valid configuration");
    sim.advance_to(DURATION).expect("a stable case");
    (sim.outputs(), sim)
}

/// Every metric the tolerance covers, by name.
fn metrics(o: &Outputs) -> [(&'static str, f64); 8] {
    let comfort = o.comfort.expect("comfort on");
    let holding = o.road_holding.expect("road holding on");
    [
        ("RMS BA", o.rms.body_acceleration),
        ("RMS SDD", o.rms.suspension_deflection),
        ("RMS TDD", o.rms.tire_deflection),
        ("J", o.objective),
        ("a_w", comfort.rms_weighted_body_acceleration),
        ("VDV", comfort.vibration_dose_value),
        ("tire-load ratio", o.rms_dynamic_tire_load_ratio),
        ("max |SDD|", holding.max_suspension_deflection),
    ]
}

fn contact_loss_time(o: &Outputs) -> f64 {
    o.road_holding.expect("road holding on").contact_loss_time
}

#[test]
fn every_metric_is_within_the_tolerance_of_a_converged_reference() {
    let mut regimes = [false; 3];
    let mut worst = 0.0f64;
    for case in cases() {
        let (reference, _) = run(SimulationConfig {
            tolerance: MAX_TOLERANCE,
            max_internal_step: REFERENCE_STEP,
            ..config(&case)
        });
        for tolerance in [1e-4, 1e-6, 1e-8] {
            let (o, sim) = run(SimulationConfig {
                tolerance,
                ..config(&case)
            });
            regimes[match sim.grid().regime {
                DelayRegime::Folded => 0,
                DelayRegime::InsideStep { .. } => 1,
                DelayRegime::WholeSteps { .. } => 2,
            }] = true;
            let step = sim.grid().step;
            for ((name, value), (_, exact)) in metrics(&o).into_iter().zip(metrics(&reference)) {
                let error = (value - exact).abs() / exact.abs();
                worst = worst.max(error / tolerance);
                assert!(
                    error <= tolerance,
                    "{}: {name} at tolerance {tolerance} (h = {step} s): {value} against {exact}, relative error {error:e}",
                    case.name
                );
            }
            let (lost, exact) = (contact_loss_time(&o), contact_loss_time(&reference));
            assert!(
                (lost - exact).abs() <= tolerance * DURATION,
                "{}: contact loss time at tolerance {tolerance}: {lost} s against {exact} s",
                case.name
            );
        }
    }
    assert_eq!(regimes, [true; 3], "every delay regime is reached");
    println!("worst error / tolerance: {worst:.3}");
}

/// The largest |SDD| is located inside the steps: at tolerance 1e-8 it is
/// not below the largest of a dense sampling of SDD (every 1e-4 s, the
/// state there from the exact dense output), and above it by no more than
/// the tolerance plus what the sampling can miss (`(δ/2)² |SDD''| / 2`
/// with δ = 1e-4 s: 4.5e-6 relative for SDD at 60 rad/s).
#[test]
fn the_largest_deflection_matches_a_dense_sampling() {
    for case in cases().into_iter().filter(|c| c.name.contains("TDVASS")) {
        let mut sim = Simulator::new(SimulationConfig {
            tolerance: 1e-8,
            ..config(&case)
        })
        .unwrap();
        let mut sampled = 0.0f64;
        let samples = 80_000;
        for i in 1..=samples {
            sim.advance_to(DURATION * i as f64 / samples as f64)
                .unwrap();
            sampled = sampled.max(sim.outputs().performance.suspension_deflection.abs());
        }
        let located = sim
            .outputs()
            .road_holding
            .unwrap()
            .max_suspension_deflection;
        assert!(
            located >= sampled * (1.0 - 1e-8) && located <= sampled * (1.0 + 5e-6),
            "{}: located {located} against sampled {sampled}",
            case.name
        );
    }
}

#[test]
fn a_tolerance_out_of_range_is_refused_with_its_value() {
    for bad in [f64::NAN, 0.0, -1e-6, 0.5, f64::INFINITY, 1e-13] {
        let error = Simulator::new(SimulationConfig {
            tolerance: bad,
            ..SimulationConfig::default()
        })
        .expect_err("refused");
        let message = error.to_string();
        assert!(
            message.contains("`tolerance`") && message.contains(&bad.to_string()),
            "{bad}: {message}"
        );
        assert!(check_tolerance(bad).is_err());
    }
    let error = Simulator::new(SimulationConfig {
        max_internal_step: -1.0,
        ..SimulationConfig::default()
    })
    .expect_err("refused")
    .to_string();
    assert!(error.contains("`max_internal_step`"), "{error}");
}

/// The step follows the tolerance: tighter, shorter; and the choice is a
/// function of the configuration alone.
#[test]
fn the_step_shrinks_with_the_tolerance_and_is_reproducible() {
    let mut previous = f64::INFINITY;
    for tolerance in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        let config = SimulationConfig {
            tolerance,
            ..SimulationConfig::default()
        };
        let step = Simulator::new(config.clone()).unwrap().grid().step;
        assert!(step <= previous, "{tolerance}: {step} after {previous}");
        assert_eq!(step, Simulator::new(config).unwrap().grid().step);
        previous = step;
    }
    // A cap below the tolerance's step is the step (here tau = 2 h).
    let capped = Simulator::new(SimulationConfig {
        max_internal_step: 1e-4,
        ..SimulationConfig::default()
    })
    .unwrap();
    assert_eq!(capped.grid().step, 1e-4);
    assert_eq!(capped.grid().regime, DelayRegime::WholeSteps { m: 2 });
}

/// A tolerance that would need an internal step below 1e-6 s (here a road
/// at 1e5 rad/s at the tightest tolerance) is refused, naming it.
#[test]
fn a_tolerance_beyond_the_work_limit_is_refused() {
    let error = Simulator::new(SimulationConfig {
        tolerance: 1e-12,
        road: harmonic(1e-6, 1e5),
        ..SimulationConfig::default()
    })
    .expect_err("refused")
    .to_string();
    assert!(
        error.contains("`tolerance`") && error.contains("below 1e-6 s"),
        "{error}"
    );
}
