//! The FMI 2.0 instance: what `fmi2Instantiate` checks beyond what every
//! version checks ([`tdvass_fmu::instantiation`]: `fmuType` and
//! `fmuResourceLocation`), the FMI 2.0 state table around every call, the status kinds of `fmi2Get*Status`, and a
//! version-neutral [`Slave`] that does everything else, called explicitly
//! ([`FrontEnd::slave_mut`]). No FFI here; [`crate::ffi`] calls the
//! instance through [`FrontEnd::run`], which enforces the state table and
//! logs every failure.

use crate::states::{self, Function};
use crate::{FmiError, Status};
use std::path::PathBuf;
use tdvass_fmu::Phase;
use tdvass_fmu::entry::FrontEnd;
use tdvass_fmu::instantiation::Instantiation;
use tdvass_fmu::slave::Dialect;
use tdvass_fmu::variables::FmiVersion;

pub use tdvass_fmu::Slave;
pub use tdvass_fmu::slave::{HOLD_WARNING_STEP, LogSink, SlaveState, extrapolation_slope};

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

/// How the slave's messages name FMI 2.0 functions and flags.
pub const FMI2_DIALECT: Dialect = Dialect {
    version: FmiVersion::Fmi2,
    prefix: "fmi2",
    last_successful_time: "fmi2LastSuccessfulTime",
    terminate_flag: "fmi2Terminated",
    set_float: "SetReal",
    set_input_derivatives: "SetRealInputDerivatives",
    fmu_state: "FMUstate",
    deserialize_state: "DeSerializeFMUstate",
    input_slope_remedy: "call fmi2SetRealInputDerivatives",
    instantiate: "Instantiate",
    update_discrete_states: "NewDiscreteStates",
    token_argument: "fmuGUID",
    given_token: "GUID",
    own_token: "GUID",
};

/// What `fmi2Instantiate` was given (strings already copied out of C).
#[derive(Debug, Clone, Default)]
pub struct InstantiateRequest<'a> {
    pub instance_name: Option<&'a str>,
    pub fmu_type: i32,
    pub guid: Option<&'a str>,
    pub resource_location: Option<&'a str>,
    pub logging_on: bool,
}

/// One FMI 2.0 instance.
pub struct Instance {
    name: String,
    resource_path: Option<PathBuf>,
    slave: Slave,
}

/// The state table is [`states::check`]; the rest is the slave's.
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
}

/// The component handle of [`crate::ffi`] holds the instance itself.
impl AsMut<Instance> for Instance {
    fn as_mut(&mut self) -> &mut Instance {
        self
    }
}

