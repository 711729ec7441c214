//! The full car in one delay equation: the chassis of [`crate::chassis`]
//! on four corners of the paper's suspension, integrated by the precise
//! integration method of [`crate::solver`] as one system, the exact
//! reference a co-simulation of the corner and chassis FMUs is judged
//! against.
//!
//! The corners (fl, fr, rl, rr) share the suspension's parameters and
//! variant and each carries its share of the body (`m b / (a + b) / 2` at
//! the front, `m a / (a + b) / 2` at the rear), which also sets its tire's
//! static load. Each corner has the delayed feedback
//! `u_c = g x_t,c(t − tau)` of the TDVASS. The roads: the left track's
//! [`CarConfig::road`], the right track's [`CarConfig::right_road`] (a
//! random road from its own seed; the harmonic road with its own phase,
//! [`CarConfig::right_phase`]), the rear wheels delayed behind the front
//! by the wheelbase over the speed (`(a + b) / vehicle_speed`), as
//! [`crate::road::RoadShift`] delays a corner FMU's road. Or each corner
//! rolls on a road of its own, [`CarConfig::corner_roads`], seen as it is
//! (a step under one wheel: that wheel's road steps, the others' stay
//! flat).
//!
//! **The step** is the quarter car's: [`Simulator::choose_step`] of each
//! axle's quarter car (its corner's share of the body as `m_s`, the left
//! track's road, the tolerance), the shorter of the two, on the quarter
//! car's [`DelayGrid`]. With the default chassis and the same road on both
//! tracks each corner is that quarter car, and its RMS values are the
//! quarter car's to rounding (`tests/car.rs`).
//!
//! Layer: engines (docs/architecture.md), beside the chassis and Model
//! Exchange; `layout` (the state and the matrices), `mirror` (the mirror
//! coordinates it is integrated in), `maps` (the exact
//! step maps), `crossings` (a switch function's zeros inside a stretch),
//! `run` (the integration) and this facade.

mod averages;
mod crossings;
mod layout;
mod maps;
mod mirror;
mod run;

pub use layout::{CORNERS, STATES, corner_share};
pub use run::CarSample;

use crate::chassis::{ChassisParams, Corner};
use crate::error::{Error, Result};
use crate::metrics::{tire_load_ratio, weighted_averages};
use crate::model::{Params, TireContact, Variant};
use crate::road::{Road, RoadPiece, RoadShift, RoadSpec};
use crate::solver::{DelayGrid, Metrics, SimulationConfig, Simulator, StepChoice};
use layout::{CarSystem, HarmonicRoads};
use run::Run;

/// Everything that defines a run of the full car.
#[derive(Debug, Clone, PartialEq)]
pub struct CarConfig {
    /// The corners' parameters (Table 1 by default; `m_s` is not used, each
    /// corner carries its share of the chassis).
    pub params: Params,
    /// CS, PVASS or TDVASS, on every corner.
    pub variant: Variant,
    /// The rigid body.
    pub chassis: ChassisParams,
    /// The left track's road.
    pub road: RoadSpec,
    /// The right track's road (the same specification, with its own seed
    /// for a random road).
    pub right_road: RoadSpec,
    /// The right track's phase on the harmonic road (rad).
    pub right_phase: f64,
    /// Each corner's own road (fl, fr, rl, rr), seen as it is (no delay,
    /// no phase), in place of the tracks when given: roads of one kind,
    /// and harmonic ones of one amplitude and frequency.
    pub corner_roads: Option<[RoadSpec; CORNERS]>,
    /// The speed (m/s): the rear wheels follow the front by `(a + b) / speed`.
    pub vehicle_speed: f64,
    /// The tires' contact law.
    pub tire_contact: TireContact,
    /// Relative accuracy of every reported metric (it sets the step as it
    /// sets the quarter car's).
    pub tolerance: f64,
    /// Optional bound of the internal step (s; 0 = none).
    pub max_internal_step: f64,
}

impl CarConfig {
    /// The paper's car (Table 1, the default chassis) on `road`, the same
    /// road on both tracks.
    pub fn new(variant: Variant, road: RoadSpec, vehicle_speed: f64) -> CarConfig {
        CarConfig {
            params: Params::default(),
            variant,
            chassis: ChassisParams::default(),
            right_road: road.clone(),
            road,
            right_phase: 0.0,
            corner_roads: None,
            vehicle_speed,
            tire_contact: TireContact::Bilateral,
            tolerance: crate::solver::DEFAULT_TOLERANCE,
            max_internal_step: 0.0,
        }
    }

    /// The rear wheels' road delay (s): `(a + b) / vehicle_speed`.
    pub fn rear_delay(&self) -> f64 {
        (self.chassis.a + self.chassis.b) / self.vehicle_speed
    }

