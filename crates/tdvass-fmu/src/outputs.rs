//! How the FMU's outputs are read from the simulator: their values, exact
//! time derivatives and exact partial derivatives with respect to the
//! input and the states.

use tdvass::model::{V_H, V_T, X_H, X_S, X_T};
use tdvass::solver::{OutputDerivatives, Outputs};

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
    RmsBodyAcceleration,
    RmsSuspensionDeflection,
    RmsTireDeflection,
    Objective,
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
    /// CS reports `x_h = x_t`, `v_h = v_t`.
    pub conventional: bool,
    /// `road = 0`: the applied road is the input.
    pub road_is_input: bool,
    /// `(g, tau)` when the control force is `g (x_t − tau v_t)` of the current
    /// state (delay folded into the plant); `None` when it acts on the delayed
    /// history only (or there is no control).
    pub instantaneous_control: Option<(f64, f64)>,
}

impl OutputId {
    /// The value in `outputs`.
    pub fn value(self, o: &Outputs) -> f64 {
        match self {
            OutputId::State(i) => o.state[i],
            OutputId::BodyAcceleration => o.performance.body_acceleration,
            OutputId::SuspensionDeflection => o.performance.suspension_deflection,
            OutputId::TireDeflection => o.performance.tire_deflection,
            OutputId::RoadDisplacement => o.road_displacement,
            OutputId::ControlForce => o.control_force,
            OutputId::RmsBodyAcceleration => o.rms.body_acceleration,
            OutputId::RmsSuspensionDeflection => o.rms.suspension_deflection,
            OutputId::RmsTireDeflection => o.rms.tire_deflection,
            OutputId::Objective => o.objective,
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
            OutputId::RmsBodyAcceleration => d.rms.body_acceleration,
            OutputId::RmsSuspensionDeflection => d.rms.suspension_deflection,
            OutputId::RmsTireDeflection => d.rms.tire_deflection,
            OutputId::Objective => d.objective,
        }
    }

    /// The exact partial derivative with respect to `known` at the current
    /// point. The running RMS values and J are integrals over the past: their
    /// partials with respect to the current state and input are 0.
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
            (OutputId::SuspensionDeflection, Known::State(j)) => {
                indicator(j == X_S) - indicator(j == X_T)
            }
            (OutputId::TireDeflection, Known::State(j)) => indicator(j == X_T),
            (OutputId::TireDeflection, Known::RoadInput) => -indicator(lin.road_is_input),
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
