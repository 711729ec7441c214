//! What an FMU state copies: the slave's life-cycle phase, settings,
//! input bookkeeping and the engine that integrates the instance. Below
//! the slave and the byte format of FMU states ([`crate::snapshot`]), which
//! both use it.

use crate::defaults::Model;
use crate::phase::Phase;
use crate::settings::Settings;
use tdvass::chassis::Chassis;
use tdvass::exchange::ModelExchange;
use tdvass::solver::Simulator;

/// What integrates an instance: the kind it was made for (at
/// instantiation) and, from the end of initialization on, its model. One
/// value, so that a Co-Simulation instance never holds a Model Exchange
/// model or the other way round.
#[derive(Debug, Clone)]
pub enum Engine {
    /// The precise integration by the FMU itself (`DoStep`).
    CoSimulation(Option<Box<Simulator>>),
    /// The master's solver integrates the states (`GetDerivatives`).
    ModelExchange(Option<Box<ModelExchange>>),
    /// The chassis's exact rigid-body step (`DoStep`; [`Model::Chassis`]).
    Chassis(Option<Box<Chassis>>),
    /// The master's solver integrates the chassis's states
    /// ([`Chassis::states`]; [`Model::Chassis`] in Model Exchange).
    ChassisExchange(Option<Box<Chassis>>),
}

impl Engine {
    /// Whether the instance was made for Model Exchange.
    pub fn is_model_exchange(&self) -> bool {
        matches!(self, Engine::ModelExchange(_) | Engine::ChassisExchange(_))
    }

    /// The same kind, without a model (before initialization).
    pub fn emptied(&self) -> Engine {
        match self {
            Engine::CoSimulation(_) => Engine::CoSimulation(None),
            Engine::ModelExchange(_) => Engine::ModelExchange(None),
            Engine::Chassis(_) => Engine::Chassis(None),
            Engine::ChassisExchange(_) => Engine::ChassisExchange(None),
        }
    }

    /// Whether a model runs (after initialization).
    pub fn is_running(&self) -> bool {
        matches!(
            self,
            Engine::CoSimulation(Some(_))
                | Engine::ModelExchange(Some(_))
                | Engine::Chassis(Some(_))
                | Engine::ChassisExchange(Some(_))
        )
    }

    /// The kind's name in messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Engine::CoSimulation(_) | Engine::Chassis(_) => "Co-Simulation",
            Engine::ModelExchange(_) | Engine::ChassisExchange(_) => "Model Exchange",
        }
    }

    /// The co-simulation's simulator, if it runs.
    pub fn simulator(&self) -> Option<&Simulator> {
        match self {
            Engine::CoSimulation(Some(sim)) => Some(sim),
            _ => None,
        }
    }

    /// The co-simulation's simulator, if it runs.
    pub fn simulator_mut(&mut self) -> Option<&mut Simulator> {
        match self {
            Engine::CoSimulation(Some(sim)) => Some(sim),
            _ => None,
        }
    }

    /// The chassis, if it runs (either kind).
    pub fn chassis(&self) -> Option<&Chassis> {
        match self {
            Engine::Chassis(Some(chassis)) | Engine::ChassisExchange(Some(chassis)) => {
                Some(chassis)
            }
            _ => None,
        }
    }

    /// The chassis, if it runs (either kind).
    pub fn chassis_mut(&mut self) -> Option<&mut Chassis> {
        match self {
            Engine::Chassis(Some(chassis)) | Engine::ChassisExchange(Some(chassis)) => {
                Some(chassis)
            }
            _ => None,
        }
    }

    /// The Model Exchange model, if it runs.
    pub fn exchange(&self) -> Option<&ModelExchange> {
        match self {
            Engine::ModelExchange(Some(model)) => Some(model),
            _ => None,
        }
    }

    /// The Model Exchange model, if it runs.
    pub fn exchange_mut(&mut self) -> Option<&mut ModelExchange> {
        match self {
            Engine::ModelExchange(Some(model)) => Some(model),
            _ => None,
        }
    }
}

