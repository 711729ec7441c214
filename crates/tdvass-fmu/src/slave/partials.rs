//! Exact partial derivatives (directional and adjoint derivatives):
//! Co-Simulation, of the outputs with respect to the input and the plant's
//! states; Model Exchange, of the state derivatives and the outputs with
//! respect to the continuous states and the inputs (`x_g`, and a
//! corner's body attachment).

use super::{Engine, Slave};
use crate::chassis_outputs::ChassisOutputId;
use crate::defaults::Model;
use crate::error::{FmiError, Status};
use crate::outputs::{Known, Linearization, OutputId};
use crate::variables::{Access, Causality, Variable, by_vr};
use tdvass::chassis::{CHASSIS_STATES, ChassisGradient, Corner};
use tdvass::exchange::Gradient;
use tdvass::model::inputs::{PRESCRIBED, prescribed_by_name};
use tdvass::model::{V_S, Variant};
use tdvass::solver::CONTINUOUS_STATES;

/// A known of Model Exchange's partials: a continuous state, the road
/// input `x_g`, or a value of an input that prescribes coordinates (its
/// index into [`tdvass::model::inputs::PRESCRIBED`], then 0 for the
/// position, 1 for the velocity: the corner's `body_displacement`,
/// `body_velocity`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum ExchangeKnown {
    State(usize),
    RoadInput,
    Prescribed(usize, usize),
}

/// An unknown of Model Exchange's partials.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ExchangeUnknown {
    Derivative(usize),
    Output(OutputId),
}