impl Instance {
    /// `fmi2Instantiate`: checks the request and creates the instance. A
    /// refusal is logged through `logger` and returns `None`.
    pub fn instantiate(request: InstantiateRequest<'_>, logger: LogSink) -> Option<Instance> {
        let instantiation = Instantiation::new(FMI2_DIALECT, logger);
        let name = instantiation.instance_name(request.instance_name)?;
        let model_exchange = match request.fmu_type {
            FMI2_COSIMULATION => false,
            FMI2_MODEL_EXCHANGE => true,
            other => {
                return instantiation.refuse(&format!(
                    "unknown fmuType {other} (0 = fmi2ModelExchange, 1 = fmi2CoSimulation)"
                ));
            }
        };
        let model = instantiation.model(request.guid)?;
        instantiation.interface(model, model_exchange)?;
        let resource_path = match request.resource_location {
            None | Some("") => None,
            Some(uri) => match crate::uri::resource_path(uri) {
                Ok(path) => Some(path),
                Err(reason) => {
                    return instantiation.refuse(&format!(
                        "fmuResourceLocation `{uri}` is not a valid file URI: {reason}"
                    ));
                }
            },
        };
        let mut slave = instantiation.slave(
            &name,
            model,
            request.logging_on,
            resource_path.as_deref(),
            "",
        );
        if model_exchange {
            slave.use_model_exchange();
        }
        Some(Instance {
            name,
            resource_path,
            slave,
        })
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The phase (the FMI 2.0 state: the slave's phase).
    pub fn phase(&self) -> Phase {
        self.slave.phase()
    }

    /// The resources directory given at instantiation.
    pub fn resource_path(&self) -> Option<&std::path::Path> {
        self.resource_path.as_deref()
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
            Ok(self.slave.last_successful_time())
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
            Ok(self.slave.terminate_requested())
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
}

impl Drop for Instance {
    fn drop(&mut self) {
        self.slave.log_freed(&self.name);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;
    use crate::variables::{FmiVersion, by_name};
    use std::cell::RefCell;
    use std::rc::Rc;

    type Log = Rc<RefCell<Vec<(Status, String, String)>>>;

    fn new_instance(logging_on: bool) -> (Instance, Log) {
        let log: Log = Rc::default();
        let sink = log.clone();
        let guid = crate::guid(Model::QuarterCar);
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
        by_name(Model::QuarterCar, FmiVersion::Fmi2, name)
            .unwrap()
            .vr
    }

    #[test]
    fn instantiate_refusals_are_logged() {
        let guid = crate::guid(Model::QuarterCar);
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
                    fmu_type: 7,
                    guid: Some(&guid),
                    ..Default::default()
                },
                "unknown fmuType 7",
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
            i.run(Function::DoStep, |i| i.slave_mut().do_step(0.0, 0.1)),
            Err(Status::Error)
        );
        let last = log.borrow().last().cloned().unwrap();
        assert_eq!(last.0, Status::Error);
        assert_eq!(last.1, "logStatusError");
        assert_eq!(last.2, "fmi2DoStep: not allowed in state instantiated");
        assert_eq!(i.phase(), Phase::Instantiated);
    }

    /// What FMI 2.0 adds to a diverging step (the slave's behaviour is
    /// tested in `tdvass-fmu`): `fmi2DoStep` returns `fmi2Discard` and logs
    /// under its name, the instance is in `stepFailed`, where the status
    /// kinds tell where it stopped and that it asks to terminate,
    /// `fmi2DoStep` is refused and `fmi2Terminate` and `fmi2Reset` are not.
    #[test]
    fn divergence_is_a_discard_with_last_successful_time() {
        let (mut i, log) = new_instance(false);
        i.run(Function::SetReal, |i| {
            i.slave_mut().set_real(
                &[vr("g"), vr("tau"), vr("x_s_start")],
                &[-40000.0, 0.11, 0.01],
            )
        })
        .unwrap();
        i.run(Function::EnterInitializationMode, |i| {
            i.slave_mut().enter_initialization_mode()
        })
        .unwrap();
        assert_eq!(
            i.run(Function::ExitInitializationMode, |i| i
                .slave_mut()
                .exit_initialization_mode()),
            Ok(Status::Warning)
        );
        let mut t = 0.0;
        let status = loop {
            match i.run(Function::DoStep, |i| i.slave_mut().do_step(t, 1.0)) {
                Ok(_) => t += 1.0,
                Err(s) => break s,
            }
            assert!(t < 1e4, "never diverged");
        };
        assert_eq!(status, Status::Discard);
        assert_eq!(i.phase(), Phase::StepFailed);
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
        assert!(
            i.run(Function::DoStep, |i| i.slave_mut().do_step(last, 1.0))
                .is_err()
        );
        i.run(Function::Terminate, |i| i.slave_mut().terminate())
            .unwrap();
        i.run(Function::Reset, |i| i.slave_mut().reset()).unwrap();
        assert_eq!(i.phase(), Phase::Instantiated);
    }

    #[test]
    fn panics_make_the_instance_fatal() {
        let (mut i, log) = new_instance(false);
        i.on_panic(Function::DoStep, "boom");
        assert_eq!(i.phase(), Phase::Fatal);
        assert_eq!(log.borrow().last().unwrap().0, Status::Fatal);
        assert!(i.run(Function::Reset, |i| i.slave_mut().reset()).is_err());
    }
}