    /// How corner `corner` sees its track's road (its own road, when
    /// given, as it is).
    pub fn road_shift(&self, corner: Corner) -> RoadShift {
        if self.corner_roads.is_some() {
            return RoadShift::NONE;
        }
        let delay = match corner {
            Corner::FrontLeft | Corner::FrontRight => 0.0,
            Corner::RearLeft | Corner::RearRight => self.rear_delay(),
        };
        let phase = match corner {
            Corner::FrontRight | Corner::RearRight => self.right_phase,
            _ => 0.0,
        };
        RoadShift { delay, phase }
    }

    /// The road specification of corner `corner`'s track, or its own road
    /// when given.
    pub fn track(&self, corner: Corner) -> &RoadSpec {
        if let Some(roads) = &self.corner_roads {
            return &roads[corner as usize];
        }
        match corner {
            Corner::FrontLeft | Corner::RearLeft => &self.road,
            Corner::FrontRight | Corner::RearRight => &self.right_road,
        }
    }

    /// The quarter car of corner `corner` as `tdvass simulate` runs it
    /// (every metric):
    /// its share of the body as `m_s`, its own road as it sees it, the
    /// car's tire, tolerance and step bound, from rest.
    pub fn quarter_car(&self, corner: Corner) -> SimulationConfig {
        SimulationConfig {
            params: Params {
                m_s: corner_share(&self.chassis, corner),
                ..self.params
            },
            variant: self.variant,
            road: self.track(corner).clone(),
            road_shift: self.road_shift(corner),
            tolerance: self.tolerance,
            max_internal_step: self.max_internal_step,
            communication_step: 0.0,
            tire_contact: self.tire_contact,
            body: crate::model::Body::Mass,
            start_time: 0.0,
            initial_state: crate::model::State::zeros(),
            weights: crate::metrics::Weights::default(),
            metrics: Metrics::Comfort,
        }
    }

    /// Checks what the car adds to its quarter cars.
    fn validate(&self) -> Result<()> {
        self.chassis.validate()?;
        if !(self.vehicle_speed.is_finite() && self.vehicle_speed > 0.0) {
            return Err(Error::InvalidParameter {
                name: "vehicle_speed",
                value: self.vehicle_speed,
                reason: "must be finite and positive (the rear wheels follow the front)",
            });
        }
        if !self.right_phase.is_finite() {
            return Err(Error::InvalidParameter {
                name: "right_phase",
                value: self.right_phase,
                reason: "must be finite",
            });
        }
        let roads: Vec<&RoadSpec> = Corner::ALL.iter().map(|&c| self.track(c)).collect();
        for spec in &roads {
            if matches!(spec, RoadSpec::Input) {
                return Err(Error::InvalidSetting {
                    name: "road",
                    value: 0,
                    reason: "the full car runs a built-in road under each wheel, not an input",
                });
            }
        }
        for spec in &roads[1..] {
            if std::mem::discriminant(*spec) != std::mem::discriminant(roads[0]) {
                return Err(Error::InvalidSetting {
                    name: "road",
                    value: spec.road_type().code(),
                    reason: "every wheel's road must be of the same kind",
                });
            }
            if let (
                RoadSpec::Harmonic {
                    amplitude,
                    angular_frequency,
                },
                RoadSpec::Harmonic {
                    amplitude: first_amplitude,
                    angular_frequency: first_frequency,
                },
            ) = (spec, roads[0])
                && (amplitude != first_amplitude || angular_frequency != first_frequency)
            {
                return Err(Error::InvalidParameter {
                    name: "road_amplitude",
                    value: *amplitude,
                    reason: "harmonic roads under the wheels must share amplitude and frequency",
                });
            }
        }
        Ok(())
    }

    /// The corners whose quarter cars choose the step: one of each axle on
    /// the tracks, all four on roads of their own.
    fn step_corners(&self) -> &'static [Corner] {
        if self.corner_roads.is_some() {
            &Corner::ALL
        } else {
            &[Corner::FrontLeft, Corner::RearLeft]
        }
    }

    /// The step the car takes: each axle's quarter car's choice (each
    /// corner's, on roads of their own), the shortest.
    pub fn choose_step(&self) -> Result<StepChoice> {
        self.validate()?;
        let mut shortest: Option<StepChoice> = None;
        for &corner in self.step_corners() {
            let choice = Simulator::choose_step(&self.quarter_car(corner))?;
            if shortest
                .as_ref()
                .is_none_or(|s| choice.step_bound < s.step_bound)
            {
                shortest = Some(choice);
            }
        }
        Ok(shortest.expect("at least one corner"))
    }
}