impl Slave {
    /// The exact partials `∂unknown_i/∂known_j`, row by row: for Model
    /// Exchange, of the state derivatives and the Real outputs with respect
    /// to the continuous states and the inputs; for Co-Simulation, of the
    /// outputs (`unknowns`) with respect to the input `x_g` and the states
    /// (`knowns`, the states addressed by the value references of the
    /// outputs `x_s` .. `v_t`).
    pub fn partials(&mut self, unknowns: &[u32], knowns: &[u32]) -> Result<Vec<f64>, FmiError> {
        if self.model() == Model::Chassis {
            return self.chassis_partials(unknowns, knowns);
        }
        if self.state.engine.exchange().is_some() {
            return self.exchange_partials(unknowns, knowns);
        }
        let known: Vec<Known> = knowns
            .iter()
            .map(|&vr| {
                let var = by_vr(self.model(), self.dialect.version, vr).ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
                match (var.access, prescribed_by_name(var.name)) {
                    // The corner's body attachment is the plant's body
                    // coordinates, set from outside.
                    (Access::Real { .. }, Some((input, k))) => Ok(Known::State(PRESCRIBED[input].coordinates[k])),
                    (Access::Real { .. }, None) if var.causality == Causality::Input => Ok(Known::RoadInput),
                    (Access::Output(OutputId::State(i)), _) => Ok(Known::State(i)),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not a known of the directional derivative (only the inputs and the states x_s, v_s, x_h, v_h, x_t, v_t)",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let outputs: Vec<OutputId> = unknowns
            .iter()
            .map(|&vr| {
                let var = by_vr(self.model(), self.dialect.version, vr)
                    .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
                match var.access {
                    Access::Output(id) => Ok(id),
                    Access::IntegerOutput(_) => Err(FmiError::error(format!(
                        "`{}` is an Integer output (a count); directional derivatives exist for Real outputs only",
                        var.name
                    ))),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not an output; directional derivatives exist for outputs only",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let lin = self.linearization()?;
        Ok(outputs
            .iter()
            .flat_map(|out| known.iter().map(move |k| out.partial(*k, &lin)))
            .collect())
    }

    /// `GetDirectionalDerivative`: `result_i = Σ_j ∂unknown_i/∂known_j seed_j`
    /// (see [`Self::partials`]).
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<Status, FmiError> {
        let matrix = self.partials(unknowns, knowns)?;
        Self::check_seed(seed)?;
        let n = knowns.len();
        for (i, r) in result.iter_mut().enumerate().take(unknowns.len()) {
            *r = matrix[i * n..(i + 1) * n]
                .iter()
                .zip(seed)
                .map(|(p, dv)| p * dv)
                .sum();
        }
        Self::check_sensitivity(result)
    }

    /// `GetAdjointDerivative`: `result_j = Σ_i seed_i ∂unknown_i/∂known_j`
    /// (the transpose of [`Self::directional_derivative`], from the same
    /// partials).
    pub fn adjoint_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<Status, FmiError> {
        let matrix = self.partials(unknowns, knowns)?;
        Self::check_seed(seed)?;
        let n = knowns.len();
        for (j, r) in result.iter_mut().enumerate().take(n) {
            *r = seed
                .iter()
                .enumerate()
                .map(|(i, s)| s * matrix[i * n + j])
                .sum();
        }
        Self::check_sensitivity(result)
    }

    /// Model Exchange: the exact partials of the state derivatives
    /// (`der(...)`) and the Real outputs (`unknowns`) with respect to the
    /// continuous states and the inputs `x_g` and a corner's
    /// `body_displacement`, `body_velocity` (`knowns`), at the current time
    /// and states ([`tdvass::exchange::ModelExchange::jacobian`]).
    fn exchange_partials(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
    ) -> Result<Vec<f64>, FmiError> {
        let (model, version) = (self.model(), self.dialect.version);
        let lookup = |vr: u32| {
            by_vr(model, version, vr)
                .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))
        };
        let known: Vec<ExchangeKnown> = knowns
            .iter()
            .map(|&vr| {
                let var: &Variable = lookup(vr)?;
                match (var.access, prescribed_by_name(var.name)) {
                    // A corner's body attachment: the plant's body
                    // coordinates, read from the inputs.
                    (Access::Real { .. }, Some((input, k))) => Ok(ExchangeKnown::Prescribed(input, k)),
                    (Access::Real { .. }, None) if var.causality == Causality::Input => Ok(ExchangeKnown::RoadInput),
                    (Access::Output(OutputId::State(i)) | Access::ContinuousState(i), _) => Ok(ExchangeKnown::State(i)),
                    (Access::Output(OutputId::ContactLossTime), _) => Ok(ExchangeKnown::State(CONTINUOUS_STATES - 1)),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not a known of the directional derivative (Model Exchange: the continuous states and the inputs)",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let unknown: Vec<ExchangeUnknown> = unknowns
            .iter()
            .map(|&vr| {
                let var: &Variable = lookup(vr)?;
                match var.access {
                    Access::StateDerivative(i) => Ok(ExchangeUnknown::Derivative(i)),
                    Access::Output(id) => Ok(ExchangeUnknown::Output(id)),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not an unknown of the directional derivative (Model Exchange: the state derivatives and the Real outputs)",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let model = self.exchange()?;
        let jacobian = model.jacobian();
        let outputs = model.output_partials();
        let rows = unknown.iter().map(|u| match *u {
            ExchangeUnknown::Derivative(i) => Gradient {
                states: jacobian.states[i],
                road_input: jacobian.road_input[i],
                prescribed: jacobian.prescribed[i],
            },
            ExchangeUnknown::Output(id) => id.exchange_gradient(&outputs),
        });
        Ok(rows
            .flat_map(|row| {
                known.iter().map(move |k| match *k {
                    ExchangeKnown::State(j) => row.states[j],
                    ExchangeKnown::RoadInput => row.road_input,
                    ExchangeKnown::Prescribed(input, k) => row.prescribed[input][k],
                })
            })
            .collect())
    }

    /// The chassis in Model Exchange: the exact partials of its state
    /// derivatives and Real outputs (`unknowns`) with respect to its
    /// continuous states and the corners' forces (`knowns`), at the current
    /// states and forces ([`tdvass::chassis::Chassis::jacobian`]). Its
    /// Co-Simulation provides none.
    fn chassis_partials(&mut self, unknowns: &[u32], knowns: &[u32]) -> Result<Vec<f64>, FmiError> {
        let version = self.dialect.version;
        let lookup = |vr: u32| {
            by_vr(Model::Chassis, version, vr)
                .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))
        };
        // A known: a state's index, or 19 + a force's corner.
        let known: Vec<usize> = knowns
            .iter()
            .map(|&vr| {
                let var: &Variable = lookup(vr)?;
                let force = Corner::ALL.iter().position(|c| c.force_name() == var.name);
                match (var.state_index(), force) {
                    (Some(i), _) => Ok(i),
                    (None, Some(c)) => Ok(CHASSIS_STATES + c),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not a known of the chassis's directional derivative (its continuous states and the forces)",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let chassis = match &self.state.engine {
            Engine::ChassisExchange(Some(chassis)) => chassis,
            Engine::ChassisExchange(None) => {
                return Err(FmiError::error(
                    "no Model Exchange model: the instance is not initialized",
                ));
            }
            _ => {
                return Err(FmiError::error(
                    "the chassis provides directional derivatives in Model Exchange only (its CoSimulation element: providesDirectionalDerivative = false)",
                ));
            }
        };
        let rows = chassis.jacobian();
        let outputs = chassis.output_partials();
        let gradients = unknowns
            .iter()
            .map(|&vr| {
                let var: &Variable = lookup(vr)?;
                use ChassisOutputId as C;
                Ok(match var.access {
                    Access::StateDerivative(i) => rows[i],
                    Access::ChassisOutput(id) => match id {
                        C::Displacement(c) => outputs.displacement[c.index()],
                        C::Velocity(c) => outputs.velocity[c.index()],
                        C::Position(k) => ChassisGradient::of_state(k),
                        C::Rate(k) => ChassisGradient::of_state(3 + k),
                        C::Acceleration(k) => outputs.acceleration[k],
                        C::SeatAcceleration => outputs.seat_acceleration,
                        C::RmsAcceleration(k) => outputs.rms_acceleration[k],
                        C::WeightedSeatAcceleration => outputs.weighted_seat_acceleration,
                        C::RmsWeightedSeatAcceleration => outputs.rms_weighted_seat_acceleration,
                        C::SeatVibrationDoseValue => outputs.seat_vibration_dose_value,
                    },
                    _ => {
                        return Err(FmiError::error(format!(
                            "`{}` is not an unknown of the chassis's directional derivative (its state derivatives and Real outputs)",
                            var.name
                        )));
                    }
                })
            })
            .collect::<Result<Vec<ChassisGradient>, FmiError>>()?;
        Ok(gradients
            .iter()
            .flat_map(|g| {
                known
                    .iter()
                    .map(move |&j| match j.checked_sub(CHASSIS_STATES) {
                        Some(c) => g.forces[c],
                        None => g.states[j],
                    })
            })
            .collect())
    }

    fn check_seed(seed: &[f64]) -> Result<(), FmiError> {
        match seed.iter().find(|v| !v.is_finite()) {
            Some(bad) => Err(FmiError::error(format!(
                "invalid seed value {bad}: must be finite"
            ))),
            None => Ok(()),
        }
    }

    fn check_sensitivity(result: &mut [f64]) -> Result<Status, FmiError> {
        if let Some(r) = result.iter_mut().find(|r| !r.is_finite()) {
            let bad = std::mem::replace(r, 0.0);
            return Err(FmiError::error(format!(
                "a directional derivative = {bad} is not finite (seed too large); no value returned"
            )));
        }
        Ok(Status::Ok)
    }

    fn linearization(&self) -> Result<Linearization, FmiError> {
        let preview;
        let sim = match self.state.engine.simulator() {
            Some(sim) => sim,
            None => {
                preview = self.build_simulator()?;
                &preview
            }
        };
        let plant = sim.plant();
        let variant = sim.config().variant;
        let mut row = [0.0; 6];
        for (j, r) in row.iter_mut().enumerate() {
            *r = plant.a[(V_S, j)];
        }
        let params = sim.config().params;
        let instantaneous_control = (!sim.grid().resolves_delay() && variant.has_control())
            .then_some((params.effective_gain(variant), params.tau));
        let mut body_force_row = [0.0; 6];
        for (j, r) in body_force_row.iter_mut().enumerate() {
            *r = plant.body_force_row[j];
        }
        Ok(Linearization {
            body_acceleration_row: row,
            body_force_row,
            conventional: variant == Variant::Cs,
            road_is_input: self.state.settings.road_is_input(),
            // In flight the dynamic tire load is the constant −W.
            tire_stiffness: if sim.in_flight() { 0.0 } else { params.k_t },
            instantaneous_control,
        })
    }
}
