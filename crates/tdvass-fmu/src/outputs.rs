//! How the FMU's outputs are read from the simulator: their values, exact
//! time derivatives and exact partial derivatives with respect to the
//! input and the states (Real outputs), and the counts (Integer outputs).

use std::ops::Range;
use tdvass::exchange::{Gradient, OutputPartials};
use tdvass::model::{V_H, V_T, X_H, X_S, X_T};
use tdvass::solver::{
    CONTINUOUS_STATES, INTEGRALS_AT, Instantaneous, OutputDerivatives, Outputs, TimeAverages,
};

/// The plant's states `[x_s, v_s, x_h, v_h, x_t, v_t]` among the continuous
/// states.
const PLANT: Range<usize> = 0..6;
/// The plant and the W_k filter.
const PLANT_AND_FILTER: Range<usize> = 0..INTEGRALS_AT;

/// The integral state `k` of [`tdvass::solver::INTEGRAL_NAMES`].
const fn integral(k: usize) -> Range<usize> {
    INTEGRALS_AT + k..INTEGRALS_AT + k + 1
}

/// An output of the simulator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OutputId {
    /// Component of the reported state `[x_s, v_s, x_h, v_h, x_t, v_t]`.
    State(usize),
    BodyAcceleration,
    SuspensionDeflection,
    TireDeflection,
    RoadDisplacement,
    ControlForce,
    /// The corner's force on the body ([`Outputs::body_force`]).
    BodyForce,
    RmsBodyAcceleration,
    RmsSuspensionDeflection,
    RmsTireDeflection,
    Objective,
    WeightedBodyAcceleration,
    RmsWeightedBodyAcceleration,
    VibrationDoseValue,
    DynamicTireLoad,
    RmsDynamicTireLoadRatio,
    ContactLossTime,
    MaxSuspensionDeflection,
}

/// An Integer output of the simulator: a count, discrete (it has no
/// derivative and no partials).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IntegerOutputId {
    /// The lift-offs since the start ([`tdvass::solver::RoadHolding::lift_off_count`]).
    LiftOffCount,
}

impl IntegerOutputId {
    /// The continuous states the count depends on: the plant's, whose
    /// contact margin decides each event.
    pub fn state_dependencies(self) -> Range<usize> {
        match self {
            IntegerOutputId::LiftOffCount => PLANT,
        }
    }

    /// The value in `outputs`, saturated at `i32::MAX` (the Integer of
    /// FMI 2.0 has 32 bits); `None` when the simulator does not keep it.
    pub fn value(self, o: &Outputs) -> Option<i32> {
        match self {
            IntegerOutputId::LiftOffCount => o
                .road_holding
                .map(|r| i32::try_from(r.lift_off_count).unwrap_or(i32::MAX)),
        }
    }
}

/// A "known" of `fmi2GetDirectionalDerivative`: the input `x_g` or a
/// component of the state `X` (addressed by the value reference of the
/// state output of the same name).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Known {
    RoadInput,
    State(usize),
}

/// What the partial derivatives of the outputs depend on, at the current point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linearization {
    /// Row `v_s` of A: BA = row · X.
    pub body_acceleration_row: [f64; 6],
    /// The force on the body = row · X ([`tdvass::model::Plant::body_force_row`]).
    pub body_force_row: [f64; 6],
    /// CS reports `x_h = x_t`, `v_h = v_t`.
    pub conventional: bool,
    /// `road = 0`: the applied road is the input.
    pub road_is_input: bool,
    /// Tire stiffness k_t (N/m): the dynamic tire load is `k_t (x_g − x_t)`;
    /// 0 while the wheel is in flight (unilateral tire), where the load is
    /// the constant −W.
    pub tire_stiffness: f64,
    /// `(g, tau)` when the control force is `g (x_t − tau v_t)` of the current
    /// state (delay folded into the plant); `None` when it acts on the delayed
    /// history only (or there is no control).
    pub instantaneous_control: Option<(f64, f64)>,
}

impl OutputId {
    /// The continuous states (indices in Model Exchange's layout,
    /// [`tdvass::solver::CONTINUOUS_STATES`]) the value is computed from at
    /// an instant, besides the time, the input `x_g` and the delay
    /// history: the dependencies on states in ModelStructure/Outputs. The
    /// instantaneous outputs come from the plant (and a_w from the filter
    /// too), the time averages from their integrals.
    pub fn state_dependencies(self) -> Range<usize> {
        match self {
            OutputId::State(i) => i..i + 1,
            OutputId::BodyAcceleration
            | OutputId::SuspensionDeflection
            | OutputId::TireDeflection
            | OutputId::ControlForce
            | OutputId::BodyForce
            | OutputId::DynamicTireLoad
            | OutputId::MaxSuspensionDeflection => PLANT,
            OutputId::RoadDisplacement => 0..0,
            OutputId::WeightedBodyAcceleration => PLANT_AND_FILTER,
            OutputId::RmsBodyAcceleration => integral(0),
            OutputId::RmsSuspensionDeflection => integral(1),
            OutputId::RmsTireDeflection | OutputId::RmsDynamicTireLoadRatio => integral(2),
            OutputId::Objective => INTEGRALS_AT..INTEGRALS_AT + 3,
            OutputId::RmsWeightedBodyAcceleration => integral(3),
            OutputId::VibrationDoseValue => integral(4),
            OutputId::ContactLossTime => CONTINUOUS_STATES - 1..CONTINUOUS_STATES,
        }
    }