/// Everything that makes up an FMU state (what getting an FMU state copies
/// and serializing it writes).
#[derive(Debug, Clone)]
pub struct SlaveState {
    /// Where the slave is in its life cycle.
    pub phase: Phase,
    /// Parameter and input values.
    pub settings: Settings,
    /// Slope of `x_g` (m/s) set by `an input derivative`.
    pub input_slope: f64,
    /// `x_g` or its slope changed since they were last applied to the road.
    pub input_pending: bool,
    /// The slope came from `an input derivative` (since `x_g` was
    /// last set); it then takes precedence over `input_extrapolation`.
    pub input_slope_given: bool,
    /// `(t, x_g)` of the last value applied at a communication point: the
    /// earlier of the two values that `input_extrapolation = 1` uses.
    pub previous_input: Option<(f64, f64)>,
    /// `(t, x_g)` of the value applied before `previous_input` (the third
    /// value of `input_extrapolation = 2`).
    pub earlier_input: Option<(f64, f64)>,
    /// The vehicle bonds' inputs at the last communication points, for
    /// `input_extrapolation`.
    pub bonds: BondHistory,
    /// The hold warning of a communication step was logged.
    pub hold_warned: bool,
    /// The first loss of tire contact was logged (bilateral tire; the
    /// unilateral tire logs every lift-off as an event instead).
    pub contact_warned: bool,
    /// Start time from `the experiment set-up` (s).
    pub start_time: f64,
    /// Stop time from `the experiment set-up`, if defined (s).
    pub stop_time: Option<f64>,
    /// End of the last successful communication step (s).
    pub last_successful_time: f64,
    /// The FMU asks the master to terminate (after a divergence).
    pub terminate_requested: bool,
    /// The kind of instance and, from the end of initialization on, what
    /// integrates it.
    pub engine: Engine,
}

impl SlaveState {
    /// A freshly instantiated `model` of the kind `engine` says (the
    /// chassis's own engine for a Co-Simulation chassis): start values, no
    /// simulation.
    pub fn new(engine: Engine, model: Model) -> SlaveState {
        let engine = match (model, engine) {
            (Model::Chassis, Engine::CoSimulation(_) | Engine::Chassis(_)) => Engine::Chassis(None),
            (Model::Chassis, Engine::ModelExchange(_) | Engine::ChassisExchange(_)) => {
                Engine::ChassisExchange(None)
            }
            (_, engine) => engine.emptied(),
        };
        SlaveState {
            phase: Phase::Instantiated,
            settings: Settings::start_values(model),
            input_slope: 0.0,
            input_pending: false,
            input_slope_given: false,
            previous_input: None,
            earlier_input: None,
            bonds: BondHistory::default(),
            hold_warned: false,
            contact_warned: false,
            start_time: crate::defaults::DEFAULT_START_TIME,
            stop_time: None,
            last_successful_time: crate::defaults::DEFAULT_START_TIME,
            terminate_requested: false,
            engine,
        }
    }
}

impl Default for SlaveState {
    /// A Co-Simulation instance's of the quarter car.
    fn default() -> Self {
        SlaveState::new(Engine::CoSimulation(None), Model::QuarterCar)
    }
}

/// What `input_extrapolation` continues the vehicle's bonds from in
/// Co-Simulation (`slave/extrapolation.rs`): a corner's body velocity, the
/// chassis's forces.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BondHistory {
    /// `(t, body_velocity)` of a corner's body input applied at the last
    /// communication point that set it.
    pub previous_body: Option<(f64, f64)>,
    /// A corner's body inputs were set since a step last applied them.
    pub body_pending: bool,
    /// The body attachment's extrapolated acceleration (m/s^2) in force
    /// (0: the attachment moves at its velocity).
    pub body_acceleration: f64,
    /// Per force of the chassis (in [`tdvass::chassis::Corner::ALL`]
    /// order), `(t, force)` applied at the last communication point that
    /// set it.
    pub previous_forces: [Option<(f64, f64)>; 4],
    /// Bit i: the chassis's force i was set since a step last applied it,
    /// and its derivative not given since.
    pub forces_pending: u8,
}
