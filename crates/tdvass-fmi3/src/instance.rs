//! The FMI 3.0 instance: what `fmi3InstantiateCoSimulation` (and Model Exchange) checks beyond
//! what every version checks ([`tdvass_fmu::instantiation`]: event mode and
//! the intermediate variables), the FMI 3.0 state table around every call, the FMI 3.0 types of the values,
//! Configuration Mode and the intermediate updates, around a
//! version-neutral [`Slave`] that does everything else, called explicitly
//! ([`FrontEnd::slave_mut`]). Where FMI 3.0 adds to a slave's function,
//! the instance has its own method ([`Instance::reset`],
//! [`Instance::enter_initialization_mode`], the typed getters and setters)
//! and the C layer calls that one. No FFI here; [`crate::ffi`] calls the
//! instance through [`FrontEnd::run`].

use crate::states::{self, Fmi3Phase, Function};
use crate::types::{ValueType, fmi3_type};
use crate::{FmiError, Status};
use std::path::PathBuf;
use tdvass_fmu::Phase;
use tdvass_fmu::entry::FrontEnd;
use tdvass_fmu::instantiation::Instantiation;
use tdvass_fmu::slave::{Dialect, LogSink};
use tdvass_fmu::variables::{Causality, DependencyKind, FmiVersion, Variable, by_vr};

pub use tdvass_fmu::Slave;

/// How the slave's messages name FMI 3.0 functions and flags.
pub const FMI3_DIALECT: Dialect = Dialect {
    version: FmiVersion::Fmi3,
    prefix: "fmi3",
    last_successful_time: "lastSuccessfulTime",
    terminate_flag: "terminateSimulation",
    set_float: "SetFloat64",
    set_input_derivatives: "SetFloat64",
    fmu_state: "FMUState",
    deserialize_state: "DeserializeFMUState",
    input_slope_remedy: "set x_g in intermediate updates",
    instantiate: "InstantiateCoSimulation",
    update_discrete_states: "UpdateDiscreteStates",
    token_argument: "instantiationToken",
    given_token: "instantiationToken",
    own_token: "token",
};

/// What `fmi3InstantiateCoSimulation` was given (strings copied out of C).
#[derive(Debug, Clone, Default)]
pub struct InstantiateRequest<'a> {
    pub instance_name: Option<&'a str>,
    pub instantiation_token: Option<&'a str>,
    pub resource_path: Option<&'a str>,
    pub logging_on: bool,
    pub event_mode_used: bool,
    pub early_return_allowed: bool,
    pub required_intermediate_variables: &'a [u32],
    /// The master passed an `intermediateUpdate` callback.
    pub intermediate_update: bool,
    /// `fmi3InstantiateModelExchange` (else Co-Simulation).
    pub model_exchange: bool,
}

/// What the master may do inside the current intermediate update.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntermediatePoint {
    /// `intermediateVariableSetRequested`: inputs may be set.
    pub set_requested: bool,
    /// `intermediateVariableGetAllowed`: outputs may be read.
    pub get_allowed: bool,
}

/// One FMI 3.0 instance.
pub struct Instance {
    name: String,
    resource_path: Option<PathBuf>,
    slave: Slave,
    early_return_allowed: bool,
    intermediate_update: bool,
    configuration: bool,
    intermediate: Option<IntermediatePoint>,
}

/// The state table is [`states::check`] on [`Instance::phase`]; beyond the
/// slave, a panic ends an intermediate update and a restored FMU state ends
/// Configuration Mode.
impl FrontEnd for Instance {
    type Function = Function;

    fn name(function: Function) -> &'static str {
        function.name()
    }

    fn check_state(&self, function: Function) -> Result<(), FmiError> {
        states::check(function, self.phase())
    }

    fn slave(&self) -> &Slave {
        &self.slave
    }

    fn slave_mut(&mut self) -> &mut Slave {
        &mut self.slave
    }

    fn after_panic(&mut self) {
        self.intermediate = None;
    }

    /// An FMU state does not hold Configuration Mode: restoring one taken
    /// after instantiation ends it (the instance is then in the restored
    /// state, where every variable is accessible).
    fn fmu_state_restored(&mut self) {
        if self.slave.phase() != Phase::Instantiated {
            self.configuration = false;
        }
    }
}