    /// The value in `outputs`.
    pub fn value(self, o: &Outputs) -> f64 {
        match self {
            OutputId::State(i) => o.state[i],
            OutputId::BodyAcceleration => o.performance.body_acceleration,
            OutputId::SuspensionDeflection => o.performance.suspension_deflection,
            OutputId::TireDeflection => o.performance.tire_deflection,
            OutputId::RoadDisplacement => o.road_displacement,
            OutputId::ControlForce => o.control_force,
            OutputId::BodyForce => o.body_force,
            OutputId::RmsBodyAcceleration => o.rms.body_acceleration,
            OutputId::RmsSuspensionDeflection => o.rms.suspension_deflection,
            OutputId::RmsTireDeflection => o.rms.tire_deflection,
            OutputId::Objective => o.objective,
            OutputId::DynamicTireLoad => o.dynamic_tire_load,
            OutputId::RmsDynamicTireLoadRatio => o.rms_dynamic_tire_load_ratio,
            // The FMU's simulator keeps every metric; NaN (refused as
            // non-finite) would say it does not.
            OutputId::WeightedBodyAcceleration => {
                o.comfort.map_or(f64::NAN, |c| c.weighted_body_acceleration)
            }
            OutputId::RmsWeightedBodyAcceleration => o
                .comfort
                .map_or(f64::NAN, |c| c.rms_weighted_body_acceleration),
            OutputId::VibrationDoseValue => o.comfort.map_or(f64::NAN, |c| c.vibration_dose_value),
            OutputId::ContactLossTime => o.road_holding.map_or(f64::NAN, |r| r.contact_loss_time),
            OutputId::MaxSuspensionDeflection => o
                .road_holding
                .map_or(f64::NAN, |r| r.max_suspension_deflection),
        }
    }

    /// Whether the output is a value at the current instant that
    /// [`Instantaneous`] holds (see [`Self::instantaneous`]).
    pub fn is_instantaneous(self) -> bool {
        matches!(
            self,
            OutputId::State(_)
                | OutputId::BodyAcceleration
                | OutputId::SuspensionDeflection
                | OutputId::TireDeflection
                | OutputId::RoadDisplacement
                | OutputId::ControlForce
                | OutputId::BodyForce
                | OutputId::DynamicTireLoad
        )
    }

    /// The value in `instant` for an instantaneous output (the same as
    /// [`Self::value`] of the outputs at the same point), `None` for the
    /// other outputs.
    pub fn instantaneous(self, instant: &Instantaneous) -> Option<f64> {
        match self {
            OutputId::State(i) => Some(instant.state[i]),
            OutputId::BodyAcceleration => Some(instant.performance.body_acceleration),
            OutputId::SuspensionDeflection => Some(instant.performance.suspension_deflection),
            OutputId::TireDeflection => Some(instant.performance.tire_deflection),
            OutputId::RoadDisplacement => Some(instant.road_displacement),
            OutputId::ControlForce => Some(instant.control_force),
            OutputId::BodyForce => Some(instant.body_force),
            OutputId::DynamicTireLoad => Some(instant.dynamic_tire_load),
            _ => None,
        }
    }

    /// Whether the output is a time average from the start (its value
    /// then comes from [`TimeAverages`] as well, see [`Self::time_average`]).
    pub fn is_time_average(self) -> bool {
        matches!(
            self,
            OutputId::RmsBodyAcceleration
                | OutputId::RmsSuspensionDeflection
                | OutputId::RmsTireDeflection
                | OutputId::Objective
                | OutputId::RmsDynamicTireLoadRatio
        )
    }

    /// The value in `averages` for a time average (the same as
    /// [`Self::value`] of the outputs at the same point), `None` for the
    /// other outputs.
    pub fn time_average(self, averages: &TimeAverages) -> Option<f64> {
        match self {
            OutputId::RmsBodyAcceleration => Some(averages.rms.body_acceleration),
            OutputId::RmsSuspensionDeflection => Some(averages.rms.suspension_deflection),
            OutputId::RmsTireDeflection => Some(averages.rms.tire_deflection),
            OutputId::Objective => Some(averages.objective),
            OutputId::RmsDynamicTireLoadRatio => Some(averages.rms_dynamic_tire_load_ratio),
            _ => None,
        }
    }

