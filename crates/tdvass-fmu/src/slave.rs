//! The version-neutral co-simulation slave: settings, simulator, phase,
//! logging and the FMU states handed out. No FFI and no FMI version here:
//! the FMI 2.0 and FMI 3.0 front-ends check their state tables, convert
//! their arguments and call these methods, which return
//! `Result<_, FmiError>`. Function names in log messages come from the
//! front-end's [`Dialect`].

use crate::defaults::Model;
use crate::error::{FmiError, Status};
use crate::guards;
use crate::phase::Phase;
use crate::settings::Settings;
use crate::variables::FmiVersion;
use std::collections::HashMap;
use std::fmt;
use tdvass::chassis::Chassis;
use tdvass::model::Params;
use tdvass::solver::{DelayGrid, Simulator};

mod exchange;
mod extrapolation;
mod fmu_states;
mod logger;
mod partials;
mod stepping;
mod values;

pub use crate::state::{Engine, SlaveState};
pub use exchange::{EventUpdate, StepCompletion};
pub use logger::{LogSink, Logger};
pub use stepping::extrapolation_slope;

/// How a front-end names what the slave's messages mention.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dialect {
    /// The FMI version (which variables exist).
    pub version: FmiVersion,
    /// Prefix of the C function names: `fmi2` or `fmi3`.
    pub prefix: &'static str,
    /// Where the master reads the time a discarded step stopped at.
    pub last_successful_time: &'static str,
    /// What tells the master to terminate.
    pub terminate_flag: &'static str,
    /// The setter of Real (Float64) values, without the prefix.
    pub set_float: &'static str,
    /// The setter of input derivatives, without the prefix.
    pub set_input_derivatives: &'static str,
    /// How the C names spell "FMU state" (`FMUstate`, `FMUState`).
    pub fmu_state: &'static str,
    /// The deserializer of FMU states, without the prefix.
    pub deserialize_state: &'static str,
    /// How the master gives the input's course over a step (the hold
    /// warning's remedy).
    pub input_slope_remedy: &'static str,
    /// The instantiation function, without the prefix.
    pub instantiate: &'static str,
    /// Model Exchange's event update, without the prefix.
    pub update_discrete_states: &'static str,
    /// The instantiation's argument that carries the token (`fmuGUID`).
    pub token_argument: &'static str,
    /// How a refused instantiation names the token the master passed.
    pub given_token: &'static str,
    /// How the messages name the FMU's own token (`GUID`, `token`).
    pub own_token: &'static str,
}

/// Communication steps longer than this (s) with a held, changing `x_g`
/// get one warning per instance (the default experiment's 1 ms stays
/// silent).
pub const HOLD_WARNING_STEP: f64 = 2e-3;

#[derive(Debug, Clone, PartialEq)]
struct SpectrumCache {
    params: Params,
    variant: i32,
    value: Result<f64, String>,
}

/// One co-simulation slave.
pub struct Slave {
    dialect: Dialect,
    /// The token serialized states carry (the GUID or instantiation token).
    token: String,
    logger: Logger,
    state: SlaveState,
    /// FMU states handed out, by their address (the handle the master gets).
    fmu_states: HashMap<usize, Box<SlaveState>>,
    spectrum: Option<SpectrumCache>,
    /// The value references of the last `GetReal`, looked up.
    read_plan: values::ReadPlan,
}

/// The C name of a function (`fmi2DoStep`, ...): its dialect's prefix and
/// the name, joined when a message is written.
#[derive(Debug, Clone, Copy)]
pub struct CallName {
    prefix: &'static str,
    function: &'static str,
}

impl fmt::Display for CallName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.prefix, self.function)
    }
}

impl Slave {
    /// A slave of `model` at its start values, speaking `dialect`;
    /// serialized states carry (and must match) `token`.
    pub fn new(dialect: Dialect, model: Model, token: String, logger: Logger) -> Slave {
        Slave {
            dialect,
            token,
            logger,
            state: SlaveState::new(Engine::CoSimulation(None), model),
            fmu_states: HashMap::new(),
            spectrum: None,
            read_plan: values::ReadPlan::default(),
        }
    }

    /// The C name of `function` (without prefix) in this dialect, written
    /// only when a message is (naming a call allocates nothing).
    pub fn call(&self, function: &'static str) -> CallName {
        CallName {
            prefix: self.dialect.prefix,
            function,
        }
    }

    /// The model the instance is of.
    pub fn model(&self) -> Model {
        self.state.settings.model
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.state.settings
    }

    /// The running simulation (after initialization).
    pub fn simulator(&self) -> Option<&Simulator> {
        self.state.engine.simulator()
    }

    /// Logs an event; the message is formatted only when events are on.
    fn event(&self, message: fmt::Arguments) {
        self.logger.log_lazily(Status::Ok, message);
    }