impl Instance {
    /// `fmi3InstantiateCoSimulation` and `fmi3InstantiateModelExchange`:
    /// checks the request and creates the instance. A refusal is logged
    /// through `logger` (naming the function called) and returns `None`.
    pub fn instantiate(request: InstantiateRequest<'_>, logger: LogSink) -> Option<Instance> {
        let dialect = if request.model_exchange {
            Dialect {
                instantiate: "InstantiateModelExchange",
                ..FMI3_DIALECT
            }
        } else {
            FMI3_DIALECT
        };
        let instantiation = Instantiation::new(dialect, logger);
        let refuse = |message: String| instantiation.refuse(&message);
        let name = instantiation.instance_name(request.instance_name)?;
        let model = instantiation.model(request.instantiation_token)?;
        instantiation.interface(model, request.model_exchange)?;
        if request.event_mode_used {
            return refuse(
                "eventModeUsed = true, but this FMU has no event mode (hasEventMode = false)"
                    .into(),
            );
        }
        for &vr in request.required_intermediate_variables {
            match by_vr(model, FmiVersion::Fmi3, vr) {
                Some(v) if v.intermediate_update => {}
                Some(v) => {
                    return refuse(format!(
                        "requiredIntermediateVariables: `{}` (value reference {vr}) is not available in intermediate updates",
                        v.name
                    ));
                }
                None => {
                    return refuse(format!(
                        "requiredIntermediateVariables: unknown value reference {vr}"
                    ));
                }
            }
        }
        let resource_path = request
            .resource_path
            .filter(|p| !p.is_empty())
            .map(PathBuf::from);
        let details = format!(
            ", intermediate updates {}, early return {}",
            if request.intermediate_update {
                "on"
            } else {
                "off"
            },
            if request.early_return_allowed {
                "allowed"
            } else {
                "not allowed"
            },
        );
        let details = if request.model_exchange {
            ", Model Exchange".to_string()
        } else {
            details
        };
        let mut slave = instantiation.slave(
            &name,
            model,
            request.logging_on,
            resource_path.as_deref(),
            &details,
        );
        if request.model_exchange {
            slave.use_model_exchange();
        }
        Some(Instance {
            name,
            resource_path,
            slave,
            early_return_allowed: request.early_return_allowed,
            intermediate_update: request.intermediate_update,
            configuration: false,
            intermediate: None,
        })
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The resources directory given at instantiation.
    pub fn resource_path(&self) -> Option<&std::path::Path> {
        self.resource_path.as_deref()
    }

    /// Whether the master allows returning early from `fmi3DoStep`.
    pub fn early_return_allowed(&self) -> bool {
        self.early_return_allowed
    }

    /// Whether the master passed an `intermediateUpdate` callback.
    pub fn has_intermediate_update(&self) -> bool {
        self.intermediate_update
    }

    /// The FMI 3.0 phase (the standard's state).
    pub fn phase(&self) -> Fmi3Phase {
        match self.slave.phase() {
            Phase::Instantiated if self.configuration => Fmi3Phase::ConfigurationMode,
            Phase::Instantiated => Fmi3Phase::Instantiated,
            Phase::InitializationMode => Fmi3Phase::InitializationMode,
            Phase::StepComplete if self.intermediate.is_some() => Fmi3Phase::IntermediateUpdate,
            Phase::StepComplete => Fmi3Phase::StepMode,
            Phase::StepFailed => Fmi3Phase::StepDiscarded,
            Phase::Terminated => Fmi3Phase::Terminated,
            Phase::Error => Fmi3Phase::Error,
            Phase::Fatal => Fmi3Phase::Fatal,
            Phase::EventMode => Fmi3Phase::EventMode,
            Phase::ContinuousTimeMode => Fmi3Phase::ContinuousTimeMode,
        }
    }

    /// `fmi3EnterInitializationMode`: the experiment's times, then
    /// Initialization Mode.
    pub fn enter_initialization_mode(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<Status, FmiError> {
        self.slave
            .setup_experiment(tolerance, start_time, stop_time)?;
        self.slave.enter_initialization_mode()
    }

    /// `fmi3EnterConfigurationMode`: structural parameters may be set.
    pub fn enter_configuration_mode(&mut self) -> Result<Status, FmiError> {
        self.configuration = true;
        Ok(Status::Ok)
    }

    /// `fmi3ExitConfigurationMode`: back to Instantiated.
    pub fn exit_configuration_mode(&mut self) -> Result<Status, FmiError> {
        self.configuration = false;
        Ok(Status::Ok)
    }

    /// `fmi3Reset`: the slave's [`Slave::reset`] (back to Instantiated with
    /// every start value), out of Configuration Mode and any intermediate
    /// update.
    pub fn reset(&mut self) -> Result<Status, FmiError> {
        self.configuration = false;
        self.intermediate = None;
        self.slave.reset()
    }

    /// Starts an intermediate update (the master's callback runs next).
    pub fn enter_intermediate_update(&mut self, point: IntermediatePoint) {
        self.intermediate = Some(point);
    }

    /// Ends the intermediate update.
    pub fn exit_intermediate_update(&mut self) {
        self.intermediate = None;
    }

    // ------------------------------------------------------------- values

    /// Checks that the variables behind `vrs` are each of FMI 3.0 value type `expected`
    /// and accessible now (`write`: to be set): in Configuration Mode only
    /// structural parameters; inside an intermediate update only the
    /// variables marked `intermediateUpdate`, outputs when reading is
    /// allowed and inputs when setting is requested.
    fn typed(&self, vrs: &[u32], expected: ValueType, write: bool) -> Result<(), FmiError> {
        for &vr in vrs {
            self.typed_one(vr, expected, write)?;
        }
        Ok(())
    }

    /// The variable behind `vr`, checked as [`Self::typed`] checks each.
    fn typed_one(
        &self,
        vr: u32,
        expected: ValueType,
        write: bool,
    ) -> Result<&'static Variable, FmiError> {
        let var = by_vr(self.slave.model(), FmiVersion::Fmi3, vr).ok_or_else(|| {
            FmiError::error(format!(
                "unknown value reference {vr} (for a {})",
                expected.name()
            ))
        })?;
        let actual = fmi3_type(var).value_type();
        if actual != expected {
            return Err(FmiError::error(format!(
                "value reference {vr} is `{}`, a {}, not a {}",
                var.name,
                actual.name(),
                expected.name()
            )));
        }
        if self.configuration && var.causality != Causality::StructuralParameter {
            return Err(FmiError::error(format!(
                "`{}` is not a structural parameter: only those are accessible in Configuration Mode",
                var.name
            )));
        }
        if let Some(point) = self.intermediate {
            let (allowed, what) = if write {
                (point.set_requested, "setting was not requested")
            } else {
                (point.get_allowed, "reading is not allowed")
            };
            if !var.intermediate_update || !allowed {
                return Err(FmiError::error(format!(
                    "`{}` is not accessible in this intermediate update ({})",
                    var.name,
                    if var.intermediate_update {
                        what
                    } else {
                        "it is not an intermediate-update variable"
                    }
                )));
            }
        }
        Ok(var)
    }

    /// `fmi3GetFloat64` (arrays element by element).
    pub fn get_float64(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Float64, false)?;
        self.slave.get_real(vrs, values)
    }

