//! The safe FMU instance: settings, simulator, machine state, logger and the
//! FMU states it handed out. No FFI here; [`crate::ffi`] calls these methods
//! through [`Instance::run`], which enforces the state table and logs every
//! failure.

use crate::states::{self, Function, MachineState};
use crate::variables::{
    Access, Calculated, Causality, Known, Linearization, OutputId, Settings, VarType, Variability,
    Variable, by_vr,
};
use crate::{FmiError, LOG_CATEGORIES, Status, TIME_TOLERANCE, limits, snapshot};
use std::collections::HashMap;
use std::path::PathBuf;
use tdvass::model::{Params, V_S, Variant};
use tdvass::solver::{DelayGrid, Outputs, Simulator};

/// Receives log messages: `(status, category, message)`.
pub type LogSink = Box<dyn Fn(Status, &str, &str)>;

/// `fmi2Type` of a Co-Simulation instance.
pub const FMI2_COSIMULATION: i32 = 1;
/// `fmi2Type` of a Model Exchange instance.
pub const FMI2_MODEL_EXCHANGE: i32 = 0;

/// `fmi2StatusKind` values.
pub mod status_kind {
    pub const DO_STEP_STATUS: i32 = 0;
    pub const PENDING_STATUS: i32 = 1;
    pub const LAST_SUCCESSFUL_TIME: i32 = 2;
    pub const TERMINATED: i32 = 3;
}

/// Communication steps longer than this (s) with a held, changing `x_g`
/// get one warning per instance (the default experiment's 1 ms stays
/// silent).
pub const HOLD_WARNING_STEP: f64 = 2e-3;

/// The slope of the straight line that continues the input over a step of
/// length `h` from its last value `(t_k, x_k)` (the last of `values`, in
/// time order, at most three):
/// - one value: 0 (held);
/// - two values: the line through both, `(x_k − x_{k−1}) / (t_k − t_{k−1})`
///   (it lags a curved input by about `(5/12) h² ẍ` on average over a step);
/// - three values: the parabola q through them, and of the lines through
///   `(t_k, x_k)` the one closest to q over the step in the mean square,
///   slope `q'(t_k) + 3 q'' h / 8` (mean lag `q'' h² / 48`, twenty times
///   less).
///
/// Times that do not increase give 0.
pub fn extrapolation_slope(values: &[(f64, f64)], h: f64) -> f64 {
    match *values {
        [.., (t1, x1), (t2, x2)] if t2 > t1 => {
            let last = (x2 - x1) / (t2 - t1);
            match *values {
                [(t0, x0), _, _] if t1 > t0 => {
                    let before = (x1 - x0) / (t1 - t0);
                    let curvature = 2.0 * (last - before) / (t2 - t0);
                    last + 0.5 * curvature * (t2 - t1) + 0.375 * curvature * h
                }
                _ => last,
            }
        }
        _ => 0.0,
    }
}

/// Everything that makes up an FMU state (what `fmi2GetFMUstate` copies and
/// `fmi2SerializeFMUstate` writes).
#[derive(Debug, Clone)]
pub struct Model {
    /// Machine state.
    pub machine: MachineState,
    /// Parameter and input values.
    pub settings: Settings,
    /// Slope of `x_g` (m/s) set by `fmi2SetRealInputDerivatives`.
    pub input_slope: f64,
    /// `x_g` or its slope changed since they were last applied to the road.
    pub input_pending: bool,
    /// The slope came from `fmi2SetRealInputDerivatives` (since `x_g` was
    /// last set); it then takes precedence over `input_extrapolation`.
    pub input_slope_given: bool,
    /// `(t, x_g)` of the last value applied at a communication point: the
    /// earlier of the two values that `input_extrapolation = 1` uses.
    pub previous_input: Option<(f64, f64)>,
    /// `(t, x_g)` of the value applied before `previous_input` (the third
    /// value of `input_extrapolation = 2`).
    pub earlier_input: Option<(f64, f64)>,
    /// The hold warning of [`Instance::do_step`] was logged.
    pub hold_warned: bool,
    /// Start time from `fmi2SetupExperiment` (s).
    pub start_time: f64,
    /// Stop time from `fmi2SetupExperiment`, if defined (s).
    pub stop_time: Option<f64>,
    /// End of the last successful communication step (s).
    pub last_successful_time: f64,
    /// The FMU asks the master to terminate (after a divergence).
    pub terminate_requested: bool,
    /// The simulation, from `fmi2ExitInitializationMode` on.
    pub sim: Option<Simulator>,
}

impl Model {
    /// A freshly instantiated model: start values, no simulation.
    pub fn new() -> Model {
        Model {
            machine: MachineState::Instantiated,
            settings: Settings::start_values(),
            input_slope: 0.0,
            input_pending: false,
            input_slope_given: false,
            previous_input: None,
            earlier_input: None,
            hold_warned: false,
            start_time: crate::DEFAULT_START_TIME,
            stop_time: None,
            last_successful_time: crate::DEFAULT_START_TIME,
            terminate_requested: false,
            sim: None,
        }
    }
}

impl Default for Model {
    fn default() -> Self {
        Model::new()
    }
}

/// What `fmi2Instantiate` was given (strings already copied out of C).
#[derive(Debug, Clone, Default)]
pub struct InstantiateRequest<'a> {
    pub instance_name: Option<&'a str>,
    pub fmu_type: i32,
    pub guid: Option<&'a str>,
    pub resource_location: Option<&'a str>,
    pub logging_on: bool,
}

#[derive(Debug, Clone, PartialEq)]
struct SpectrumCache {
    params: Params,
    variant: i32,
    value: Result<f64, String>,
}

/// One FMU instance.
pub struct Instance {
    name: String,
    guid: String,
    logger: LogSink,
    /// Enabled flags of the categories of [`LOG_CATEGORIES`] (without `logAll`).
    log_enabled: [bool; 5],
    resource_path: Option<PathBuf>,
    model: Model,
    /// FMU states handed out, by their address (the `fmi2FMUstate` value).
    fmu_states: HashMap<usize, Box<Model>>,
    spectrum: Option<SpectrumCache>,
}

fn category_of(status: Status) -> usize {
    match status {
        Status::Ok | Status::Pending => 0,
        Status::Warning => 1,
        Status::Discard => 2,
        Status::Error => 3,
        Status::Fatal => 4,
    }
}

