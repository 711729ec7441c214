//! Model Exchange: the slave's calls for a master whose own solver
//! integrates the model ([`tdvass::exchange::ModelExchange`]): time and
//! continuous states in, derivatives and event indicators out, the event
//! updates, and completed integrator steps. The front-ends' state tables
//! decide where each may be called; here each checks its arguments and
//! names what it refuses.

use super::{Engine, Slave};
use crate::defaults::Model;
use crate::error::{FmiError, Status};
use crate::guards;
use crate::phase::Phase;
use tdvass::chassis::{CHASSIS_STATES, chassis_nominals};
use tdvass::exchange::{ContactEvent, EVENT_INDICATORS, ModelExchange, nominals};
use tdvass::model::dynamics::SWITCHES;
use tdvass::solver::CONTINUOUS_STATES;

/// The most continuous states an engine has (the quarter car's; the
/// chassis's fill the first [`CHASSIS_STATES`] of an array this long).
const ENGINE_STATES: usize = if CONTINUOUS_STATES > CHASSIS_STATES {
    CONTINUOUS_STATES
} else {
    CHASSIS_STATES
};

/// An engine's continuous states or their derivatives, by the engine's
/// own index (the chassis's in the first [`CHASSIS_STATES`]).
pub(super) type EngineStates = [f64; ENGINE_STATES];

/// `values` in the first places of an [`EngineStates`].
fn engine_states(values: &[f64]) -> EngineStates {
    let mut all = [0.0; ENGINE_STATES];
    all[..values.len()].copy_from_slice(values);
    all
}

/// What an event update tells the master (FMI 2.0 `fmi2EventInfo`, the
/// out-arguments of FMI 3.0 `fmi3UpdateDiscreteStates`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EventUpdate {
    /// The FMU asks the master to stop (after a divergence).
    pub terminate_simulation: bool,
    /// The master must restart its integrator: set at a switch of the
    /// contact mode, whose derivatives jump (the time without contact
    /// starts or stops counting; with the unilateral tire the plant's
    /// too), although the states keep their values. A master that restarts
    /// only when told (fmusim) otherwise meets the jump with its old
    /// history.
    pub values_of_continuous_states_changed: bool,
    /// The next time event, if any (none: see docs/fmu.md).
    pub next_event_time: Option<f64>,
}

/// What `CompletedIntegratorStep` tells the master.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepCompletion {
    /// Event Mode must be entered (never: every event is state or time).
    pub enter_event_mode: bool,
    /// The FMU asks the master to stop (after a divergence).
    pub terminate_simulation: bool,
}

impl Slave {
    /// Whether the instance was made for Model Exchange.
    pub fn is_model_exchange(&self) -> bool {
        self.state.engine.is_model_exchange()
    }

    /// Makes the instance a Model Exchange instance (at instantiation).
    pub fn use_model_exchange(&mut self) {
        self.state.engine = match self.model() {
            Model::Chassis => Engine::ChassisExchange(None),
            Model::QuarterCar | Model::Corner => Engine::ModelExchange(None),
        };
    }

    /// The model of the current settings at the start time (checked as
    /// initialization checks it), with the inputs applied.
    pub(super) fn build_exchange(&self) -> Result<ModelExchange, FmiError> {
        let m = &self.state;
        guards::check_rates(&m.settings)?;
        let config = m.settings.to_config(m.start_time)?;
        let mut model = ModelExchange::new(config)?;
        if m.settings.road_is_input() {
            model.set_road_input(m.settings.x_g)?;
        }
        for (input, values) in m.settings.prescribed().into_iter().enumerate() {
            if let Some(values) = values {
                model.set_prescribed(input, values)?;
            }
        }
        Ok(model)
    }

    /// The running model: Model Exchange after initialization.
    pub(super) fn exchange(&mut self) -> Result<&mut ModelExchange, FmiError> {
        self.state.engine.exchange_mut().ok_or_else(|| {
            FmiError::error("no Model Exchange model: the instance is not initialized")
        })
    }

    /// Checks that a Model Exchange model runs (either kind).
    fn check_exchange_runs(&self) -> Result<(), FmiError> {
        match &self.state.engine {
            Engine::ModelExchange(Some(_)) | Engine::ChassisExchange(Some(_)) => Ok(()),
            _ => Err(FmiError::error(
                "no Model Exchange model: the instance is not initialized",
            )),
        }
    }

