//! The settings of an instance: every parameter and the input, as the core
//! library's types ([`Params`], [`Weights`], the initial [`State`]) plus the
//! FMU's integer codes; [`Settings::to_config`] turns them into a
//! [`SimulationConfig`]. Start values come from the one variable table
//! ([`crate::variables`], which reads and writes these settings).

use crate::defaults::Model;
use tdvass::TireContact;
use tdvass::chassis::ChassisParams;
use tdvass::metrics::Weights;
use tdvass::model::inputs::{BODY_ATTACHMENT, PRESCRIBED, PrescribedValues};
use tdvass::model::{Body, Params, STANDARD_GRAVITY, State, Variant};
use tdvass::road::{RandomRoad, RoadClass, RoadShift, RoadSpec, RoadType};
use tdvass::solver::{DEFAULT_TOLERANCE, Metrics, SimulationConfig};

/// Every setting of an instance: the parameters and the input. Start values
/// come from the variable table ([`Settings::start_values`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The model these settings are of (no variable: the token chose it).
    pub model: Model,
    /// `variant` code: 1 CS, 2 PVASS, 3 TDVASS.
    pub variant: i32,
    /// The physical and controller parameters (Table 1, g, tau).
    pub params: Params,
    /// `road` code ([`RoadType`]).
    pub road: i32,
    pub road_amplitude: f64,
    pub road_angular_frequency: f64,
    pub road_class: i32,
    pub vehicle_speed: f64,
    pub road_cutoff_frequency: f64,
    pub road_seed: i32,
    pub road_sample_interval: f64,
    pub max_internal_step: f64,
    /// `tire_contact` code ([`TireContact`]): 0 bilateral, 1 unilateral.
    pub tire_contact: i32,
    /// The relative tolerance of the experiment: the master's, when it
    /// defines one, else the DefaultExperiment's ([`DEFAULT_TOLERANCE`]).
    /// No variable: it comes from `the experiment set-up`.
    pub tolerance: f64,
    /// The weights of J (Eq. (6)).
    pub weights: Weights,
    /// `road = 0`: 0 holds `x_g` over a communication step, 1 extrapolates
    /// it linearly from the last two values set, 2 from the last three.
    pub input_extrapolation: i32,
    /// `[x_s, v_s, x_h, v_h, x_t, v_t]` at the start time.
    pub initial_state: [f64; 6],
    /// The input `x_g` (m).
    pub x_g: f64,
    /// FMI 3.0: simulated time between intermediate updates (s; 0 = every
    /// internal node).
    pub intermediate_update_interval: f64,
    /// FMI 3.0: how many rightmost roots `rightmost_roots` lists.
    pub root_count: i32,
    /// The corner: its share W_c of the body's weight (N), which stands
    /// for the quarter car's `m_s = W_c / g0` ([`Settings::params`]).
    pub static_load: f64,
    /// The corner: the built-in road delayed by this (s).
    pub road_delay: f64,
    /// The corner: the harmonic road's phase (rad).
    pub road_phase: f64,
    /// The corner: the body's attachment point's displacement (m).
    pub body_displacement: f64,
    /// The corner: the body's attachment point's velocity (m/s).
    pub body_velocity: f64,
    /// The chassis: its mass, geometry, inertias and seat point.
    pub chassis: ChassisParams,
    /// The chassis: the corners' forces on the body (N), in the order of
    /// [`tdvass::chassis::Corner::ALL`].
    pub forces: [f64; 4],
    /// The chassis: the forces' rates over the next communication step
    /// (N/s; the input derivatives, 0 unless the master gives them).
    pub force_rates: [f64; 4],
}

impl Settings {
    /// Every value zero (codes 0, no weights), the default tolerance: what
    /// the table's start values ([`Settings::start_values`], in
    /// [`crate::variables`]) are written over.
    pub fn zeroed(model: Model) -> Settings {
        let zero_params = Params {
            m_s: 0.0,
            m_h: 0.0,
            m_t: 0.0,
            k_s: 0.0,
            k_h: 0.0,
            k_t: 0.0,
            c_s: 0.0,
            c_h: 0.0,
            g: 0.0,
            tau: 0.0,
        };
        Settings {
            model,
            variant: 0,
            params: zero_params,
            road: 0,
            road_amplitude: 0.0,
            road_angular_frequency: 0.0,
            road_class: 0,
            vehicle_speed: 0.0,
            road_cutoff_frequency: 0.0,
            road_seed: 0,
            road_sample_interval: 0.0,
            max_internal_step: 0.0,
            tire_contact: 0,
            tolerance: DEFAULT_TOLERANCE,
            weights: Weights {
                body_acceleration: 0.0,
                suspension_deflection: 0.0,
                tire_deflection: 0.0,
            },
            input_extrapolation: 0,
            initial_state: [0.0; 6],
            x_g: 0.0,
            intermediate_update_interval: 0.0,
            root_count: 0,
            static_load: 0.0,
            road_delay: 0.0,
            road_phase: 0.0,
            body_displacement: 0.0,
            body_velocity: 0.0,
            chassis: ChassisParams {
                mass: 0.0,
                a: 0.0,
                b: 0.0,
                track_front: 0.0,
                track_rear: 0.0,
                pitch_inertia: 0.0,
                roll_inertia: 0.0,
                seat_x: 0.0,
                seat_y: 0.0,
            },
            forces: [0.0; 4],
            force_rates: [0.0; 4],
        }
    }

