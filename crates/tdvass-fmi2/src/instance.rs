//! The FMI 2.0 instance: what `fmi2Instantiate` checks, the FMI 2.0 state
//! table around every call, the status kinds of `fmi2Get*Status`, and a
//! version-neutral [`Slave`] that does everything else (it is reached
//! through `Deref`, so `instance.do_step(..)` is the slave's). No FFI here;
//! [`crate::ffi`] calls these methods through [`Instance::run`], which
//! enforces the state table and logs every failure.

use crate::states::{self, Function, MachineState};
use crate::{FmiError, Status};
use std::ops::{Deref, DerefMut};
use std::path::PathBuf;
use tdvass_fmu::slave::{Dialect, Logger};
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

impl Deref for Instance {
    type Target = Slave;
    fn deref(&self) -> &Slave {
        &self.slave
    }
}

impl DerefMut for Instance {
    fn deref_mut(&mut self) -> &mut Slave {
        &mut self.slave
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
        let logger = Logger::new(logger, request.logging_on);
        let instance = Instance {
            name,
            resource_path,
            slave: Slave::new(FMI2_DIALECT, expected.clone(), logger),
        };
        instance.logger().log(
            Status::Ok,
            &format!(
                "fmi2Instantiate: instance `{}` of {} (GUID {}), resources {}",
                instance.name,
                crate::MODEL_NAME,
                expected,
                instance
                    .resource_path
                    .as_ref()
                    .map(|p| format!("at {}", p.display()))
                    .unwrap_or_else(|| "not given".into())
            ),
        );
        Some(instance)
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The machine state.
    pub fn machine_state(&self) -> MachineState {
        self.slave.phase()
    }

    /// The resources directory given at instantiation.
    pub fn resource_path(&self) -> Option<&std::path::Path> {
        self.resource_path.as_deref()
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
        let result = states::check(function, self.machine_state()).and_then(|()| op(self));
        result.map_err(|e| {
            self.logger()
                .log(e.status, &format!("{}: {}", function.name(), e.message));
            if e.status == Status::Fatal {
                self.slave.set_phase(MachineState::Fatal);
            }
            e.status
        })
    }

    /// After a panic inside `function` (caught by the FFI layer): the
    /// instance may be inconsistent, so it goes to `fatal`.
    pub fn on_panic(&mut self, function: Function, message: &str) {
        self.slave.set_phase(MachineState::Fatal);
        self.logger().log(
            Status::Fatal,
            &format!(
                "{}: internal error (panic: {message}); the instance is unusable, free it",
                function.name()
            ),
        );
    }

    /// Logs that a Model Exchange function was called.
    pub fn refuse_model_exchange(&self, function: &str) -> Status {
        self.logger().log(
            Status::Error,
            &format!("{function}: Model Exchange function; this FMU implements Co-Simulation only"),
        );
        Status::Error
    }

    /// `fmi2SetDebugLogging`: `categories` empty means all. Unknown
    /// categories refuse the whole call.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<Status, FmiError> {
        self.slave.logger_mut().set_categories(on, categories)
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
        self.logger().log(
            Status::Ok,
            &format!(
                "fmi2FreeInstance: `{}` freed with {} FMU state(s)",
                self.name,
                self.slave.fmu_state_count()
            ),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::variables::{Causality, VARIABLES, VarType, by_name};
    use std::cell::RefCell;
    use std::rc::Rc;
    use tdvass::model::V_S;

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
        assert_eq!(i.settings().params.m_s, 345.0, "nothing applied");
        assert_eq!(
            i.run(Function::SetInteger, |i| i
                .set_integer(&[vr("road_class")], &[9])),
            Err(Status::Error)
        );
        assert!(log.borrow().last().unwrap().2.contains("road_class"));
        for (name, bad) in [("tau", -1.0), ("g", f64::NAN), ("max_internal_step", -1e-4)] {
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
        assert_eq!(i.settings().params.g, 5386.0);
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
                .filter(|v| v.causality == Causality::Output && v.var_type() == VarType::Real)
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
            // The counts are Integers: no partials, and no dependencies.
            let mut partial = [f64::NAN];
            let e = i
                .directional_derivative(&[vr("lift_off_count")], &[vr("x_g")], &[1.0], &mut partial)
                .unwrap_err();
            assert!(
                e.message.contains("`lift_off_count` is an Integer output"),
                "{}",
                e.message
            );
            assert!(by_name("lift_off_count").unwrap().feedthrough.is_empty());
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
        let a = i.simulator().unwrap().plant().a;
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

    /// PVASS on an ISO 8608 road at 30 m/s for 2 s: class H loses the tire
    /// contact (one warning, naming time, variable and value, and a growing
    /// `contact_loss_time`), class A does not.
    #[test]
    fn a_loss_of_tire_contact_is_logged_once() {
        for (class, loses) in [(8, true), (1, false)] {
            let (mut i, log) = new_instance(false);
            i.run(Function::SetInteger, |i| {
                i.set_integer(
                    &[vr("variant"), vr("road"), vr("road_class")],
                    &[2, 2, class],
                )
            })
            .unwrap();
            i.run(Function::SetReal, |i| {
                i.set_real(&[vr("vehicle_speed")], &[30.0])
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
            let mut t = 0.0;
            for _ in 0..200 {
                i.run(Function::DoStep, |i| i.do_step(t, 0.01)).unwrap();
                t += 0.01;
            }
            let warnings: Vec<_> = log
                .borrow()
                .iter()
                .filter(|(s, _, m)| *s == Status::Warning && m.contains("leaves the road"))
                .map(|(_, _, m)| m.clone())
                .collect();
            let lost = get(&mut i, "contact_loss_time");
            if loses {
                assert_eq!(warnings.len(), 1, "{warnings:?}");
                assert!(
                    warnings[0].starts_with("fmi2DoStep: the tire leaves the road at t = ")
                        && warnings[0].contains("`dynamic_tire_load` = -"),
                    "{}",
                    warnings[0]
                );
                assert!(lost > 0.0 && lost < 2.0, "{lost}");
            } else {
                assert!(warnings.is_empty(), "{warnings:?}");
                assert_eq!(lost, 0.0);
            }
        }
    }

    fn lift_off_count(i: &mut Instance) -> i32 {
        let mut n = [-1];
        i.run(Function::GetInteger, |i| {
            i.get_integer(&[vr("lift_off_count")], &mut n)
        })
        .unwrap();
        n[0]
    }

    /// The same PVASS run on class H as above with `tire_contact = 1`: no
    /// warning; each lift-off is an event (time, TDD at W/k_t), as many as
    /// `lift_off_count`; in flight the dynamic tire load is −W and does not
    /// depend on `x_t`. A code that is none is refused by name.
    #[test]
    fn the_unilateral_tire_logs_each_lift_off_as_an_event() {
        let (mut i, log) = new_instance(true);
        let refused = i.run(Function::SetInteger, |i| {
            i.set_integer(&[vr("tire_contact")], &[2])
        });
        assert_eq!(refused, Err(Status::Error));
        let message = log.borrow().last().unwrap().2.clone();
        assert!(
            message.contains("`tire_contact`") && message.contains("invalid value 2"),
            "{message}"
        );
        i.run(Function::SetInteger, |i| {
            i.set_integer(
                &[
                    vr("variant"),
                    vr("road"),
                    vr("road_class"),
                    vr("tire_contact"),
                ],
                &[2, 2, 8, 1],
            )
        })
        .unwrap();
        i.run(Function::SetReal, |i| {
            i.set_real(&[vr("vehicle_speed")], &[30.0])
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
        let static_load = (345.0 + 4.05) * 9.80665 + 40.5 * 9.80665;
        let limit = static_load / 190000.0;
        let (mut t, mut flights, mut contacts) = (0.0, 0, 0);
        for _ in 0..200 {
            i.run(Function::DoStep, |i| i.do_step(t, 0.01)).unwrap();
            t += 0.01;
            let mut partial = [f64::NAN];
            i.run(Function::GetDirectionalDerivative, |i| {
                i.directional_derivative(
                    &[vr("dynamic_tire_load")],
                    &[vr("x_t")],
                    &[1.0],
                    &mut partial,
                )
            })
            .unwrap();
            let load = get(&mut i, "dynamic_tire_load");
            if i.simulator().unwrap().in_flight() {
                flights += 1;
                assert_eq!(partial[0], 0.0);
                assert!((load + static_load).abs() <= 1e-9 * static_load, "{load}");
            } else {
                contacts += 1;
                assert_eq!(partial[0], -190000.0);
                assert!(load >= -static_load * (1.0 + 1e-9), "{load}");
            }
        }
        assert!(flights > 0 && contacts > 0, "{flights} {contacts}");
        let log = log.borrow();
        assert!(
            !log.iter()
                .any(|(s, _, m)| *s == Status::Warning && m.contains("the tire leaves the road")),
            "the bilateral tire's warning with the unilateral tire"
        );
        let events: Vec<&String> = log
            .iter()
            .filter(|(s, c, m)| {
                *s == Status::Ok && c == "logEvents" && m.contains("lift-off at t = ")
            })
            .map(|(_, _, m)| m)
            .collect();
        let count = lift_off_count(&mut i);
        assert!(count > 0);
        assert_eq!(events.len(), count as usize, "{events:?}");
        let mut last = 0.0;
        for e in events {
            let number = |after: &str| -> f64 {
                let rest = &e[e.find(after).unwrap() + after.len()..];
                rest[..rest.find(' ').unwrap()].parse().unwrap()
            };
            let (time, tdd, shown) = (number("t = "), number("TDD = "), number("W/k_t = "));
            assert!(time > last && time <= 2.0, "{e}");
            last = time;
            assert!((shown - limit).abs() <= 1e-12 * limit, "{e}");
            assert!((tdd - shown).abs() <= 1e-9 * shown, "{e}");
        }
        assert!(get(&mut i, "contact_loss_time") > 0.0);
    }

    /// With the bilateral tire `lift_off_count` counts the falls of the load
    /// below −W (no events, the one warning of the test above).
    #[test]
    fn the_bilateral_tire_counts_its_would_be_lift_offs() {
        for (class, loses) in [(8, true), (1, false)] {
            let (mut i, log) = new_instance(true);
            i.run(Function::SetInteger, |i| {
                i.set_integer(
                    &[vr("variant"), vr("road"), vr("road_class")],
                    &[2, 2, class],
                )
            })
            .unwrap();
            i.run(Function::SetReal, |i| {
                i.set_real(&[vr("vehicle_speed")], &[30.0])
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
            i.run(Function::DoStep, |i| i.do_step(0.0, 2.0)).unwrap();
            let count = lift_off_count(&mut i);
            assert_eq!(count > 0, loses, "class {class}: {count}");
            assert!(
                !log.borrow()
                    .iter()
                    .any(|(_, _, m)| m.contains("lift-off at t = "))
            );
        }
    }
}