    /// Logs a warning; the message is formatted only when warnings are on.
    fn warning(&self, message: fmt::Arguments) {
        self.logger.log_lazily(Status::Warning, message);
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.state.phase
    }

    /// Moves the slave to `phase`. Private: the life-cycle methods (which
    /// a front-end calls only where its state table allows them) and the
    /// two failures below are the only changes of phase.
    fn set_phase(&mut self, phase: Phase) {
        self.state.phase = phase;
    }

    /// Reports the failure `e` of the call `function` (its C name, which
    /// prefixes the message) and returns its status. A `Fatal` failure
    /// leaves the slave in [`Phase::Fatal`].
    pub fn report_failure(&mut self, function: &str, e: &FmiError) -> Status {
        self.logger
            .log(e.status, &format!("{function}: {}", e.message));
        if e.status == Status::Fatal {
            self.set_phase(Phase::Fatal);
        }
        e.status
    }

    /// After a panic inside `function` (its C name): the slave may be
    /// inconsistent, so it goes to [`Phase::Fatal`], and says so.
    pub fn report_panic(&mut self, function: &str, message: &str) {
        self.set_phase(Phase::Fatal);
        self.logger.log(
            Status::Fatal,
            &format!(
                "{function}: internal error (panic: {message}); the instance is unusable, free it"
            ),
        );
    }

    /// How the front-end names what the slave's messages mention.
    pub fn dialect(&self) -> &Dialect {
        &self.dialect
    }

    /// The logger.
    pub fn logger(&self) -> &Logger {
        &self.logger
    }

    /// The logger, to switch categories.
    pub fn logger_mut(&mut self) -> &mut Logger {
        &mut self.logger
    }

    /// End of the last successful communication step (s).
    pub fn last_successful_time(&self) -> f64 {
        self.state.last_successful_time
    }

    /// Whether the slave asks the master to terminate (after a divergence).
    pub fn terminate_requested(&self) -> bool {
        self.state.terminate_requested
    }

    /// Number of FMU states currently owned by the instance.
    pub fn fmu_state_count(&self) -> usize {
        self.fmu_states.len()
    }

    // ------------------------------------------------------------- life cycle

    /// `SetupExperiment`. A defined tolerance becomes the relative
    /// accuracy of the run (it sets the internal step; see
    /// `tdvass::solver::accuracy`); an undefined one means the
    /// DefaultExperiment's, [`tdvass::solver::DEFAULT_TOLERANCE`].
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<Status, FmiError> {
        if !start_time.is_finite() {
            return Err(FmiError::error(format!(
                "invalid startTime {start_time}: must be finite"
            )));
        }
        if let Some(stop) = stop_time
            && !(stop.is_finite() && stop >= start_time)
        {
            return Err(FmiError::error(format!(
                "invalid stopTime {stop}: must be finite and >= startTime {start_time}"
            )));
        }
        let tolerance = tolerance.unwrap_or(tdvass::solver::DEFAULT_TOLERANCE);
        tdvass::solver::accuracy::check_tolerance(tolerance)?;
        self.state.settings.tolerance = tolerance;
        self.state.start_time = start_time;
        self.state.stop_time = stop_time;
        self.state.last_successful_time = start_time;
        Ok(Status::Ok)
    }

