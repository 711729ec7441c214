//! The monolithic full car (`tdvass::car`): with the default chassis
//! (`I_θ = m a b`, the centre of gravity midway) and the same road on both
//! tracks, front and rear decouple and left equals right, so each corner
//! is the paper's quarter car; the car takes the quarter car's grid and
//! approximations, so each corner's RMS values equal the quarter car's
//! (`Simulator` on the same step) to 1e-10 relative, for the three
//! variants and the three delay regimes, and with the unilateral tire too
//! (on a harmonic road and on a rough one), the lift-off counts equal.

use std::sync::Arc;
use tdvass::car::{CarConfig, CarReport, run_car_with};
use tdvass::chassis::Corner;
use tdvass::model::{Params, TireContact, Variant};
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::{RunSummary, Simulator};

/// The bar of the comparison (relative), with either tire.
const DECOUPLED: f64 = 1e-10;

fn iso(class: RoadClass, speed: f64) -> RoadSpec {
    RoadSpec::Iso8608(RandomRoad {
        class,
        speed,
        cutoff_frequency: 0.1,
        seed: 7,
    })
}

fn relative(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

/// The car and each axle's quarter car on the car's step.
fn car_and_quarter_cars(config: &CarConfig, duration: f64) -> (CarReport, [RunSummary; 2]) {
    let choice = config.choose_step().unwrap();
    let car = run_car_with(config, &choice, duration, 0, &mut |_| {}).unwrap();
    let quarter = |corner| {
        let mut sim = Simulator::with_choice(config.quarter_car(corner), choice).unwrap();
        sim.run_for(duration).unwrap()
    };
    (car, [quarter(Corner::FrontLeft), quarter(Corner::RearLeft)])
}

fn check_decoupled(config: &CarConfig, duration: f64, bar: f64) -> f64 {
    let (car, quarter) = car_and_quarter_cars(config, duration);
    let mut worst: f64 = 0.0;
    for (c, corner) in car.corners.iter().enumerate() {
        let q = &quarter[c / 2];
        let holding = q.road_holding.unwrap();
        for (name, ours, theirs) in [
            (
                "rms_suspension_deflection",
                corner.rms_suspension_deflection,
                q.rms.suspension_deflection,
            ),
            (
                "rms_tire_deflection",
                corner.rms_tire_deflection,
                q.rms.tire_deflection,
            ),
            (
                "rms_dynamic_tire_load_ratio",
                corner.rms_dynamic_tire_load_ratio,
                q.rms_dynamic_tire_load_ratio,
            ),
        ] {
            let gap = relative(ours, theirs);
            worst = worst.max(gap);
            assert!(
                gap <= bar,
                "{config:?} corner {c} {name}: {ours} vs {theirs} ({gap:e})"
            );
        }
        assert_eq!(corner.lift_off_count, holding.lift_off_count, "corner {c}");
    }
    worst
}

#[test]
fn the_decoupled_car_is_four_quarter_cars() {
    for variant in Variant::ALL {
        for tau in [0.0, 2e-4, 0.011] {
            let mut config = CarConfig::new(variant, iso(RoadClass::C, 20.0), 20.0);
            config.params = Params {
                tau,
                ..Params::default()
            };
            let worst = check_decoupled(&config, 2.0, DECOUPLED);
            eprintln!("{variant:?} tau {tau}: {worst:e}");
        }
    }
}

#[test]
fn the_decoupled_car_is_the_quarter_car_on_every_built_in_road() {
    // The rear wheels' breakpoints fall between the front's grid nodes on
    // the paper-compatible road (0.1 s apart, 0.13 s behind at 20 m/s).
    let paper = RoadSpec::PaperCompatible {
        road: RandomRoad {
            class: RoadClass::C,
            speed: 20.0,
            cutoff_frequency: 0.1,
            seed: 3,
        },
        sample_interval: 0.1,
    };
    let harmonic = RoadSpec::Harmonic {
        amplitude: 0.05,
        angular_frequency: 5.0,
    };
    for road in [paper, harmonic] {
        let config = CarConfig::new(Variant::Tdvass, road, 20.0);
        check_decoupled(&config, 2.0, DECOUPLED);
    }
}

#[test]
fn the_decoupled_car_lifts_off_as_the_quarter_car() {
    for tau in [0.0, 2e-4, 0.011] {
        let road = RoadSpec::Harmonic {
            amplitude: 0.03,
            angular_frequency: 60.0,
        };
        let mut config = CarConfig::new(Variant::Tdvass, road, 30.0);
        config.params = Params {
            tau,
            ..Params::default()
        };
        config.tire_contact = TireContact::Unilateral;
        let worst = check_decoupled(&config, 2.0, DECOUPLED);
        eprintln!("unilateral tau {tau}: {worst:e}");
    }
}

#[test]
fn on_a_rough_road_the_decoupled_car_lifts_off_as_the_quarter_car_and_never_rolls() {
    // Class E at 30 m/s: every wheel lifts off about 16 times a second,
    // many landings grazing the road. The car's left and right stay equal
    // to the bit (its mirror coordinates), so it does not roll, and its
    // twins switch together.
    for variant in Variant::ALL {
        for tau in [0.0, 2e-4, 0.011] {
            let mut config = CarConfig::new(variant, iso(RoadClass::E, 30.0), 30.0);
            config.params = Params {
                tau,
                ..Params::default()
            };
            config.tire_contact = TireContact::Unilateral;
            let worst = check_decoupled(&config, 2.0, DECOUPLED);
            eprintln!("rough, unilateral, {variant:?} tau {tau}: {worst:e}");
            let (car, _) = car_and_quarter_cars(&config, 2.0);
            assert_eq!(car.rms_roll_acceleration, 0.0, "{variant:?} tau {tau}");
            assert_eq!(car.corners[0], car.corners[1], "{variant:?} tau {tau}");
            assert_eq!(car.corners[2], car.corners[3], "{variant:?} tau {tau}");
            assert!(car.corners.iter().all(|c| c.lift_off_count > 20), "{car:?}");
        }
    }
}

/// A 2 cm step at `at` (s), climbed in 0.1 ms.
fn step_road(at: f64) -> RoadSpec {
    RoadSpec::Samples(Arc::new(vec![(0.0, 0.0), (at, 0.0), (at + 1e-4, 0.02)]))
}

fn flat_road() -> RoadSpec {
    RoadSpec::Samples(Arc::new(vec![(0.0, 0.0)]))
}

#[test]
fn every_wheel_on_its_own_road_the_same_step_is_the_quarter_car() {
    // Four roads of their own, all the same step: no wheelbase delay, so
    // the car heaves without pitch or roll and each corner is the quarter
    // car on that road (the rear's check_decoupled compares the rear left
    // with its own quarter car, on the same road).
    for tau in [0.0, 2e-4, 0.011] {
        let mut config = CarConfig::new(Variant::Tdvass, step_road(0.2), 20.0);
        config.params = Params {
            tau,
            ..Params::default()
        };
        config.corner_roads = Some(std::array::from_fn(|_| step_road(0.2)));
        let worst = check_decoupled(&config, 1.0, DECOUPLED);
        eprintln!("own roads, tau {tau}: {worst:e}");
        let choice = config.choose_step().unwrap();
        let car = run_car_with(&config, &choice, 1.0, 0, &mut |_| {}).unwrap();
        assert!(car.rms_heave_acceleration > 0.1, "{car:?}");
        // Pitch and roll are roundings of zero.
        let rounding = 1e-12 * car.rms_heave_acceleration;
        assert!(car.rms_pitch_acceleration < rounding, "{car:?}");
        assert!(car.rms_roll_acceleration < rounding, "{car:?}");
    }
}

#[test]
fn a_step_under_one_front_wheel_rolls_the_car_and_its_mirror_rolls_it_back() {
    let under = |corner: Corner| {
        let mut config = CarConfig::new(Variant::Tdvass, flat_road(), 20.0);
        config.chassis.seat_y = 0.0;
        config.corner_roads = Some(std::array::from_fn(|c| {
            if c == corner as usize {
                step_road(0.1)
            } else {
                flat_road()
            }
        }));
        let choice = config.choose_step().unwrap();
        run_car_with(&config, &choice, 1.0, 0, &mut |_| {}).unwrap()
    };
    let left = under(Corner::FrontLeft);
    let right = under(Corner::FrontRight);
    assert!(left.rms_roll_acceleration > 0.1, "{left:?}");
    assert!(left.rms_pitch_acceleration > 0.01, "{left:?}");
    // The wheel on the step works hardest.
    let fl = &left.corners[Corner::FrontLeft as usize];
    for other in &left.corners[1..] {
        assert!(
            fl.rms_tire_deflection > 2.0 * other.rms_tire_deflection,
            "{left:?}"
        );
    }
    let mirror = [1, 0, 3, 2];
    let mut worst: f64 = 0.0;
    for (ours, theirs) in [
        (left.rms_heave_acceleration, right.rms_heave_acceleration),
        (left.rms_pitch_acceleration, right.rms_pitch_acceleration),
        (left.rms_roll_acceleration, right.rms_roll_acceleration),
        (
            left.rms_weighted_seat_acceleration,
            right.rms_weighted_seat_acceleration,
        ),
        (
            left.seat_vibration_dose_value,
            right.seat_vibration_dose_value,
        ),
    ]
    .into_iter()
    .chain((0..4).flat_map(|c| {
        let (ours, theirs) = (&left.corners[c], &right.corners[mirror[c]]);
        [
            (
                ours.rms_suspension_deflection,
                theirs.rms_suspension_deflection,
            ),
            (ours.rms_tire_deflection, theirs.rms_tire_deflection),
            (
                ours.rms_dynamic_tire_load_ratio,
                theirs.rms_dynamic_tire_load_ratio,
            ),
        ]
    })) {
        worst = worst.max(relative(ours, theirs));
    }
    eprintln!("mirror: {worst:e}");
    assert!(worst <= DECOUPLED, "{left:?}\n{right:?}");
}

#[test]
fn roads_of_their_own_must_be_alike() {
    let harmonic = |amplitude| RoadSpec::Harmonic {
        amplitude,
        angular_frequency: 5.0,
    };
    let mut config = CarConfig::new(Variant::Tdvass, harmonic(0.05), 20.0);
    config.corner_roads = Some([harmonic(0.05), harmonic(0.05), harmonic(0.05), flat_road()]);
    let error = config.choose_step().unwrap_err().to_string();
    assert!(error.contains("same kind"), "{error}");
    config.corner_roads = Some([
        harmonic(0.05),
        harmonic(0.04),
        harmonic(0.05),
        harmonic(0.05),
    ]);
    let error = config.choose_step().unwrap_err().to_string();
    assert!(
        error.contains("road_amplitude") && error.contains("0.04"),
        "{error}"
    );
    config.corner_roads = Some(std::array::from_fn(|_| harmonic(0.05)));
    assert!(config.choose_step().is_ok());
}