impl Instance {
    /// `fmi2Instantiate`: checks the request and creates the instance. A
    /// refusal is logged through `logger` and returns `None`.
    pub fn instantiate(request: InstantiateRequest<'_>, logger: LogSink) -> Option<Instance> {
        let refuse = |message: String| {
            logger(
                Status::Error,
                "logStatusError",
                &format!("fmi2Instantiate: {message}"),
            );
            None
        };
        let expected = crate::guid();
        let name = match request.instance_name {
            None => return refuse("instanceName is NULL".into()),
            Some("") => return refuse("instanceName is empty".into()),
            Some(name) => name.to_string(),
        };
        match request.fmu_type {
            FMI2_COSIMULATION => {}
            FMI2_MODEL_EXCHANGE => {
                return refuse(
                    "fmuType fmi2ModelExchange is not supported: this FMU implements Co-Simulation only".into(),
                );
            }
            other => return refuse(format!("unknown fmuType {other}")),
        }
        match request.guid {
            None => return refuse("fmuGUID is NULL".into()),
            Some(g) if g != expected => {
                return refuse(format!(
                    "GUID {g} does not match this FMU's GUID {expected} (modelDescription.xml and binary are from different builds)"
                ));
            }
            Some(_) => {}
        }
        let resource_path = match request.resource_location {
            None | Some("") => None,
            Some(uri) => match crate::uri::resource_path(uri) {
                Ok(path) => Some(path),
                Err(reason) => {
                    return refuse(format!(
                        "fmuResourceLocation `{uri}` is not a valid file URI: {reason}"
                    ));
                }
            },
        };
        let instance = Instance {
            name,
            guid: expected,
            logger,
            log_enabled: [request.logging_on, true, true, true, true],
            resource_path,
            model: Model::new(),
            fmu_states: HashMap::new(),
            spectrum: None,
        };
        instance.event(format!(
            "fmi2Instantiate: instance `{}` of {} (GUID {}), resources {}",
            instance.name,
            crate::MODEL_NAME,
            instance.guid,
            instance
                .resource_path
                .as_ref()
                .map(|p| format!("at {}", p.display()))
                .unwrap_or_else(|| "not given".into())
        ));
        Some(instance)
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The machine state.
    pub fn machine_state(&self) -> MachineState {
        self.model.machine
    }

    /// The resources directory given at instantiation.
    pub fn resource_path(&self) -> Option<&std::path::Path> {
        self.resource_path.as_deref()
    }

    /// Number of FMU states currently owned by the instance.
    pub fn fmu_state_count(&self) -> usize {
        self.fmu_states.len()
    }

    // ---------------------------------------------------------------- logging

    fn log(&self, status: Status, message: &str) {
        let category = category_of(status);
        // Discard, Error and Fatal are always reported.
        if category >= 2 || self.log_enabled[category] {
            (self.logger)(status, LOG_CATEGORIES[category].0, message);
        }
    }

    fn event(&self, message: String) {
        self.log(Status::Ok, &message);
    }

    fn warning(&self, message: String) {
        self.log(Status::Warning, &message);
    }

    /// Runs `op` as `function`: refuses it (fmi2Error, logged "fmi2X: not
    /// allowed in state Y") when the state table forbids it in the current
    /// state, and logs any failure with the function name. A refused call
    /// changes nothing; `fmi2Fatal` moves the instance to `fatal`.
    pub fn run<T>(
        &mut self,
        function: Function,
        op: impl FnOnce(&mut Self) -> Result<T, FmiError>,
    ) -> Result<T, Status> {
        let result = states::check(function, self.model.machine).and_then(|()| op(self));
        result.map_err(|e| {
            self.log(e.status, &format!("{}: {}", function.name(), e.message));
            if e.status == Status::Fatal {
                self.model.machine = MachineState::Fatal;
            }
            e.status
        })
    }

    /// After a panic inside `function` (caught by the FFI layer): the
    /// instance may be inconsistent, so it goes to `fatal`.
    pub fn on_panic(&mut self, function: Function, message: &str) {
        self.model.machine = MachineState::Fatal;
        self.log(
            Status::Fatal,
            &format!(
                "{}: internal error (panic: {message}); the instance is unusable, free it",
                function.name()
            ),
        );
    }

    /// Logs that a Model Exchange function was called.
    pub fn refuse_model_exchange(&self, function: &str) -> Status {
        self.log(
            Status::Error,
            &format!("{function}: Model Exchange function; this FMU implements Co-Simulation only"),
        );
        Status::Error
    }

    /// `fmi2SetDebugLogging`: `categories` empty means all. Unknown
    /// categories refuse the whole call.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<Status, FmiError> {
        let mut enabled = self.log_enabled;
        if categories.is_empty() {
            enabled = [on; 5];
        }
        for &category in categories {
            match LOG_CATEGORIES
                .iter()
                .position(|(name, _)| *name == category)
            {
                Some(5) => enabled = [on; 5],
                Some(i) => enabled[i] = on,
                None => {
                    let known: Vec<_> = LOG_CATEGORIES.iter().map(|(n, _)| *n).collect();
                    return Err(FmiError::error(format!(
                        "unknown log category `{category}` (known: {})",
                        known.join(", ")
                    )));
                }
            }
        }
        self.log_enabled = enabled;
        Ok(Status::Ok)
    }

    // ------------------------------------------------------------- life cycle

    /// `fmi2SetupExperiment`. The tolerance is ignored: the integration is
    /// exact up to rounding for the internal step `max_internal_step`.
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
        if let Some(tol) = tolerance {
            self.event(format!(
                "fmi2SetupExperiment: tolerance {tol} ignored (accuracy is set by max_internal_step)"
            ));
        }
        self.model.start_time = start_time;
        self.model.stop_time = stop_time;
        self.model.last_successful_time = start_time;
        Ok(Status::Ok)
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Result<Status, FmiError> {
        self.model.machine = MachineState::InitializationMode;
        Ok(Status::Ok)
    }