    /// `EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Result<Status, FmiError> {
        self.state.phase = Phase::InitializationMode;
        Ok(Status::Ok)
    }

    /// A simulator for the current settings at the start time, with the
    /// input applied.
    fn build_simulator(&self) -> Result<Simulator, FmiError> {
        let m = &self.state;
        guards::check_rates(&m.settings)?;
        let config = m.settings.to_config(m.start_time)?;
        // Checked before `Simulator::new` (which refuses the same start
        // times) for the FMU's message, which gives the limit in seconds.
        let tau = if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        };
        let choice = Simulator::choose_step(&config)?;
        let step = DelayGrid::new(tau, choice.step_bound)?.step;
        guards::check_time_resolution("startTime", m.start_time, step)?;
        let mut sim = Simulator::with_choice(config, choice)?;
        if m.settings.road_is_input() {
            sim.set_road_input(m.settings.x_g, m.input_slope)?;
        }
        // The inputs that prescribe coordinates (the corner's body
        // attachment), like the road input, are applied to the simulation
        // (the configuration does not depend on inputs).
        for (input, values) in m.settings.prescribed().into_iter().enumerate() {
            if let Some(values) = values {
                sim.set_prescribed(input, values)?;
            }
        }
        // Stepping, the getters and the setters allocate nothing from here
        // on (docs/fmu.md, "Real-time").
        sim.reserve();
        if let Some((name, value)) = guards::non_finite_output(m.settings.model, &sim.outputs()) {
            return Err(FmiError::error(format!(
                "the settings give a non-finite initial output `{name}` = {value}"
            )));
        }
        Ok(sim)
    }

    /// The chassis of the current settings at the start time, the forces
    /// applied (the parameters checked; an error names the one refused).
    fn build_chassis(&self) -> Result<Chassis, FmiError> {
        let s = &self.state.settings;
        let mut chassis = Chassis::new(s.chassis, self.state.start_time)?;
        chassis.set_forces(s.forces, s.force_rates)?;
        Ok(chassis)
    }

    /// `ExitInitializationMode`: validates every setting (an invalid
    /// one refuses the call, naming variable and value, and the instance
    /// stays in initialization mode), starts the simulation and checks
    /// stability (an unstable (g, tau) gives `Warning`).
    pub fn exit_initialization_mode(&mut self) -> Result<Status, FmiError> {
        if self.state.engine.is_model_exchange() {
            return self.exit_initialization_to_event_mode();
        }
        if self.model() == Model::Chassis {
            return self.exit_initialization_of_chassis();
        }
        let sim = self.build_simulator()?;
        let grid = sim.grid();
        self.state.engine = Engine::CoSimulation(Some(Box::new(sim)));
        self.state.input_pending = false;
        self.state.previous_input = Some((self.state.start_time, self.state.settings.x_g));
        self.state.earlier_input = None;
        self.start_input_history();
        self.state.phase = Phase::StepComplete;
        self.state.last_successful_time = self.state.start_time;
        self.state.terminate_requested = false;
        let s = &self.state.settings;
        self.event(format_args!(
            "{}: variant {}, road {}, tire_contact {}, tolerance {}, internal step {} s ({}), start {} s, stop {}",
            self.call("ExitInitializationMode"),
            s.variant,
            s.road,
            s.tire_contact,
            s.tolerance,
            grid.step,
            if grid.delay_inside_step() {
                "delay inside the step".to_string()
            } else {
                format!("{} steps per delay", grid.delay_steps())
            },
            self.state.start_time,
            self.state
                .stop_time
                .map(|t| format!("{t} s"))
                .unwrap_or_else(|| "not defined".into())
        ));
        Ok(self.stability_check(self.call("ExitInitializationMode")))
    }

    /// `ExitInitializationMode` of the chassis: its parameters checked, at
    /// rest at the static equilibrium under the forces set.
    fn exit_initialization_of_chassis(&mut self) -> Result<Status, FmiError> {
        let chassis = self.build_chassis()?;
        self.state.engine = Engine::Chassis(Some(Box::new(chassis)));
        self.state.input_pending = false;
        self.start_input_history();
        self.state.phase = Phase::StepComplete;
        self.state.last_successful_time = self.state.start_time;
        self.state.terminate_requested = false;
        let p = self.state.settings.chassis;
        self.event(format_args!(
            "{}: chassis of {} kg, a = {} m, b = {} m, pitch inertia {} kg m2, roll inertia {} kg m2, start {} s",
            self.call("ExitInitializationMode"),
            p.mass,
            p.a,
            p.b,
            p.pitch_inertia,
            p.roll_inertia,
            self.state.start_time
        ));
        Ok(Status::Ok)
    }

    /// Logs a warning (and returns `Warning`) when (g, tau) is unstable.
    fn stability_check(&mut self, function: CallName) -> Status {
        let s = self.state.settings;
        match self.spectral_abscissa() {
            Ok(a) if a >= 0.0 => {
                self.warning(format_args!(
                    "{function}: unstable feedback: g = {} N/m, tau = {} s gives spectral abscissa {a} 1/s >= 0; the response will grow without bound",
                    s.params.g, s.params.tau
                ));
                Status::Warning
            }
            Ok(_) => Status::Ok,
            Err(e) => {
                self.warning(format_args!(
                    "{function}: stability of g = {} N/m, tau = {} s not determined: {e}",
                    s.params.g, s.params.tau
                ));
                Status::Warning
            }
        }
    }

    /// `Terminate`.
    pub fn terminate(&mut self) -> Result<Status, FmiError> {
        self.state.phase = Phase::Terminated;
        self.event(format_args!(
            "{}: at t = {} s",
            self.call("Terminate"),
            self.time()
        ));
        Ok(Status::Ok)
    }

    /// `Reset`: back to `instantiated` with every start value (time,
    /// history, road generator, RMS accumulators, stop time all reset). FMU
    /// states handed out stay valid.
    pub fn reset(&mut self) -> Result<Status, FmiError> {
        self.state = SlaveState::new(self.state.engine.emptied(), self.model());
        self.event(format_args!(
            "{}: back to the start values",
            self.call("Reset")
        ));
        Ok(Status::Ok)
    }

    /// Current time: the simulator's, or the start time before initialization.
    pub fn time(&self) -> f64 {
        match &self.state.engine {
            Engine::ModelExchange(Some(model)) => model.time(),
            Engine::CoSimulation(Some(sim)) => sim.time(),
            Engine::Chassis(Some(chassis)) | Engine::ChassisExchange(Some(chassis)) => {
                chassis.time()
            }
            _ => self.state.start_time,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