    /// `fmi3SetFloat64` (no Float64 array is settable).
    pub fn set_float64(&mut self, vrs: &[u32], values: &[f64]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Float64, true)?;
        Self::check_count(vrs, values.len())?;
        self.slave.set_real(vrs, values)
    }

    fn check_count(vrs: &[u32], n: usize) -> Result<(), FmiError> {
        if vrs.len() == n {
            Ok(())
        } else {
            Err(FmiError::error(format!(
                "{n} values given for {} value references",
                vrs.len()
            )))
        }
    }

    /// `fmi3GetInt32`.
    pub fn get_int32(&mut self, vrs: &[u32], values: &mut [i32]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Int32, false)?;
        Self::check_count(vrs, values.len())?;
        self.slave.get_integer(vrs, values)
    }

    /// `fmi3SetInt32`.
    pub fn set_int32(&mut self, vrs: &[u32], values: &[i32]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Int32, true)?;
        Self::check_count(vrs, values.len())?;
        self.slave.set_integer(vrs, values)
    }

    fn get_wide<T>(
        &mut self,
        vrs: &[u32],
        values: &mut [T],
        ty: ValueType,
        widen: impl Fn(i32) -> T,
    ) -> Result<Status, FmiError> {
        self.typed(vrs, ty, false)?;
        Self::check_count(vrs, values.len())?;
        let mut narrow = vec![0; vrs.len()];
        self.slave.get_integer(vrs, &mut narrow)?;
        for (v, n) in values.iter_mut().zip(narrow) {
            *v = widen(n);
        }
        Ok(Status::Ok)
    }

    fn set_wide<T: Copy + std::fmt::Display>(
        &mut self,
        vrs: &[u32],
        values: &[T],
        ty: ValueType,
        narrow: impl Fn(T) -> Option<i32>,
    ) -> Result<Status, FmiError> {
        self.typed(vrs, ty, true)?;
        Self::check_count(vrs, values.len())?;
        let narrowed = vrs
            .iter()
            .zip(values)
            .map(|(&vr, &value)| {
                let var = self.typed_one(vr, ty, true)?;
                narrow(value).ok_or_else(|| {
                    FmiError::error(format!(
                        "invalid value {value} for `{}`: {}",
                        var.name,
                        var.range.describe()
                    ))
                })
            })
            .collect::<Result<Vec<i32>, _>>()?;
        self.slave.set_integer(vrs, &narrowed)
    }

    /// `fmi3GetInt64`: the Enumerations (`variant`, `road`, `road_class`, `tire_contact`).
    pub fn get_int64(&mut self, vrs: &[u32], values: &mut [i64]) -> Result<Status, FmiError> {
        self.get_wide(vrs, values, ValueType::Int64, i64::from)
    }

    /// `fmi3SetInt64`: the Enumerations, by their codes.
    pub fn set_int64(&mut self, vrs: &[u32], values: &[i64]) -> Result<Status, FmiError> {
        self.set_wide(vrs, values, ValueType::Int64, |v| i32::try_from(v).ok())
    }

    /// `fmi3GetUInt64`: the structural parameter `root_count`.
    pub fn get_uint64(&mut self, vrs: &[u32], values: &mut [u64]) -> Result<Status, FmiError> {
        self.get_wide(vrs, values, ValueType::UInt64, |v| v.max(0) as u64)
    }

    /// `fmi3SetUInt64`: the structural parameter `root_count`.
    pub fn set_uint64(&mut self, vrs: &[u32], values: &[u64]) -> Result<Status, FmiError> {
        self.set_wide(vrs, values, ValueType::UInt64, |v| i32::try_from(v).ok())
    }

    /// `fmi3GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], values: &mut [bool]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Boolean, false)?;
        Self::check_count(vrs, values.len())?;
        self.slave.get_boolean(vrs, values)
    }

    /// `fmi3SetBoolean`: the only Boolean is a calculated parameter.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Result<Status, FmiError> {
        self.typed(vrs, ValueType::Boolean, true)?;
        Self::check_count(vrs, values.len())?;
        self.slave.set_boolean(vrs, values)
    }

    /// A getter or setter of a type no variable has: every value reference
    /// is refused (none is of that type), an empty call succeeds.
    pub fn no_variable_of(&mut self, vrs: &[u32], ty: ValueType) -> Result<Status, FmiError> {
        self.typed(vrs, ty, false)?;
        Ok(Status::Ok)
    }

    /// `fmi3GetNumberOfVariableDependencies`: the knowns an output depends
    /// on (ModelStructure); other variables have none listed.
    pub fn number_of_dependencies(&self, vr: u32) -> Result<usize, FmiError> {
        Ok(self.dependencies(vr)?.len())
    }

    /// `fmi3GetVariableDependencies`: value references of the knowns `vr`
    /// depends on and how, ascending, as ModelStructure lists them: the input
    /// `x_g` where it feeds through, the continuous states it is computed
    /// from ([`Variable::output_dependencies`]).
    pub fn dependencies(&self, vr: u32) -> Result<Vec<(u32, DependencyKind)>, FmiError> {
        let model = self.slave.model();
        let var = by_vr(model, FmiVersion::Fmi3, vr)
            .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
        if var.causality != Causality::Output {
            return Err(FmiError::error(format!(
                "`{}` is not an output; dependencies are listed for outputs",
                var.name
            )));
        }
        let mut found: Vec<(u32, DependencyKind)> = var
            .output_dependencies(model, FmiVersion::Fmi3)
            .into_iter()
            .map(|(known, kind)| (known.vr, kind))
            .collect();
        found.sort_unstable_by_key(|&(vr, _)| vr);
        Ok(found)
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        self.slave.log_freed(&self.name);
    }
}