    /// `ExitInitializationMode` of a Model Exchange instance: the model
    /// starts at the start time, in Event Mode.
    pub(super) fn exit_initialization_to_event_mode(&mut self) -> Result<Status, FmiError> {
        if self.model() == Model::Chassis {
            let chassis = self.build_chassis()?;
            self.state.engine = Engine::ChassisExchange(Some(Box::new(chassis)));
            self.state.phase = Phase::EventMode;
            self.state.terminate_requested = false;
            self.event(format_args!(
                "{}: Model Exchange of the chassis, start {} s, {CHASSIS_STATES} continuous states, no event indicator",
                self.call("ExitInitializationMode"),
                self.state.start_time,
            ));
            return Ok(Status::Ok);
        }
        let model = self.build_exchange()?;
        self.state.engine = Engine::ModelExchange(Some(Box::new(model)));
        self.state.phase = Phase::EventMode;
        self.state.terminate_requested = false;
        let s = &self.state.settings;
        self.event(format_args!(
            "{}: Model Exchange, variant {}, road {}, tire_contact {}, start {} s, {} continuous states, {} event indicator",
            self.call("ExitInitializationMode"),
            s.variant,
            s.road,
            s.tire_contact,
            self.state.start_time,
            self.model().continuous_states().len(),
            EVENT_INDICATORS,
        ));
        Ok(self.stability_check(self.call("ExitInitializationMode")))
    }

    /// `EnterEventMode`.
    pub fn enter_event_mode(&mut self) -> Result<Status, FmiError> {
        self.check_exchange_runs()?;
        self.state.phase = Phase::EventMode;
        Ok(Status::Ok)
    }

    /// `EnterContinuousTimeMode`.
    pub fn enter_continuous_time_mode(&mut self) -> Result<Status, FmiError> {
        self.check_exchange_runs()?;
        self.state.phase = Phase::ContinuousTimeMode;
        Ok(Status::Ok)
    }

    /// `NewDiscreteStates` / `UpdateDiscreteStates`: the contact mode
    /// follows the margin; a lift-off is logged as an event. The chassis
    /// has no events.
    pub fn update_discrete_states(&mut self) -> Result<EventUpdate, FmiError> {
        if self.state.engine.chassis().is_some() {
            self.check_exchange_runs()?;
            return Ok(EventUpdate::default());
        }
        let event = self.exchange()?.update_discrete_states();
        match event {
            Some(ContactEvent::LiftOff {
                time,
                tire_deflection,
            }) => self.event(format_args!(
                "{}: lift-off at t = {time} s (TDD = {tire_deflection} m)",
                self.call(self.dialect.update_discrete_states)
            )),
            Some(ContactEvent::TouchDown { time }) => self.event(format_args!(
                "{}: touch-down at t = {time} s",
                self.call(self.dialect.update_discrete_states)
            )),
            None => {}
        }
        Ok(EventUpdate {
            terminate_simulation: self.divergence_warning(self.dialect.update_discrete_states)?,
            values_of_continuous_states_changed: event.is_some(),
            ..EventUpdate::default()
        })
    }

    /// Logs a diverged plant state once, naming the `function` that saw
    /// it, and asks the master to stop.
    fn divergence_warning(&mut self, function: &'static str) -> Result<bool, FmiError> {
        let Some((name, value)) = self.exchange()?.diverged() else {
            return Ok(false);
        };
        if !self.state.terminate_requested {
            self.state.terminate_requested = true;
            self.logger.log(
                Status::Warning,
                &format!(
                    "{}: the state diverged: `{name}` = {value} at t = {} s is beyond the divergence bound; terminate the simulation",
                    self.call(function),
                    self.time()
                ),
            );
        }
        Ok(true)
    }

    /// `CompletedIntegratorStep`: the current point is accepted (delay
    /// history, the largest |SDD|).
    pub fn completed_integrator_step(&mut self) -> Result<StepCompletion, FmiError> {
        if self.state.engine.chassis().is_some() {
            self.check_exchange_runs()?;
            return Ok(StepCompletion::default());
        }
        self.exchange()?.complete_step();
        Ok(StepCompletion {
            enter_event_mode: false,
            terminate_simulation: self.divergence_warning("CompletedIntegratorStep")?,
        })
    }

    /// `SetTime`: finite and not before the last completed step or event.
    pub fn set_time(&mut self, time: f64) -> Result<Status, FmiError> {
        if let Engine::ChassisExchange(Some(chassis)) = &mut self.state.engine {
            chassis.set_time(time)?;
            return Ok(Status::Ok);
        }
        self.exchange()?.set_time(time)?;
        Ok(Status::Ok)
    }

    /// `SetContinuousStates`: the model's states
    /// ([`Model::continuous_states`]; the corner's others keep their
    /// values).
    pub fn set_continuous_states(&mut self, states: &[f64]) -> Result<Status, FmiError> {
        let model = self.model();
        let order = model.continuous_states();
        if states.len() != order.len() {
            return Err(FmiError::error(format!(
                "{} continuous states given, the model has {}",
                states.len(),
                order.len()
            )));
        }
        if let Engine::ChassisExchange(Some(chassis)) = &mut self.state.engine {
            chassis.set_states(states)?;
            return Ok(Status::Ok);
        }
        let exchange = self.exchange()?;
        if model == Model::QuarterCar {
            exchange.set_states(states)?;
        } else {
            let mut all = *exchange.states();
            if let Some(k) = states.iter().position(|v| !v.is_finite()) {
                return Err(FmiError::error(format!(
                    "continuous state {k} (`{}`) = {} is not finite",
                    tdvass::exchange::state_names()[order[k]],
                    states[k]
                )));
            }
            for (&i, &value) in order.iter().zip(states) {
                all[i] = value;
            }
            exchange.set_states(&all)?;
        }
        Ok(Status::Ok)
    }