    /// The exact first time derivative (the running RMS values and J are
    /// time averages, differentiable after the start).
    pub fn derivative(self, d: &OutputDerivatives) -> f64 {
        match self {
            OutputId::State(i) => d.state[i],
            OutputId::BodyAcceleration => d.performance.body_acceleration,
            OutputId::SuspensionDeflection => d.performance.suspension_deflection,
            OutputId::TireDeflection => d.performance.tire_deflection,
            OutputId::RoadDisplacement => d.road_displacement,
            OutputId::ControlForce => d.control_force,
            OutputId::BodyForce => d.body_force,
            OutputId::RmsBodyAcceleration => d.rms.body_acceleration,
            OutputId::RmsSuspensionDeflection => d.rms.suspension_deflection,
            OutputId::RmsTireDeflection => d.rms.tire_deflection,
            OutputId::Objective => d.objective,
            OutputId::DynamicTireLoad => d.dynamic_tire_load,
            OutputId::RmsDynamicTireLoadRatio => d.rms_dynamic_tire_load_ratio,
            OutputId::WeightedBodyAcceleration => {
                d.comfort.map_or(f64::NAN, |c| c.weighted_body_acceleration)
            }
            OutputId::RmsWeightedBodyAcceleration => d
                .comfort
                .map_or(f64::NAN, |c| c.rms_weighted_body_acceleration),
            OutputId::VibrationDoseValue => d.comfort.map_or(f64::NAN, |c| c.vibration_dose_value),
            OutputId::ContactLossTime => d.road_holding.map_or(f64::NAN, |r| r.contact_loss_time),
            OutputId::MaxSuspensionDeflection => d
                .road_holding
                .map_or(f64::NAN, |r| r.max_suspension_deflection),
        }
    }

    /// Model Exchange: the output's partials with respect to the
    /// continuous states and the input, from the model's `partials`.
    pub fn exchange_gradient(self, partials: &OutputPartials) -> Gradient {
        let p = partials;
        match self {
            OutputId::State(i) => Gradient::of_state(i),
            OutputId::BodyAcceleration => p.body_acceleration,
            OutputId::SuspensionDeflection => p.suspension_deflection,
            OutputId::TireDeflection => p.tire_deflection,
            OutputId::RoadDisplacement => p.road_displacement,
            OutputId::ControlForce => p.control_force,
            OutputId::BodyForce => p.body_force,
            OutputId::RmsBodyAcceleration => p.rms_body_acceleration,
            OutputId::RmsSuspensionDeflection => p.rms_suspension_deflection,
            OutputId::RmsTireDeflection => p.rms_tire_deflection,
            OutputId::Objective => p.objective,
            OutputId::WeightedBodyAcceleration => p.weighted_body_acceleration,
            OutputId::RmsWeightedBodyAcceleration => p.rms_weighted_body_acceleration,
            OutputId::VibrationDoseValue => p.vibration_dose_value,
            OutputId::DynamicTireLoad => p.dynamic_tire_load,
            OutputId::RmsDynamicTireLoadRatio => p.rms_dynamic_tire_load_ratio,
            OutputId::ContactLossTime => p.contact_loss_time,
            OutputId::MaxSuspensionDeflection => p.max_suspension_deflection,
        }
    }

    /// The exact partial derivative with respect to `known` at the current
    /// point. The running RMS values, J, VDV, the contact loss time and the
    /// running maximum are functionals of the past, and a_w is a state of
    /// the strictly proper W_k filter: their partials with respect to the
    /// current plant state and input are 0.
    pub fn partial(self, known: Known, lin: &Linearization) -> f64 {
        let indicator = |b: bool| if b { 1.0 } else { 0.0 };
        match (self, known) {
            (OutputId::State(i), Known::State(j)) => {
                let source = match i {
                    X_H if lin.conventional => X_T,
                    V_H if lin.conventional => V_T,
                    _ => i,
                };
                indicator(source == j)
            }
            (OutputId::BodyAcceleration, Known::State(j)) => lin.body_acceleration_row[j],
            (OutputId::BodyForce, Known::State(j)) => lin.body_force_row[j],
            (OutputId::SuspensionDeflection, Known::State(j)) => {
                indicator(j == X_S) - indicator(j == X_T)
            }
            (OutputId::TireDeflection, Known::State(j)) => indicator(j == X_T),
            (OutputId::TireDeflection, Known::RoadInput) => -indicator(lin.road_is_input),
            (OutputId::DynamicTireLoad, Known::State(j)) => {
                -lin.tire_stiffness * indicator(j == X_T)
            }
            (OutputId::DynamicTireLoad, Known::RoadInput) => {
                lin.tire_stiffness * indicator(lin.road_is_input)
            }
            (OutputId::RoadDisplacement, Known::RoadInput) => indicator(lin.road_is_input),
            (OutputId::ControlForce, Known::State(j)) => match lin.instantaneous_control {
                Some((g, _)) if j == X_T => g,
                Some((g, tau)) if j == V_T => -g * tau,
                _ => 0.0,
            },
            _ => 0.0,
        }
    }
}