/// One corner's results over a run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CornerReport {
    /// RMS SDD (m).
    pub rms_suspension_deflection: f64,
    /// RMS TDD (m).
    pub rms_tire_deflection: f64,
    /// `k_t RMS(TDD) / W_c`.
    pub rms_dynamic_tire_load_ratio: f64,
    /// Lift-offs (unilateral: switches to flight; bilateral: the times
    /// the dynamic tire load fell below −W_c).
    pub lift_off_count: u64,
    /// The time without tire contact (s).
    pub contact_loss_time: f64,
    /// The largest |SDD| (m).
    pub max_suspension_deflection: f64,
    /// This corner's share of the body's weight (N).
    pub static_load: f64,
}

/// The full car's results over a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarReport {
    /// fl, fr, rl, rr.
    pub corners: [CornerReport; CORNERS],
    /// RMS z'' (m/s²).
    pub rms_heave_acceleration: f64,
    /// RMS θ'' (rad/s²).
    pub rms_pitch_acceleration: f64,
    /// RMS φ'' (rad/s²).
    pub rms_roll_acceleration: f64,
    /// RMS a_w at the seat (m/s²).
    pub rms_weighted_seat_acceleration: f64,
    /// The seat's VDV (m/s^1.75).
    pub seat_vibration_dose_value: f64,
    /// The internal step h (s).
    pub internal_step: f64,
    /// The simulated duration (s).
    pub duration: f64,
}

/// Runs the full car `config` for `duration` (s) from rest on the step
/// `choice` (from [`CarConfig::choose_step`]), calling `sample` at every
/// `every`-th grid node (0: never).
pub fn run_car_with(
    config: &CarConfig,
    choice: &StepChoice,
    duration: f64,
    every: u64,
    sample: &mut dyn FnMut(CarSample),
) -> Result<CarReport> {
    config.validate()?;
    if !(duration.is_finite() && duration > 0.0) {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: duration,
            reason: "must be finite and positive",
        });
    }
    let resolved = if config.variant.has_control() {
        config.params.tau
    } else {
        0.0
    };
    let grid = DelayGrid::new(resolved, choice.step_bound)?;
    let roads: [Road; CORNERS] = {
        let mut roads = Vec::with_capacity(CORNERS);
        for corner in Corner::ALL {
            let mut road = Road::with_shift(config.track(corner), 0.0, config.road_shift(corner))?;
            road.reserve_window(grid.step);
            roads.push(road);
        }
        roads.try_into().expect("four roads")
    };
    let harmonic = match roads[0].harmonic() {
        Some(RoadPiece::Harmonic {
            amplitude,
            angular_frequency,
            ..
        }) => Some(HarmonicRoads {
            amplitude,
            angular_frequency,
            phases: std::array::from_fn(|c| match roads[c].harmonic() {
                Some(RoadPiece::Harmonic { phase, .. }) => phase,
                _ => 0.0,
            }),
        }),
        _ => None,
    };
    let folded = (!grid.resolves_delay()).then_some(resolved);
    let system = CarSystem::new(
        &config.params,
        config.variant,
        &config.chassis,
        folded,
        harmonic,
    )?;
    let static_loads = system.static_loads;
    let tire_loads = system.tire_loads;
    let mut run = Run::new(
        system,
        grid,
        0.0,
        roads,
        config.tire_contact.is_unilateral(),
    );
    run.run(duration, every, sample)?;
    let acc = &run.accumulated;
    let rms = |integral: f64| (integral.max(0.0) / duration).sqrt();
    let corners = std::array::from_fn(|c| {
        let rms_tire_deflection = rms(acc.tire(c));
        CornerReport {
            rms_suspension_deflection: rms(acc.deflection(c)),
            rms_tire_deflection,
            rms_dynamic_tire_load_ratio: tire_load_ratio(
                config.params.k_t,
                rms_tire_deflection,
                tire_loads[c],
            ),
            lift_off_count: acc.lift_offs[c],
            contact_loss_time: acc.loss_time[c],
            max_suspension_deflection: acc.max_deflection[c],
            static_load: static_loads[c],
        }
    });
    let (square, fourth) = acc.weighted();
    let (rms_weighted, dose) = weighted_averages(square, fourth, duration);
    Ok(CarReport {
        corners,
        rms_heave_acceleration: rms(acc.acceleration(0)),
        rms_pitch_acceleration: rms(acc.acceleration(1)),
        rms_roll_acceleration: rms(acc.acceleration(2)),
        rms_weighted_seat_acceleration: rms_weighted,
        seat_vibration_dose_value: dose,
        internal_step: run.step(),
        duration,
    })
}

/// Runs the full car `config` for `duration` (s) from rest, its step
/// chosen from the tolerance ([`CarConfig::choose_step`]).
pub fn run_car(config: &CarConfig, duration: f64) -> Result<CarReport> {
    let choice = config.choose_step()?;
    run_car_with(config, &choice, duration, 0, &mut |_| {})
}