    /// The physical parameters; the corner's `m_s` is `static_load / g0`
    /// (it sets the tire's static load and nothing else,
    /// [`tdvass::model::Body::Attached`]).
    pub fn params(&self) -> Params {
        match self.model {
            // The chassis has no suspension: its settings leave them alone.
            Model::QuarterCar | Model::Chassis => self.params,
            Model::Corner => Params {
                m_s: self.static_load / STANDARD_GRAVITY,
                ..self.params
            },
        }
    }

    /// What carries the suspension: the quarter car's own mass, or the
    /// corner's body outside the model.
    pub fn body(&self) -> Body {
        match self.model {
            Model::QuarterCar | Model::Chassis => Body::Mass,
            Model::Corner => Body::Attached,
        }
    }

    /// What the model's simulation computes: every metric (ISO 2631-1
    /// comfort, road holding, working space) whatever the master reads;
    /// the corner all but comfort, since it carries no body to weigh (its
    /// body acceleration is zero; a car's comfort is its chassis's).
    pub fn metrics(&self) -> Metrics {
        match self.body() {
            Body::Mass => Metrics::Comfort,
            Body::Attached => Metrics::RoadHolding,
        }
    }

    /// The corner's body attachment point `(displacement, velocity)`;
    /// `None` for the quarter car.
    pub fn body_input(&self) -> Option<(f64, f64)> {
        self.prescribed()[BODY_ATTACHMENT].map(|[displacement, velocity]| (displacement, velocity))
    }

    /// The values of the inputs that prescribe coordinates
    /// ([`tdvass::model::inputs::PRESCRIBED`], by index), `None` for one
    /// the model does not have.
    pub fn prescribed(&self) -> PrescribedValues {
        // One pair per entry of the list: a new entry without its values
        // here does not compile.
        let values: [[f64; 2]; PRESCRIBED.len()] = [[self.body_displacement, self.body_velocity]];
        std::array::from_fn(|i| (PRESCRIBED[i].applies)(self.body()).then_some(values[i]))
    }

    /// The variant (`variant` code checked).
    pub fn variant(&self) -> tdvass::Result<Variant> {
        Variant::from_code(self.variant as i64)
    }

    /// The tire's contact law (`tire_contact` code checked).
    pub fn tire_contact(&self) -> tdvass::Result<TireContact> {
        TireContact::from_code(self.tire_contact as i64)
    }

    /// The weights of J.
    pub fn weights(&self) -> Weights {
        self.weights
    }

    /// Whether the road is the input `x_g` (`road = 0`).
    pub fn road_is_input(&self) -> bool {
        self.road_type() == Some(RoadType::Input)
    }

    /// The road type of the `road` code (`None` for a code that is none,
    /// or for the file samples, which are no setting).
    pub fn road_type(&self) -> Option<RoadType> {
        RoadType::from_code(self.road as i64).filter(|t| *t != RoadType::Samples)
    }

    /// The road (`road` code and the fields it uses checked).
    pub fn road_spec(&self) -> tdvass::Result<RoadSpec> {
        let random = || -> tdvass::Result<RandomRoad> {
            Ok(RandomRoad {
                class: RoadClass::from_code(self.road_class as i64)?,
                speed: self.vehicle_speed,
                cutoff_frequency: self.road_cutoff_frequency,
                seed: u64::try_from(self.road_seed).map_err(|_| tdvass::Error::InvalidSetting {
                    name: "road_seed",
                    value: self.road_seed as i64,
                    reason: "must be >= 0",
                })?,
            })
        };
        Ok(match self.road_type() {
            Some(RoadType::Input) => RoadSpec::Input,
            Some(RoadType::Harmonic) => RoadSpec::Harmonic {
                amplitude: self.road_amplitude,
                angular_frequency: self.road_angular_frequency,
            },
            Some(RoadType::Iso8608) => RoadSpec::Iso8608(random()?),
            Some(RoadType::PaperCompatible) => RoadSpec::PaperCompatible {
                road: random()?,
                sample_interval: self.road_sample_interval,
            },
            Some(RoadType::Samples) | None => {
                return Err(tdvass::Error::InvalidSetting {
                    name: "road",
                    value: self.road as i64,
                    reason: "must be 0 (input x_g), 1 (harmonic), 2 (ISO 8608) or 3 (paper-compatible)",
                });
            }
        })
    }

    /// The simulation these settings describe, starting at `start_time`.
    /// Only the codes are checked here; [`tdvass::solver::Simulator::new`]
    /// validates the rest.
    pub fn to_config(&self, start_time: f64) -> tdvass::Result<SimulationConfig> {
        Ok(SimulationConfig {
            params: self.params(),
            variant: self.variant()?,
            road: self.road_spec()?,
            road_shift: RoadShift {
                delay: self.road_delay,
                phase: self.road_phase,
            },
            tolerance: self.tolerance,
            max_internal_step: self.max_internal_step,
            // The internal step divides the DefaultExperiment stepSize: a
            // master stepping by it meets internal nodes only.
            communication_step: crate::defaults::DEFAULT_STEP_SIZE,
            tire_contact: self.tire_contact()?,
            body: self.body(),
            start_time,
            initial_state: State::from(self.initial_state),
            weights: self.weights(),
            metrics: self.metrics(),
        })
    }
}