    /// A simulator for the current settings at the start time, with the
    /// input applied.
    fn build_simulator(&self) -> Result<Simulator, FmiError> {
        let m = &self.model;
        limits::check_rates(&m.settings)?;
        let config = m.settings.to_config(m.start_time)?;
        // Checked before `Simulator::new` (which refuses the same start
        // times) for the FMU's message, which gives the limit in seconds.
        let tau = if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        };
        let step = DelayGrid::new(tau, config.max_internal_step)?.step;
        limits::check_time_resolution("startTime", m.start_time, step)?;
        let mut sim = Simulator::new(config)?;
        if m.settings.road_is_input() {
            sim.set_road_input(m.settings.x_g, m.input_slope)?;
        }
        if let Some((name, value)) = limits::non_finite_output(&sim.outputs()) {
            return Err(FmiError::error(format!(
                "the settings give a non-finite initial output `{name}` = {value}"
            )));
        }
        Ok(sim)
    }

    /// `fmi2ExitInitializationMode`: validates every setting (an invalid
    /// one refuses the call, naming variable and value, and the instance
    /// stays in initialization mode), starts the simulation and checks
    /// stability (an unstable (g, tau) gives `fmi2Warning`).
    pub fn exit_initialization_mode(&mut self) -> Result<Status, FmiError> {
        let sim = self.build_simulator()?;
        let grid = sim.grid();
        self.model.sim = Some(sim);
        self.model.input_pending = false;
        self.model.previous_input = Some((self.model.start_time, self.model.settings.x_g));
        self.model.earlier_input = None;
        self.model.machine = MachineState::StepComplete;
        self.model.last_successful_time = self.model.start_time;
        self.model.terminate_requested = false;
        let s = &self.model.settings;
        self.event(format!(
            "fmi2ExitInitializationMode: variant {}, road {}, internal step {} s ({}), start {} s, stop {}",
            s.variant,
            s.road,
            grid.step,
            if grid.delay_inside_step() {
                "delay inside the step".to_string()
            } else {
                format!("{} steps per delay", grid.delay_steps())
            },
            self.model.start_time,
            self.model
                .stop_time
                .map(|t| format!("{t} s"))
                .unwrap_or_else(|| "not defined".into())
        ));
        Ok(self.stability_check("fmi2ExitInitializationMode"))
    }

    /// Logs a warning (and returns `fmi2Warning`) when (g, tau) is unstable.
    fn stability_check(&mut self, function: &str) -> Status {
        let s = self.model.settings;
        match self.spectral_abscissa() {
            Ok(a) if a >= 0.0 => {
                self.warning(format!(
                    "{function}: unstable feedback: g = {} N/m, tau = {} s gives spectral abscissa {a} 1/s >= 0; the response will grow without bound",
                    s.g, s.tau
                ));
                Status::Warning
            }
            Ok(_) => Status::Ok,
            Err(e) => {
                self.warning(format!(
                    "{function}: stability of g = {} N/m, tau = {} s not determined: {e}",
                    s.g, s.tau
                ));
                Status::Warning
            }
        }
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<Status, FmiError> {
        self.model.machine = MachineState::Terminated;
        self.event(format!("fmi2Terminate: at t = {} s", self.time()));
        Ok(Status::Ok)
    }

    /// `fmi2Reset`: back to `instantiated` with every start value (time,
    /// history, road generator, RMS accumulators, stop time all reset). FMU
    /// states handed out stay valid.
    pub fn reset(&mut self) -> Result<Status, FmiError> {
        self.model = Model::new();
        self.event("fmi2Reset: back to the start values".into());
        Ok(Status::Ok)
    }

    /// Current time: the simulator's, or the start time before initialization.
    pub fn time(&self) -> f64 {
        self.model
            .sim
            .as_ref()
            .map(Simulator::time)
            .unwrap_or(self.model.start_time)
    }

    // ------------------------------------------------------------ get and set

    fn variable(&self, vr: u32, ty: VarType) -> Result<&'static Variable, FmiError> {
        let var = by_vr(vr).ok_or_else(|| {
            FmiError::error(format!(
                "unknown value reference {vr} (for a {})",
                ty.as_str()
            ))
        })?;
        if var.var_type() != ty {
            return Err(FmiError::error(format!(
                "value reference {vr} is `{}`, a {}, not a {}",
                var.name,
                var.var_type().as_str(),
                ty.as_str()
            )));
        }
        Ok(var)
    }

    /// The outputs now: from the simulation, or during initialization from
    /// a simulator built from the current settings.
    fn outputs(&mut self) -> Result<Outputs, FmiError> {
        match self.model.sim.as_mut() {
            Some(sim) => Ok(sim.outputs()),
            None => Ok(self.build_simulator()?.outputs()),
        }
    }

    /// The spectral abscissa at the current settings (cached).
    pub fn spectral_abscissa(&mut self) -> Result<f64, FmiError> {
        let params = self.model.settings.params();
        let variant = self.model.settings.variant;
        let fresh = self
            .spectrum
            .as_ref()
            .is_some_and(|c| c.params == params && c.variant == variant);
        if !fresh {
            let value = Variant::from_code(variant as i64)
                .and_then(|v| tdvass::analysis::spectrum::spectral_abscissa(&params, v))
                .map_err(|e| e.to_string());
            self.spectrum = Some(SpectrumCache {
                params,
                variant,
                value,
            });
        }
        match &self.spectrum {
            Some(SpectrumCache { value: Ok(a), .. }) => Ok(*a),
            Some(SpectrumCache { value: Err(e), .. }) => Err(FmiError::error(format!(
                "spectral abscissa not available: {e}"
            ))),
            None => unreachable!("filled above"),
        }
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<Status, FmiError> {
        let mut outputs = None;
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            let var = self.variable(vr, VarType::Real)?;
            *value = match var.access {
                Access::Real { get, .. } => get(&self.model.settings),
                Access::Output(id) => {
                    if outputs.is_none() {
                        outputs = Some(self.outputs()?);
                    }
                    id.value(outputs.as_ref().expect("computed above"))
                }
                Access::Calculated(Calculated::SpectralAbscissa) => self.spectral_abscissa()?,
                Access::Integer { .. } | Access::Calculated(Calculated::Stable) => {
                    unreachable!("type checked")
                }
            };
            if !value.is_finite() {
                let bad = std::mem::replace(value, 0.0);
                return Err(FmiError::error(format!(
                    "`{}` = {bad} is not finite; no value returned",
                    var.name
                )));
            }
        }
        Ok(Status::Ok)
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<Status, FmiError> {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.variable(vr, VarType::Integer)?.access {
                Access::Integer { get, .. } => *value = get(&self.model.settings),
                _ => unreachable!("type checked"),
            }
        }
        Ok(Status::Ok)
    }

    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], values: &mut [bool]) -> Result<Status, FmiError> {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.variable(vr, VarType::Boolean)?.access {
                Access::Calculated(Calculated::Stable) => *value = self.spectral_abscissa()? < 0.0,
                _ => unreachable!("type checked"),
            }
        }
        Ok(Status::Ok)
    }

    /// `fmi2GetString`: there are no String variables, so any value
    /// reference is refused.
    pub fn get_string(&mut self, vrs: &[u32]) -> Result<Status, FmiError> {
        for &vr in vrs {
            self.variable(vr, VarType::String)?;
        }
        Ok(Status::Ok)
    }

    /// Whether `var` may be set now to `value` (the state table already
    /// allows setting something).
    fn check_settable(&self, var: &Variable, value: f64) -> Result<(), FmiError> {
        match (var.causality, var.variability) {
            (Causality::Output, _) => Err(FmiError::error(format!(
                "`{}` is an output and cannot be set (value {value} refused)",
                var.name
            ))),
            (Causality::CalculatedParameter, _) => Err(FmiError::error(format!(
                "`{}` is a calculated parameter and cannot be set (value {value} refused)",
                var.name
            ))),
            (Causality::Parameter, Variability::Fixed) if self.model.machine.is_simulating() => {
                Err(FmiError::error(format!(
                    "`{}` is a fixed parameter and cannot be changed after initialization (value {value} refused; reset the instance to change it)",
                    var.name
                )))
            }
            _ => {
                var.range.check(var.name, value)?;
                limits::check_value(var.name, value)
            }
        }
    }

    /// Applies a checked Real value; tunable parameters reach the running
    /// simulation at once.
    fn apply_real(&mut self, var: &Variable, value: f64) -> Result<(), FmiError> {
        let Access::Real { set, .. } = var.access else {
            unreachable!("only settable Reals get here")
        };
        set(&mut self.model.settings, value);
        let weights = self.model.settings.weights();
        match (var.name, self.model.sim.as_mut()) {
            ("x_g", _) => {
                self.model.input_slope = 0.0;
                self.model.input_slope_given = false;
                self.model.input_pending = true;
            }
            ("g", Some(sim)) => sim.set_gain(value)?,
            ("w_ba" | "w_sdd" | "w_tdd", Some(sim)) => sim.set_weights(weights),
            _ => {}
        }
        Ok(())
    }

    /// `fmi2SetReal`. All values are checked first; a refused value leaves
    /// every variable unchanged. Tuning `g` to an unstable value while
    /// simulating gives `fmi2Warning`.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<Status, FmiError> {
        let mut checked = Vec::with_capacity(vrs.len());
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            self.check_settable(var, value)?;
            checked.push((var, value));
        }
        if self.model.machine.is_simulating() {
            let mut candidate = self.model.settings;
            for (var, value) in &checked {
                if let Access::Real { set, .. } = var.access {
                    set(&mut candidate, *value);
                }
            }
            limits::check_rates(&candidate)?;
        }
        let mut gain_tuned = false;
        for (var, value) in checked {
            self.apply_real(var, value)?;
            gain_tuned |= var.name == "g";
        }
        if gain_tuned && self.model.machine.is_simulating() {
            return Ok(self.stability_check("fmi2SetReal"));
        }
        Ok(Status::Ok)
    }

    /// `fmi2SetInteger` (all Integer variables are fixed parameters).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<Status, FmiError> {
        let mut checked = Vec::with_capacity(vrs.len());
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Integer)?;
            self.check_settable(var, value as f64)?;
            checked.push((var, value));
        }
        for (var, value) in checked {
            if let Access::Integer { set, .. } = var.access {
                set(&mut self.model.settings, value);
            }
        }
        Ok(Status::Ok)
    }

    /// `fmi2SetBoolean`: the only Boolean is a calculated parameter.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<Status, FmiError> {
        for (&vr, &value) in vrs.iter().zip(values) {
            let var = self.variable(vr, VarType::Boolean)?;
            self.check_settable(var, value as i32 as f64)?;
        }
        Ok(Status::Ok)
    }

    /// `fmi2SetString`: there are no String variables.
    pub fn set_string(&mut self, vrs: &[u32]) -> Result<Status, FmiError> {
        self.get_string(vrs)
    }

    // ------------------------------------------------------------------ steps

    /// `fmi2DoStep` from `t` (must equal the FMU time to a relative 1e-9)
    /// over `h` (> 0, finite, not past a defined stop time). A divergence
    /// returns `fmi2Discard`: the instance stays at the last good grid node
    /// (`fmi2LastSuccessfulTime`), asks for termination (`fmi2Terminated`)
    /// and goes to `stepFailed`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Status, FmiError> {
        let now = self.time();
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::error(format!(
                "invalid communicationStepSize {h}: must be finite and > 0"
            )));
        }
        if !t.is_finite() || (t - now).abs() > TIME_TOLERANCE * now.abs().max(t.abs()).max(h) {
            return Err(FmiError::error(format!(
                "currentCommunicationPoint {t} does not match the FMU time {now}"
            )));
        }
        let target = (t + h).max(now);
        if !target.is_finite() {
            return Err(FmiError::error(format!(
                "a step of {h} s from {t} s does not end at a finite time"
            )));
        }
        if let Some(stop) = self.model.stop_time
            && target > stop + TIME_TOLERANCE * stop.abs().max(h)
        {
            return Err(FmiError::error(format!(
                "a step of {h} s from {t} s ends at {target} s, past the stop time {stop} s"
            )));
        }
        let settings = self.model.settings;
        let pending = self.model.input_pending;
        let slope = if settings.road_is_input() {
            self.input_slope_for_step(now, h)?
        } else {
            0.0
        };
        let Some(sim) = self.model.sim.as_mut() else {
            unreachable!("stepComplete has a simulator")
        };
        limits::check_step_work(&settings, sim.grid().step, target - now)?;
        limits::check_time_resolution("the step end", target, sim.grid().step)?;
        if pending && settings.road_is_input() {
            sim.set_road_input(settings.x_g, slope)?;
            self.model.earlier_input = self.model.previous_input;
            self.model.previous_input = Some((now, settings.x_g));
        }
        self.model.input_pending = false;
        match sim.advance_to(target) {
            Ok(()) => match limits::non_finite_output(&sim.outputs()) {
                None => {
                    self.model.last_successful_time = sim.time();
                    Ok(Status::Ok)
                }
                Some((name, value)) => {
                    self.model.terminate_requested = true;
                    self.model.machine = MachineState::StepFailed;
                    Err(FmiError::discard(format!(
                        "output `{name}` = {value} is not finite at t = {target} s; the outputs are not available, fmi2LastSuccessfulTime is {} s, the FMU asks to terminate (fmi2Terminated)",
                        self.model.last_successful_time
                    )))
                }
            },
            Err(e @ tdvass::Error::Diverged { .. }) => {
                let stopped = sim.time();
                self.model.last_successful_time = stopped;
                self.model.terminate_requested = true;
                self.model.machine = MachineState::StepFailed;
                Err(FmiError::discard(format!(
                    "{e}; the FMU stays at t = {stopped} s (fmi2LastSuccessfulTime) and asks to terminate (fmi2Terminated); g = {} N/m, tau = {} s",
                    settings.g, settings.tau
                )))
            }
            Err(e) => {
                self.model.machine = MachineState::Error;
                Err(FmiError::error(format!("the simulation failed: {e}")))
            }
        }
    }

    /// The slope of `x_g` over the step of length `h` that starts at `now`
    /// (road = 0): the input derivative when the master set one; else, when
    /// a new value was set, the slope [`extrapolation_slope`] gives for
    /// `input_extrapolation` 1 or 2 (fewer values than it needs: the
    /// values there are; the first step holds); else 0 (held). Logs one
    /// warning per instance when a held input with a changing value meets
    /// communication steps longer than [`HOLD_WARNING_STEP`].
    fn input_slope_for_step(&mut self, now: f64, h: f64) -> Result<f64, FmiError> {
        let m = &self.model;
        let x_g = m.settings.x_g;
        let rate = match m.previous_input {
            Some((t, value)) if now > t && m.input_pending => (x_g - value) / (now - t),
            _ => 0.0,
        };
        if m.input_slope_given {
            return Ok(m.input_slope);
        }
        let mode = m.settings.input_extrapolation;
        if mode >= 1 {
            if !m.input_pending {
                return Ok(m.input_slope);
            }
            let earlier = if mode == 2 { m.earlier_input } else { None };
            let values: Vec<(f64, f64)> = [earlier, m.previous_input, Some((now, x_g))]
                .into_iter()
                .flatten()
                .collect();
            let slope = extrapolation_slope(&values, h);
            limits::check_value("x_g derivative", slope).map_err(|e| {
                FmiError::error(format!(
                    "input_extrapolation = {mode}: the slope {slope} m/s through x_g = {x_g} m at {now} s and the values before it is refused: {}",
                    e.message
                ))
            })?;
            self.model.input_slope = slope;
            return Ok(slope);
        }
        if h > HOLD_WARNING_STEP && rate != 0.0 && !m.hold_warned {
            self.model.hold_warned = true;
            self.warning(format!(
                "fmi2DoStep: x_g is held over communication steps of {h} s (no input derivative, input_extrapolation = 0); at its current rate of change {rate:.4e} m/s the held value lags by about {:.3e} m on average ({:.3e} m at the step end). Set input_extrapolation = 2 (or 1), call fmi2SetRealInputDerivatives, or use steps of at most 1 ms.",
                0.5 * rate.abs() * h,
                rate.abs() * h
            ));
        }
        Ok(0.0)
    }

    /// `fmi2SetRealInputDerivatives`: order 1 of `x_g` sets the slope used
    /// from the current communication point on (until `x_g` or the slope is
    /// set again). Higher orders are ignored with `fmi2Warning`.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<Status, FmiError> {
        let mut slope = None;
        let mut ignored = Vec::new();
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            if var.causality != Causality::Input {
                return Err(FmiError::error(format!(
                    "`{}` is not an input; only the derivative of `x_g` can be set",
                    var.name
                )));
            }
            if order < 1 {
                return Err(FmiError::error(format!(
                    "invalid derivative order {order} for `{}`: must be >= 1",
                    var.name
                )));
            }
            if !value.is_finite() {
                return Err(FmiError::error(format!(
                    "invalid value {value} for the order-{order} derivative of `{}`: must be finite",
                    var.name
                )));
            }
            if order == 1 {
                limits::check_value("x_g derivative", value)?;
                slope = Some(value);
            } else {
                ignored.push(order);
            }
        }
        if let Some(slope) = slope {
            self.model.input_slope = slope;
            self.model.input_slope_given = true;
            self.model.input_pending = true;
        }
        if ignored.is_empty() {
            Ok(Status::Ok)
        } else {
            self.warning(format!(
                "fmi2SetRealInputDerivatives: derivative orders {ignored:?} of `x_g` ignored (the input is extrapolated linearly)"
            ));
            Ok(Status::Warning)
        }
    }

    /// `fmi2GetRealOutputDerivatives` (order 1 only).
    pub fn get_real_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &mut [f64],
    ) -> Result<Status, FmiError> {
        let Some(sim) = self.model.sim.as_mut() else {
            unreachable!("allowed only with a simulation")
        };
        let derivatives = sim.output_derivatives();
        for ((&vr, &order), value) in vrs.iter().zip(orders).zip(values.iter_mut()) {
            let var = by_vr(vr)
                .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
            let Access::Output(id) = var.access else {
                return Err(FmiError::error(format!(
                    "`{}` is not an output; derivatives exist for outputs only",
                    var.name
                )));
            };
            if order != 1 {
                return Err(FmiError::error(format!(
                    "derivative order {order} of `{}` not available (maxOutputDerivativeOrder = 1)",
                    var.name
                )));
            }
            *value = id.derivative(&derivatives);
            if !value.is_finite() {
                let bad = std::mem::replace(value, 0.0);
                return Err(FmiError::error(format!(
                    "the derivative of `{}` = {bad} is not finite; no value returned",
                    var.name
                )));
            }
        }
        Ok(Status::Ok)
    }

    /// `fmi2GetDirectionalDerivative`: exact partials of the outputs
    /// (`vUnknown_ref`) with respect to the input `x_g` and the states
    /// (addressed by the value references of the outputs `x_s` .. `v_t`).
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<Status, FmiError> {
        let known: Vec<Known> = knowns
            .iter()
            .map(|&vr| {
                let var = by_vr(vr).ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
                match var.access {
                    Access::Real { .. } if var.causality == Causality::Input => Ok(Known::RoadInput),
                    Access::Output(OutputId::State(i)) => Ok(Known::State(i)),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not a known of the directional derivative (only the input x_g and the states x_s, v_s, x_h, v_h, x_t, v_t)",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        let outputs: Vec<OutputId> = unknowns
            .iter()
            .map(|&vr| {
                let var = by_vr(vr)
                    .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
                match var.access {
                    Access::Output(id) => Ok(id),
                    _ => Err(FmiError::error(format!(
                        "`{}` is not an output; directional derivatives exist for outputs only",
                        var.name
                    ))),
                }
            })
            .collect::<Result<_, _>>()?;
        if let Some(bad) = seed.iter().find(|v| !v.is_finite()) {
            return Err(FmiError::error(format!(
                "invalid seed value {bad} in dvKnown: must be finite"
            )));
        }
        let lin = self.linearization()?;
        for (out, r) in outputs.iter().zip(result.iter_mut()) {
            *r = known
                .iter()
                .zip(seed)
                .map(|(k, dv)| out.partial(*k, &lin) * dv)
                .sum();
            if !r.is_finite() {
                let bad = std::mem::replace(r, 0.0);
                return Err(FmiError::error(format!(
                    "a directional derivative = {bad} is not finite (seed too large); no value returned"
                )));
            }
        }
        Ok(Status::Ok)
    }

    fn linearization(&self) -> Result<Linearization, FmiError> {
        let preview;
        let sim = match &self.model.sim {
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
        Ok(Linearization {
            body_acceleration_row: row,
            conventional: variant == Variant::Cs,
            road_is_input: self.model.settings.road_is_input(),
            instantaneous_control,
        })
    }

    // ----------------------------------------------------------------- status

    fn status_kind_name(kind: i32) -> Result<&'static str, FmiError> {
        match kind {
            status_kind::DO_STEP_STATUS => Ok("fmi2DoStepStatus"),
            status_kind::PENDING_STATUS => Ok("fmi2PendingStatus"),
            status_kind::LAST_SUCCESSFUL_TIME => Ok("fmi2LastSuccessfulTime"),
            status_kind::TERMINATED => Ok("fmi2Terminated"),
            other => Err(FmiError::error(format!("unknown status kind {other}"))),
        }
    }

    fn status_not_available(kind: i32, of: &str) -> FmiError {
        match Self::status_kind_name(kind) {
            Ok(name) => FmiError::discard(format!(
                "no {of} status {name} (this FMU steps synchronously; available: fmi2LastSuccessfulTime as Real, fmi2Terminated as Boolean)"
            )),
            Err(e) => e,
        }
    }

    /// `fmi2GetStatus`: nothing is ever pending, so no kind is available.
    pub fn get_status(&mut self, kind: i32) -> Result<Status, FmiError> {
        Err(Self::status_not_available(kind, "fmi2Status"))
    }

    /// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime`.
    pub fn get_real_status(&mut self, kind: i32) -> Result<f64, FmiError> {
        if kind == status_kind::LAST_SUCCESSFUL_TIME {
            Ok(self.model.last_successful_time)
        } else {
            Err(Self::status_not_available(kind, "Real"))
        }
    }

    /// `fmi2GetIntegerStatus`: no kind is an Integer.
    pub fn get_integer_status(&mut self, kind: i32) -> Result<i32, FmiError> {
        Err(Self::status_not_available(kind, "Integer"))
    }

    /// `fmi2GetBooleanStatus`: `fmi2Terminated`.
    pub fn get_boolean_status(&mut self, kind: i32) -> Result<bool, FmiError> {
        if kind == status_kind::TERMINATED {
            Ok(self.model.terminate_requested)
        } else {
            Err(Self::status_not_available(kind, "Boolean"))
        }
    }

    /// `fmi2GetStringStatus`: nothing is pending, so no kind is available.
    pub fn get_string_status(&mut self, kind: i32) -> Result<Status, FmiError> {
        Err(Self::status_not_available(kind, "String"))
    }

    /// `fmi2CancelStep` is refused by the state table before this runs.
    pub fn cancel_step(&mut self) -> Result<Status, FmiError> {
        Err(FmiError::error("no asynchronous step to cancel"))
    }

    // ------------------------------------------------------------- FMU states

    fn owned(&self, handle: usize) -> Result<&Model, FmiError> {
        self.fmu_states.get(&handle).map(|b| &**b).ok_or_else(|| {
            FmiError::error(format!(
                "FMU state {handle:#x} was not created by this instance or was already freed"
            ))
        })
    }

    fn store(&mut self, model: Model, reuse: Option<usize>) -> Result<usize, FmiError> {
        match reuse {
            Some(handle) => {
                self.owned(handle)?;
                if let Some(slot) = self.fmu_states.get_mut(&handle) {
                    **slot = model;
                }
                Ok(handle)
            }
            None => {
                let boxed = Box::new(model);
                let handle = &*boxed as *const Model as usize;
                self.fmu_states.insert(handle, boxed);
                Ok(handle)
            }
        }
    }

    /// `fmi2GetFMUstate`: a copy of everything; `reuse` overwrites a state
    /// of this instance. Returns the handle (the `fmi2FMUstate` value).
    pub fn get_fmu_state(&mut self, reuse: Option<usize>) -> Result<usize, FmiError> {
        let handle = self.store(self.model.clone(), reuse)?;
        self.event(format!(
            "fmi2GetFMUstate: state {handle:#x} at t = {} s",
            self.time()
        ));
        Ok(handle)
    }

    /// `fmi2SetFMUstate`: only states of this instance are accepted.
    pub fn set_fmu_state(&mut self, handle: usize) -> Result<Status, FmiError> {
        self.model = self.owned(handle)?.clone();
        self.event(format!(
            "fmi2SetFMUstate: state {handle:#x}, now at t = {} s in state {}",
            self.time(),
            self.model.machine.name()
        ));
        Ok(Status::Ok)
    }

    /// `fmi2FreeFMUstate`.
    pub fn free_fmu_state(&mut self, handle: usize) -> Result<Status, FmiError> {
        self.owned(handle)?;
        self.fmu_states.remove(&handle);
        Ok(Status::Ok)
    }

    /// The serialized bytes of a state of this instance.
    pub fn serialize_fmu_state(&self, handle: usize) -> Result<Vec<u8>, FmiError> {
        Ok(snapshot::serialize(self.owned(handle)?, &self.guid))
    }

    /// `fmi2DeSerializeFMUstate`: a new state (or `reuse` overwritten) from
    /// bytes written by this FMU, in any instance or process.
    pub fn deserialize_fmu_state(
        &mut self,
        bytes: &[u8],
        reuse: Option<usize>,
    ) -> Result<usize, FmiError> {
        if let Some(handle) = reuse {
            self.owned(handle)?;
        }
        let model = snapshot::deserialize(bytes, &self.guid)?;
        let handle = self.store(model, reuse)?;
        self.event(format!(
            "fmi2DeSerializeFMUstate: {} bytes into state {handle:#x}",
            bytes.len()
        ));
        Ok(handle)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        self.event(format!(
            "fmi2FreeInstance: `{}` freed with {} FMU state(s)",
            self.name,
            self.fmu_states.len()
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::variables::{VARIABLES, by_name};
    use std::cell::RefCell;
    use std::rc::Rc;

    type Log = Rc<RefCell<Vec<(Status, String, String)>>>;

    fn new_instance(logging_on: bool) -> (Instance, Log) {
        let log: Log = Rc::default();
        let sink = log.clone();
        let guid = crate::guid();
        let instance = Instance::instantiate(
            InstantiateRequest {
                instance_name: Some("test"),
                fmu_type: FMI2_COSIMULATION,
                guid: Some(&guid),
                resource_location: Some("file:///tmp/resources"),
                logging_on,
            },
            Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
        )
        .unwrap();
        (instance, log)
    }

    fn vr(name: &str) -> u32 {
        by_name(name).unwrap().vr
    }

    fn initialized() -> (Instance, Log) {
        let (mut i, log) = new_instance(false);
        i.run(Function::SetupExperiment, |i| {
            i.setup_experiment(None, 0.0, Some(15.0))
        })
        .unwrap();
        i.run(Function::EnterInitializationMode, |i| {
            i.enter_initialization_mode()
        })
        .unwrap();
        i.run(Function::ExitInitializationMode, |i| {
            i.exit_initialization_mode()
        })
        .unwrap();
        (i, log)
    }

    fn get(i: &mut Instance, name: &str) -> f64 {
        let mut v = [0.0];
        i.run(Function::GetReal, |i| i.get_real(&[vr(name)], &mut v))
            .unwrap();
        v[0]
    }

    #[test]
    fn instantiate_refusals_are_logged() {
        let guid = crate::guid();
        let cases: [(InstantiateRequest, &str); 5] = [
            (
                InstantiateRequest {
                    instance_name: Some("a"),
                    fmu_type: FMI2_COSIMULATION,
                    guid: Some("{wrong}"),
                    ..Default::default()
                },
                "GUID {wrong}",
            ),
            (
                InstantiateRequest {
                    instance_name: Some("a"),
                    fmu_type: FMI2_MODEL_EXCHANGE,
                    guid: Some(&guid),
                    ..Default::default()
                },
                "fmi2ModelExchange",
            ),
            (
                InstantiateRequest {
                    instance_name: Some(""),
                    fmu_type: FMI2_COSIMULATION,
                    guid: Some(&guid),
                    ..Default::default()
                },
                "empty",
            ),
            (
                InstantiateRequest {
                    instance_name: None,
                    fmu_type: FMI2_COSIMULATION,
                    guid: Some(&guid),
                    ..Default::default()
                },
                "NULL",
            ),
            (
                InstantiateRequest {
                    instance_name: Some("a"),
                    fmu_type: FMI2_COSIMULATION,
                    guid: Some(&guid),
                    resource_location: Some("http://x/y"),
                    ..Default::default()
                },
                "http://x/y",
            ),
        ];
        for (request, expected) in cases {
            let log: Log = Rc::default();
            let sink = log.clone();
            let made = Instance::instantiate(
                request,
                Box::new(move |s, c, m| sink.borrow_mut().push((s, c.into(), m.into()))),
            );
            assert!(made.is_none());
            let log = log.borrow();
            assert_eq!(log.len(), 1);
            assert_eq!(log[0].0, Status::Error);
            assert!(log[0].2.contains(expected), "{}", log[0].2);
        }
    }

    #[test]
    fn wrong_state_is_refused_and_logged() {
        let (mut i, log) = new_instance(false);
        assert_eq!(
            i.run(Function::DoStep, |i| i.do_step(0.0, 0.1)),
            Err(Status::Error)
        );
        let last = log.borrow().last().cloned().unwrap();
        assert_eq!(last.0, Status::Error);
        assert_eq!(last.1, "logStatusError");
        assert_eq!(last.2, "fmi2DoStep: not allowed in state instantiated");
        assert_eq!(i.machine_state(), MachineState::Instantiated);
    }

    #[test]
    fn values_are_checked_at_set_time_and_at_initialization() {
        let (mut i, log) = new_instance(false);
        assert_eq!(
            i.run(Function::SetReal, |i| i
                .set_real(&[vr("m_s"), vr("m_h")], &[300.0, -1.0])),
            Err(Status::Error)
        );
        assert!(log.borrow().last().unwrap().2.contains("`m_h`"));
        assert_eq!(i.model.settings.m_s, 345.0, "nothing applied");
        assert_eq!(
            i.run(Function::SetInteger, |i| i
                .set_integer(&[vr("road_class")], &[9])),
            Err(Status::Error)
        );
        assert!(log.borrow().last().unwrap().2.contains("road_class"));
        for (name, bad) in [("tau", -1.0), ("g", f64::NAN), ("max_internal_step", 0.0)] {
            assert!(
                i.run(Function::SetReal, |i| i.set_real(&[vr(name)], &[bad]))
                    .is_err()
            );
            let message = log.borrow().last().unwrap().2.clone();
            assert!(
                message.contains(name) && message.contains(&format!("{bad}")),
                "{message}"
            );
        }
        // A delay needing too many history nodes passes the range check and
        // is refused when the simulation starts; the instance can be fixed.
        i.run(Function::SetReal, |i| i.set_real(&[vr("tau")], &[1e4]))
            .unwrap();
        i.run(Function::EnterInitializationMode, |i| {
            i.enter_initialization_mode()
        })
        .unwrap();
        assert!(
            i.run(Function::ExitInitializationMode, |i| i
                .exit_initialization_mode())
                .is_err()
        );
        assert!(log.borrow().last().unwrap().2.contains("`tau`"));
        assert_eq!(i.machine_state(), MachineState::InitializationMode);
        i.run(Function::SetReal, |i| i.set_real(&[vr("tau")], &[2e-4]))
            .unwrap();
        i.run(Function::ExitInitializationMode, |i| {
            i.exit_initialization_mode()
        })
        .unwrap();
        // Fixed after initialization, outputs and calculated never.
        let refused = [
            ("m_s", "fixed parameter"),
            ("x_s", "output"),
            ("spectral_abscissa", "calculated"),
        ];
        for (name, why) in refused {
            assert!(
                i.run(Function::SetReal, |i| i.set_real(&[vr(name)], &[1.0]))
                    .is_err()
            );
            let message = log.borrow().last().unwrap().2.clone();
            assert!(message.contains(name) && message.contains(why), "{message}");
        }
        assert!(
            i.run(Function::SetBoolean, |i| i
                .set_boolean(&[vr("stable")], &[true]))
                .is_err()
        );
        assert!(
            i.run(Function::SetReal, |i| i.set_real(&[vr("g")], &[1000.0]))
                .is_ok()
        );
        assert!(
            i.run(Function::SetReal, |i| i.set_real(&[vr("variant")], &[1.0]))
                .is_err()
        );
        assert!(
            log.borrow()
                .last()
                .unwrap()
                .2
                .contains("Integer, not a Real")
        );
    }

    #[test]
    fn default_experiment_reproduces_table2() {
        let (mut i, _) = initialized();
        let mut t = 0.0;
        for k in 1..=15000 {
            let next = k as f64 * 1e-3;
            i.run(Function::DoStep, |i| i.do_step(t, next - t)).unwrap();
            t = next;
        }
        let ba = get(&mut i, "rms_body_acceleration");
        let sdd = get(&mut i, "rms_suspension_deflection");
        let tdd = get(&mut i, "rms_tire_deflection");
        assert!((ba - 0.3068).abs() < 1.5e-4, "{ba}");
        assert!((sdd - 0.0388).abs() < 1.5e-4, "{sdd}");
        assert!((tdd * 1e3 - 0.6251).abs() < 1.5e-4, "{tdd}");
        // Past the stop time.
        assert!(i.run(Function::DoStep, |i| i.do_step(15.0, 0.1)).is_err());
    }

    #[test]
    fn divergence_is_a_discard_with_last_successful_time() {
        let (mut i, log) = new_instance(false);
        i.run(Function::SetReal, |i| {
            i.set_real(
                &[vr("g"), vr("tau"), vr("x_s_start")],
                &[-40000.0, 0.11, 0.01],
            )
        })
        .unwrap();
        i.run(Function::EnterInitializationMode, |i| {
            i.enter_initialization_mode()
        })
        .unwrap();
        assert_eq!(
            i.run(Function::ExitInitializationMode, |i| i
                .exit_initialization_mode()),
            Ok(Status::Warning)
        );
        assert!(log.borrow().iter().any(|(s, c, m)| *s == Status::Warning
            && c == "logStatusWarning"
            && m.contains("-40000")
            && m.contains("0.11")));
        let mut t = 0.0;
        let status = loop {
            match i.run(Function::DoStep, |i| i.do_step(t, 1.0)) {
                Ok(_) => t += 1.0,
                Err(s) => break s,
            }
            assert!(t < 1e4, "never diverged");
        };
        assert_eq!(status, Status::Discard);
        assert_eq!(i.machine_state(), MachineState::StepFailed);
        let last = i
            .run(Function::GetRealStatus, |i| {
                i.get_real_status(status_kind::LAST_SUCCESSFUL_TIME)
            })
            .unwrap();
        assert!(last >= t && last < t + 1.0, "{last}");
        assert!(
            i.run(Function::GetBooleanStatus, |i| i
                .get_boolean_status(status_kind::TERMINATED))
                .unwrap()
        );
        let message = log.borrow().last().unwrap().2.clone();
        assert!(
            message.starts_with("fmi2DoStep: simulation diverged at t ="),
            "{message}"
        );
        for name in [
            "x_s",
            "x_t",
            "body_acceleration",
            "objective",
            "control_force",
        ] {
            assert!(get(&mut i, name).is_finite());
        }
        assert!(i.run(Function::DoStep, |i| i.do_step(last, 1.0)).is_err());
        i.run(Function::Terminate, |i| i.terminate()).unwrap();
        i.run(Function::Reset, |i| i.reset()).unwrap();
        assert_eq!(i.machine_state(), MachineState::Instantiated);
        assert_eq!(i.model.settings.g, 5386.0);
    }

    #[test]
    fn fmu_states_belong_to_their_instance() {
        let (mut a, _) = initialized();
        let (mut b, log) = initialized();
        let s = a
            .run(Function::GetFmuState, |i| i.get_fmu_state(None))
            .unwrap();
        assert!(
            b.run(Function::SetFmuState, |i| i.set_fmu_state(s))
                .is_err()
        );
        assert!(
            log.borrow()
                .last()
                .unwrap()
                .2
                .contains("not created by this instance")
        );
        a.run(Function::DoStep, |i| i.do_step(0.0, 0.5)).unwrap();
        let x = get(&mut a, "x_s");
        a.run(Function::SetFmuState, |i| i.set_fmu_state(s))
            .unwrap();
        assert_eq!(a.time(), 0.0);
        a.run(Function::DoStep, |i| i.do_step(0.0, 0.5)).unwrap();
        assert_eq!(get(&mut a, "x_s"), x);
        // Re-use overwrites in place.
        let again = a
            .run(Function::GetFmuState, |i| i.get_fmu_state(Some(s)))
            .unwrap();
        assert_eq!(again, s);
        assert_eq!(a.fmu_state_count(), 1);
        // Moving through bytes works across instances, parameters included.
        let bytes = a.serialize_fmu_state(s).unwrap();
        let t = b
            .run(Function::DeSerializeFmuState, |i| {
                i.deserialize_fmu_state(&bytes, None)
            })
            .unwrap();
        b.run(Function::SetFmuState, |i| i.set_fmu_state(t))
            .unwrap();
        assert_eq!(b.time(), 0.5);
        assert_eq!(get(&mut b, "x_s"), x);
        a.run(Function::FreeFmuState, |i| i.free_fmu_state(s))
            .unwrap();
        assert!(
            a.run(Function::FreeFmuState, |i| i.free_fmu_state(s))
                .is_err(),
            "double free"
        );
    }

    #[test]
    fn extrapolation_slopes() {
        // x = 1 + 2 t − 3 t², sampled at uneven times; the next step is 0.004 s.
        let x = |t: f64| 1.0 + 2.0 * t - 3.0 * t * t;
        let times = [0.010, 0.012, 0.015];
        let values: Vec<(f64, f64)> = times.iter().map(|&t| (t, x(t))).collect();
        let h = 0.004;
        assert_eq!(extrapolation_slope(&values[2..], h), 0.0);
        let chord = (x(0.015) - x(0.012)) / 0.003;
        assert!((extrapolation_slope(&values[1..], h) - chord).abs() < 1e-12);
        // Of the lines through (t_k, x_k), the one closest to the parabola
        // over the step: the mean-square error is smallest at its slope.
        let best = extrapolation_slope(&values, h);
        let mean_square = |slope: f64| {
            (0..=1000)
                .map(|i| {
                    let s = h * i as f64 / 1000.0;
                    let e = x(0.015) + slope * s - x(0.015 + s);
                    e * e
                })
                .sum::<f64>()
        };
        assert!((best - (2.0 - 6.0 * 0.015 - 3.0 * 0.375 * 2.0 * h)).abs() < 1e-9);
        assert!(mean_square(best) < mean_square(best + 1e-3));
        assert!(mean_square(best) < mean_square(best - 1e-3));
        // Times that do not increase hold the input.
        assert_eq!(extrapolation_slope(&[(0.1, 1.0), (0.1, 2.0)], h), 0.0);
    }

    #[test]
    fn input_derivative_semantics() {
        let (mut i, _) = new_instance(false);
        i.run(Function::SetInteger, |i| i.set_integer(&[vr("road")], &[0]))
            .unwrap();
        i.run(Function::EnterInitializationMode, |i| {
            i.enter_initialization_mode()
        })
        .unwrap();
        i.run(Function::ExitInitializationMode, |i| {
            i.exit_initialization_mode()
        })
        .unwrap();
        i.run(Function::SetReal, |i| i.set_real(&[vr("x_g")], &[0.01]))
            .unwrap();
        assert_eq!(
            i.run(Function::SetRealInputDerivatives, |i| {
                i.set_real_input_derivatives(&[vr("x_g"), vr("x_g")], &[1, 2], &[0.5, 3.0])
            }),
            Ok(Status::Warning)
        );
        i.run(Function::DoStep, |i| i.do_step(0.0, 0.1)).unwrap();
        assert!((get(&mut i, "road_displacement") - 0.06).abs() < 1e-15);
        // Not set again: the same line continues.
        i.run(Function::DoStep, |i| i.do_step(0.1, 0.1)).unwrap();
        assert!((get(&mut i, "road_displacement") - 0.11).abs() < 1e-15);
        // fmi2SetReal resets the slope.
        i.run(Function::SetReal, |i| i.set_real(&[vr("x_g")], &[0.02]))
            .unwrap();
        i.run(Function::DoStep, |i| i.do_step(0.2, 0.1)).unwrap();
        assert_eq!(get(&mut i, "road_displacement"), 0.02);
        let mut d = [0.0];
        i.run(Function::GetRealOutputDerivatives, |i| {
            i.get_real_output_derivatives(&[vr("road_displacement")], &[1], &mut d)
        })
        .unwrap();
        assert_eq!(d[0], 0.0);
        assert!(
            i.run(Function::GetRealOutputDerivatives, |i| {
                i.get_real_output_derivatives(&[vr("x_s")], &[2], &mut d)
            })
            .is_err()
        );
    }

    #[test]
    fn model_structure_dependencies_are_the_nonzero_partials() {
        // One declaration: an output lists `x_g` among its dependencies in
        // the description exactly when its partial with respect to `x_g`
        // is not zero, for every variant with the road fed through `x_g`.
        for variant in [1, 2, 3] {
            let (mut i, _) = new_instance(false);
            i.run(Function::SetupExperiment, |i| {
                i.setup_experiment(None, 0.0, Some(1.0))
            })
            .unwrap();
            i.run(Function::EnterInitializationMode, |i| {
                i.enter_initialization_mode()
            })
            .unwrap();
            i.run(Function::SetInteger, |i| {
                i.set_integer(&[vr("variant"), vr("road")], &[variant, 0])
            })
            .unwrap();
            i.run(Function::ExitInitializationMode, |i| {
                i.exit_initialization_mode()
            })
            .unwrap();
            for v in VARIABLES
                .iter()
                .filter(|v| v.causality == Causality::Output)
            {
                let mut partial = [f64::NAN];
                i.run(Function::GetDirectionalDerivative, |i| {
                    i.directional_derivative(&[v.vr], &[vr("x_g")], &[1.0], &mut partial)
                })
                .unwrap();
                assert_eq!(
                    partial[0] != 0.0,
                    v.feedthrough.contains(&"x_g"),
                    "variant {variant}, `{}`: partial {} against the declared dependencies {:?}",
                    v.name,
                    partial[0],
                    v.feedthrough
                );
            }
        }
    }

    #[test]
    fn directional_derivatives_are_exact() {
        let (mut i, _) = initialized();
        i.run(Function::DoStep, |i| i.do_step(0.0, 0.3)).unwrap();
        let states = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"].map(vr);
        let mut x = [0.0; 6];
        i.run(Function::GetReal, |i| i.get_real(&states, &mut x))
            .unwrap();
        let mut ba = [0.0];
        let seed = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        i.run(Function::GetDirectionalDerivative, |i| {
            i.directional_derivative(&[vr("body_acceleration")], &states, &seed, &mut ba)
        })
        .unwrap();
        let a = i.model.sim.as_ref().unwrap().plant().a;
        let expected: f64 = (0..6).map(|j| a[(V_S, j)] * seed[j]).sum();
        assert_eq!(ba[0], expected);
        // BA is linear in the state: the partials reproduce it exactly.
        let ba_now = get(&mut i, "body_acceleration");
        let mut lin = [0.0];
        i.run(Function::GetDirectionalDerivative, |i| {
            i.directional_derivative(&[vr("body_acceleration")], &states, &x, &mut lin)
        })
        .unwrap();
        assert!((lin[0] - ba_now).abs() <= 1e-12 * ba_now.abs().max(1.0));
        let mut tdd = [0.0];
        i.run(Function::GetDirectionalDerivative, |i| {
            i.directional_derivative(
                &[vr("tire_deflection")],
                &[vr("x_g"), vr("x_t")],
                &[1.0, 1.0],
                &mut tdd,
            )
        })
        .unwrap();
        assert_eq!(tdd[0], 1.0, "road = 1: x_g is not applied");
        assert!(
            i.run(Function::GetDirectionalDerivative, |i| {
                i.directional_derivative(&[vr("m_s")], &[vr("x_g")], &[1.0], &mut tdd)
            })
            .is_err()
        );
    }

    #[test]
    fn debug_logging_categories() {
        let (mut i, log) = new_instance(false);
        assert!(
            i.run(Function::SetDebugLogging, |i| i
                .set_debug_logging(true, &["logNothing"]))
                .is_err()
        );
        assert!(log.borrow().last().unwrap().2.contains("logNothing"));
        i.run(Function::SetDebugLogging, |i| {
            i.set_debug_logging(true, &["logEvents"])
        })
        .unwrap();
        let before = log.borrow().len();
        i.run(Function::Reset, |i| i.reset()).unwrap();
        assert_eq!(log.borrow().len(), before + 1);
        i.run(Function::SetDebugLogging, |i| {
            i.set_debug_logging(false, &[])
        })
        .unwrap();
        i.run(Function::Reset, |i| i.reset()).unwrap();
        assert_eq!(log.borrow().len(), before + 1);
        // Errors are always reported.
        assert!(i.run(Function::Terminate, |i| i.terminate()).is_err());
        assert_eq!(log.borrow().len(), before + 2);
    }

    #[test]
    fn panics_make_the_instance_fatal() {
        let (mut i, log) = new_instance(false);
        i.on_panic(Function::DoStep, "boom");
        assert_eq!(i.machine_state(), MachineState::Fatal);
        assert_eq!(log.borrow().last().unwrap().0, Status::Fatal);
        assert!(i.run(Function::Reset, |i| i.reset()).is_err());
    }
}