    /// `out[k]` = `all[i_k]` for the model's states `i_k`, `out` of their
    /// count.
    fn pick_states(&self, what: &str, all: &[f64], out: &mut [f64]) -> Result<(), FmiError> {
        let order = self.model().continuous_states();
        Self::check_count(what, out.len(), order.len())?;
        for (o, &i) in out.iter_mut().zip(order) {
            *o = all[i];
        }
        Ok(())
    }

    /// Checks that an array argument holds exactly the model's count.
    fn check_count(what: &str, given: usize, expected: usize) -> Result<(), FmiError> {
        if given == expected {
            Ok(())
        } else {
            Err(FmiError::error(format!(
                "{given} {what} asked for, the model has {expected}"
            )))
        }
    }

    /// `GetDerivatives`: the point becomes a trial point of the delay
    /// history.
    pub fn get_derivatives(&mut self, out: &mut [f64]) -> Result<Status, FmiError> {
        self.check_exchange_runs()?;
        let all = self.state_derivatives()?;
        self.pick_states("derivatives", &all, out)?;
        Ok(Status::Ok)
    }

    /// `GetEventIndicators`.
    pub fn get_event_indicators(&mut self, out: &mut [f64]) -> Result<Status, FmiError> {
        Self::check_count(
            "event indicators",
            out.len(),
            self.model().event_indicators(),
        )?;
        if self.state.engine.chassis().is_some() {
            return self.check_exchange_runs().map(|()| Status::Ok);
        }
        out.copy_from_slice(&self.exchange()?.event_indicators()?);
        Ok(Status::Ok)
    }

    /// `GetContinuousStates`.
    pub fn get_continuous_states(&mut self, out: &mut [f64]) -> Result<Status, FmiError> {
        self.check_exchange_runs()?;
        let all = self.continuous_states()?;
        self.pick_states("continuous states", &all, out)?;
        Ok(Status::Ok)
    }

    /// `GetNominalsOfContinuousStates` (fixed, from the parameters'
    /// scales; see [`nominals`] and [`chassis_nominals`]).
    pub fn get_nominals(&mut self, out: &mut [f64]) -> Result<Status, FmiError> {
        let all = match self.model() {
            Model::Chassis => engine_states(&chassis_nominals()),
            Model::QuarterCar | Model::Corner => engine_states(&nominals()),
        };
        self.pick_states("nominals", &all, out)?;
        Ok(Status::Ok)
    }

    /// The continuous states for a getter, by the engine's index: Model
    /// Exchange's, the co-simulation's, or during initialization those of
    /// the start.
    pub(super) fn continuous_states(&mut self) -> Result<EngineStates, FmiError> {
        let chassis = self.model() == Model::Chassis;
        match &mut self.state.engine {
            Engine::ModelExchange(Some(model)) => Ok(engine_states(model.states())),
            Engine::CoSimulation(Some(sim)) => Ok(engine_states(&sim.continuous_states())),
            Engine::Chassis(Some(chassis)) | Engine::ChassisExchange(Some(chassis)) => {
                Ok(engine_states(&chassis.states()))
            }
            _ if chassis => Ok(engine_states(&self.build_chassis()?.states())),
            _ => Ok(engine_states(self.build_exchange()?.states())),
        }
    }

    /// The derivatives of [`Self::continuous_states`] (the chassis's in
    /// Model Exchange refused when one is not finite, naming it, as the
    /// suspension's are).
    pub(super) fn state_derivatives(&mut self) -> Result<EngineStates, FmiError> {
        let chassis = self.model() == Model::Chassis;
        match &mut self.state.engine {
            Engine::ModelExchange(Some(model)) => Ok(engine_states(&model.derivatives()?)),
            Engine::CoSimulation(Some(sim)) => {
                Ok(engine_states(&sim.continuous_state_derivatives()))
            }
            Engine::Chassis(Some(chassis)) => Ok(engine_states(&chassis.rates())),
            Engine::ChassisExchange(Some(chassis)) => Ok(engine_states(&chassis.derivatives()?)),
            _ if chassis => Ok(engine_states(&self.build_chassis()?.rates())),
            _ => Ok(engine_states(&self.build_exchange()?.derivatives()?)),
        }
    }

    /// The event indicators for a getter (the co-simulation: the elements'
    /// levels without hysteresis).
    pub(super) fn event_indicator_values(&mut self) -> Result<[f64; EVENT_INDICATORS], FmiError> {
        match &mut self.state.engine {
            Engine::ModelExchange(Some(model)) => Ok(model.event_indicators()?),
            Engine::CoSimulation(Some(sim)) => {
                let o = sim.outputs();
                let (x, road) = (o.state.as_slice(), o.road_displacement);
                let switching = sim.switching();
                Ok(SWITCHES.map(|switch| switching.level(switch, x, road)))
            }
            _ => Ok(self.build_exchange()?.event_indicators()?),
        }
    }
}
