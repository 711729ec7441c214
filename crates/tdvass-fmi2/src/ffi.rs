//! The C ABI: every fmi2 function of FMI 2.0 Co-Simulation and Model
//! Exchange, exported with C linkage. The standard has 47 functions, each a
//! few lines of conversions; they stay together so that every `unsafe` of
//! this crate is in one file (hence its length).
//!
//! This layer holds the C signatures, converts `fmi2Boolean`, `fmi2Byte`
//! and `fmi2Status`, and calls the safe [`Instance`] through
//! [`tdvass_fmu::entry`]: [`entry::call`] finds the instance behind the
//! component, runs the call under the FMI 2.0 state table
//! ([`FrontEnd::run`], which logs failures) and catches every panic (a
//! panic becomes `fmi2Fatal` and the instance goes to `fatal` instead of
//! unwinding into the host); `entry` also holds the bodies of the
//! FMU-state functions, `fmi2FreeInstance` and `fmi2SetDebugLogging`, which
//! FMI 3.0 shares. Pointer arguments are checked by
//! [`tdvass_fmu::pointers`].
//!
//! # Safety
//!
//! The master must respect the FMI 2.0 calling convention: `c` is NULL or a
//! component returned by `fmi2Instantiate` and not yet freed; every array
//! argument is NULL or points to at least as many elements as its count
//! says; strings are NUL-terminated. Within that contract nothing here is
//! undefined behaviour; NULL pointers, wrong counts of zero, unaligned
//! pointers and foreign FMU-state pointers are detected and refused. An
//! instance must not be used from two threads at the same time (FMI 2.0
//! allows that restriction); distinct instances are independent (no global
//! mutable state).
// The only module of the crate that may use `unsafe` (denied elsewhere).
#![allow(unsafe_code)]
#![allow(non_camel_case_types, non_snake_case, clippy::missing_safety_doc)]

use crate::instance::{FMI2_COSIMULATION, Instance, InstantiateRequest, LogSink};
use crate::states::Function;
use crate::{FmiError, Status};
use libc::{c_char, c_double, c_int, c_uint, c_void, size_t};
use std::ffi::CStr;
use std::panic::catch_unwind;
use tdvass_fmu::entry::{self, FrontEnd, fmu_state};
use tdvass_fmu::pointers::{self, LogText, c_string, copy_str, input, out_value, output};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = c_double;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;
pub type fmi2Status = c_int;
pub type fmi2Type = c_int;
pub type fmi2StatusKind = c_int;

/// `fmi2CallbackLogger` (printf-like; we pass a pre-formatted message with
/// every `%` doubled, so no variadic argument is ever read).
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(size_t, size_t) -> *mut c_void>;
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocateMemory: fmi2CallbackAllocateMemory,
    pub freeMemory: fmi2CallbackFreeMemory,
    pub stepFinished: fmi2StepFinished,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// `fmi2EventInfo` (Model Exchange).
#[repr(C)]
pub struct fmi2EventInfo {
    pub newDiscreteStatesNeeded: fmi2Boolean,
    pub terminateSimulation: fmi2Boolean,
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    pub nextEventTimeDefined: fmi2Boolean,
    pub nextEventTime: fmi2Real,
}

const FMI2_TRUE: fmi2Boolean = 1;
const FMI2_FALSE: fmi2Boolean = 0;

/// The tag of an FMI 2.0 instance handle (see [`pointers::Handle`]).
const HANDLE_MAGIC: u64 = 0x5444_5641_5353_4649; // "TDVASSFI"

/// The handle of an instance made in Rust ([`Instance::instantiate`], with
/// a Rust logger), as `fmi2Instantiate` returns it: for a master in Rust
/// that calls the C functions in-process (the training run of the
/// profile-guided build). `fmi2FreeInstance` frees it.
pub fn into_component(instance: Instance) -> fmi2Component {
    pointers::into_raw(HANDLE_MAGIC, instance)
}

fn status(s: Status) -> fmi2Status {
    s as fmi2Status
}

/// The master's logger as a [`LogSink`].
fn c_logger(
    logger: unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
    environment: fmi2ComponentEnvironment,
    instance_name: &str,
) -> LogSink {
    let name = c_string(instance_name);
    Box::new(move |s: Status, category: &str, message: &str| {
        let category = LogText::new(category, true);
        let message = LogText::new(message, true);
        // SAFETY: `logger` is the master's callback with the FMI signature;
        // every string is NUL-terminated and outlives the call; the message
        // contains no conversion specification (every `%` is doubled), so
        // the callee reads no variadic argument.
        unsafe {
            logger(
                environment,
                name.as_ptr(),
                status(s),
                category.as_ptr(),
                message.as_ptr(),
            )
        }
    })
}

/// Runs `op` on the instance behind `c` as `function` ([`entry::call`]:
/// state table, logging, panics caught, then `fmi2Fatal`). An invalid `c`
/// gives `fmi2Error`.
fn call(
    c: fmi2Component,
    function: Function,
    op: impl FnOnce(&mut Instance) -> Result<Status, FmiError>,
) -> fmi2Status {
    // SAFETY: `c` comes from the master, which passes a component of this
    // FMU (module contract).
    status(unsafe { entry::call::<Instance, Instance>(c, HANDLE_MAGIC, function, op) })
}

fn bools_from(values: &[fmi2Boolean]) -> Vec<bool> {
    values.iter().map(|&v| v != FMI2_FALSE).collect()
}

// ------------------------------------------------------------------ common

/// `TYPES_PLATFORM` as a C string.
const TYPES_PLATFORM_C: &CStr = c"default";
/// `FMI_VERSION` as a C string.
const FMI_VERSION_C: &CStr = c"2.0";

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    catch_unwind(|| TYPES_PLATFORM_C.as_ptr()).unwrap_or(std::ptr::null())
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    catch_unwind(|| FMI_VERSION_C.as_ptr()).unwrap_or(std::ptr::null())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: size_t,
    categories: *const fmi2String,
) -> fmi2Status {
    call(c, Function::SetDebugLogging, |i| {
        // SAFETY: module contract: `categories` holds `nCategories` strings.
        unsafe { entry::set_debug_logging(i, loggingOn != FMI2_FALSE, nCategories, categories) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let made = catch_unwind(|| {
        if functions.is_null() || !functions.is_aligned() {
            return std::ptr::null_mut();
        }
        // SAFETY: non-NULL, aligned, and by contract an fmi2CallbackFunctions;
        // the two fields needed are copied out.
        let (logger, environment) =
            unsafe { ((*functions).logger, (*functions).componentEnvironment) };
        let Some(logger) = logger else {
            return std::ptr::null_mut();
        };
        // SAFETY: by contract NULL or a NUL-terminated string; copied.
        let name = unsafe { copy_str(instanceName) };
        // SAFETY: as above.
        let guid = unsafe { copy_str(fmuGUID) };
        // SAFETY: as above.
        let resource = unsafe { copy_str(fmuResourceLocation) };
        let sink = c_logger(logger, environment, name.as_deref().unwrap_or(""));
        let request = InstantiateRequest {
            instance_name: name.as_deref(),
            fmu_type: fmuType,
            guid: guid.as_deref(),
            resource_location: resource.as_deref(),
            logging_on: loggingOn != FMI2_FALSE,
        };
        match Instance::instantiate(request, sink) {
            Some(instance) => into_component(instance),
            None => std::ptr::null_mut(),
        }
    });
    made.unwrap_or(std::ptr::null_mut())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    // SAFETY: module contract; the master passes `c` no more.
    unsafe { entry::free_instance::<Instance, Instance>(c, HANDLE_MAGIC, Function::FreeInstance) }
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    call(c, Function::SetupExperiment, |i| {
        i.slave_mut().setup_experiment(
            (toleranceDefined != FMI2_FALSE).then_some(tolerance),
            startTime,
            (stopTimeDefined != FMI2_FALSE).then_some(stopTime),
        )
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    call(c, Function::EnterInitializationMode, |i: &mut Instance| {
        i.slave_mut().enter_initialization_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    call(c, Function::ExitInitializationMode, |i: &mut Instance| {
        i.slave_mut().exit_initialization_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    call(c, Function::Terminate, |i: &mut Instance| {
        i.slave_mut().terminate()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    call(c, Function::Reset, |i: &mut Instance| i.slave_mut().reset())
}

// ------------------------------------------------------------- get and set

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(c, Function::GetReal, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, output(value, nvr, "value")?) };
        i.slave_mut().get_real(vrs, values)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *mut fmi2Integer,
) -> fmi2Status {
    call(c, Function::GetInteger, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, output(value, nvr, "value")?) };
        i.slave_mut().get_integer(vrs, values)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    call(c, Function::GetBoolean, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, output(value, nvr, "value")?) };
        let mut flags = vec![false; vrs.len()];
        let s = i.slave_mut().get_boolean(vrs, &mut flags)?;
        for (v, f) in values.iter_mut().zip(flags) {
            *v = if f { FMI2_TRUE } else { FMI2_FALSE };
        }
        Ok(s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *mut fmi2String,
) -> fmi2Status {
    call(c, Function::GetString, |i| {
        // SAFETY: module contract (arrays of nvr elements). No String
        // variable exists, so nothing is ever written.
        let (vrs, _) = unsafe { (input(vr, nvr, "vr")?, output(value, nvr, "value")?) };
        i.slave_mut().get_string(vrs)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *const fmi2Real,
) -> fmi2Status {
    call(c, Function::SetReal, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, input(value, nvr, "value")?) };
        i.slave_mut().set_real(vrs, values)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *const fmi2Integer,
) -> fmi2Status {
    call(c, Function::SetInteger, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, input(value, nvr, "value")?) };
        i.slave_mut().set_integer(vrs, values)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *const fmi2Boolean,
) -> fmi2Status {
    call(c, Function::SetBoolean, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, values) = unsafe { (input(vr, nvr, "vr")?, input(value, nvr, "value")?) };
        i.slave_mut().set_boolean(vrs, &bools_from(values))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    value: *const fmi2String,
) -> fmi2Status {
    call(c, Function::SetString, |i| {
        // SAFETY: module contract (arrays of nvr elements). The strings are
        // never read: no String variable exists.
        let (vrs, _) = unsafe { (input(vr, nvr, "vr")?, input(value, nvr, "value")?) };
        i.slave_mut().set_string(vrs)
    })
}

// -------------------------------------------------------------- FMU states

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, Function::GetFmuState, |i| {
        // SAFETY: module contract: FMUstate points to an fmi2FMUstate.
        unsafe { fmu_state::get(i, FMUstate) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    call(c, Function::SetFmuState, |i| fmu_state::set(i, FMUstate))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, Function::FreeFmuState, |i| {
        // SAFETY: module contract: FMUstate is NULL or points to an
        // fmi2FMUstate.
        unsafe { fmu_state::free(i, FMUstate) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut size_t,
) -> fmi2Status {
    call(c, Function::SerializedFmuStateSize, |i| {
        // SAFETY: module contract: size points to a size_t.
        unsafe { fmu_state::serialized_size(i, FMUstate, size) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: size_t,
) -> fmi2Status {
    call(c, Function::SerializeFmuState, |i| {
        // SAFETY: module contract: serializedState holds `size` writable
        // bytes (fmi2Byte is a byte).
        unsafe { fmu_state::serialize(i, FMUstate, serializedState as *mut u8, size) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: size_t,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    call(c, Function::DeSerializeFmuState, |i| {
        // SAFETY: module contract: `size` readable bytes (fmi2Byte is a
        // byte) and a state slot.
        unsafe { fmu_state::deserialize(i, serializedState as *const u8, size, FMUstate) }
    })
}

// ------------------------------------------------------------- derivatives

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: size_t,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: size_t,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    call(c, Function::GetDirectionalDerivative, |i| {
        // SAFETY: module contract (arrays of the given lengths).
        let (unknowns, knowns, seed, result) = unsafe {
            (
                input(vUnknown_ref, nUnknown, "vUnknown_ref")?,
                input(vKnown_ref, nKnown, "vKnown_ref")?,
                input(dvKnown, nKnown, "dvKnown")?,
                output(dvUnknown, nUnknown, "dvUnknown")?,
            )
        };
        i.slave_mut()
            .directional_derivative(unknowns, knowns, seed, result)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    call(c, Function::SetRealInputDerivatives, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, orders, values) = unsafe {
            (
                input(vr, nvr, "vr")?,
                input(order, nvr, "order")?,
                input(value, nvr, "value")?,
            )
        };
        i.slave_mut()
            .set_real_input_derivatives(vrs, orders, values)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: size_t,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(c, Function::GetRealOutputDerivatives, |i| {
        // SAFETY: module contract (arrays of nvr elements).
        let (vrs, orders, values) = unsafe {
            (
                input(vr, nvr, "vr")?,
                input(order, nvr, "order")?,
                output(value, nvr, "value")?,
            )
        };
        i.slave_mut()
            .get_real_output_derivatives(vrs, orders, values)
    })
}

// ------------------------------------------------------------------- steps

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    call(c, Function::DoStep, |i| {
        i.slave_mut()
            .do_step(currentCommunicationPoint, communicationStepSize)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    call(c, Function::CancelStep, Instance::cancel_step)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    call(c, Function::GetStatus, |i| {
        // SAFETY: module contract: value points to an fmi2Status.
        let value = unsafe { out_value(value, "value") }?;
        *value = status(i.get_status(s)?);
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    call(c, Function::GetRealStatus, |i| {
        // SAFETY: module contract: value points to an fmi2Real.
        let value = unsafe { out_value(value, "value") }?;
        *value = i.get_real_status(s)?;
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    call(c, Function::GetIntegerStatus, |i| {
        // SAFETY: module contract: value points to an fmi2Integer.
        let value = unsafe { out_value(value, "value") }?;
        *value = i.get_integer_status(s)?;
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    call(c, Function::GetBooleanStatus, |i| {
        // SAFETY: module contract: value points to an fmi2Boolean.
        let value = unsafe { out_value(value, "value") }?;
        *value = if i.get_boolean_status(s)? {
            FMI2_TRUE
        } else {
            FMI2_FALSE
        };
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    call(c, Function::GetStringStatus, |i| {
        // SAFETY: module contract: value points to an fmi2String. Nothing is
        // written: no String status is ever available.
        unsafe { out_value(value, "value") }?;
        i.get_string_status(s)
    })
}

// ---------------------------------------------------------- Model Exchange

/// Writes an `fmi2Boolean` out-argument.
fn set_flag(target: &mut fmi2Boolean, value: bool) {
    *target = if value { FMI2_TRUE } else { FMI2_FALSE };
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    call(c, Function::EnterEventMode, |i| {
        i.slave_mut().enter_event_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    call(c, Function::NewDiscreteStates, |i| {
        // SAFETY: module contract: eventInfo points to an fmi2EventInfo.
        let info = unsafe { out_value(eventInfo, "eventInfo") }?;
        let update = i.slave_mut().update_discrete_states()?;
        set_flag(&mut info.newDiscreteStatesNeeded, false);
        set_flag(&mut info.terminateSimulation, update.terminate_simulation);
        set_flag(&mut info.nominalsOfContinuousStatesChanged, false);
        set_flag(
            &mut info.valuesOfContinuousStatesChanged,
            update.values_of_continuous_states_changed,
        );
        set_flag(
            &mut info.nextEventTimeDefined,
            update.next_event_time.is_some(),
        );
        info.nextEventTime = update.next_event_time.unwrap_or(0.0);
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    call(c, Function::EnterContinuousTimeMode, |i| {
        i.slave_mut().enter_continuous_time_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    call(c, Function::CompletedIntegratorStep, |i| {
        // SAFETY: module contract: both point to an fmi2Boolean.
        let (enter, terminate) = unsafe {
            (
                out_value(enterEventMode, "enterEventMode")?,
                out_value(terminateSimulation, "terminateSimulation")?,
            )
        };
        let completion = i.slave_mut().completed_integrator_step()?;
        set_flag(enter, completion.enter_event_mode);
        set_flag(terminate, completion.terminate_simulation);
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    call(c, Function::SetTime, |i| i.slave_mut().set_time(time))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    x: *const fmi2Real,
    nx: size_t,
) -> fmi2Status {
    call(c, Function::SetContinuousStates, |i| {
        // SAFETY: module contract (an array of nx elements).
        let states = unsafe { input(x, nx, "x") }?;
        i.slave_mut().set_continuous_states(states)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: fmi2Component,
    derivatives: *mut fmi2Real,
    nx: size_t,
) -> fmi2Status {
    call(c, Function::GetDerivatives, |i| {
        // SAFETY: module contract (an array of nx elements).
        let out = unsafe { output(derivatives, nx, "derivatives") }?;
        i.slave_mut().get_derivatives(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: fmi2Component,
    eventIndicators: *mut fmi2Real,
    ni: size_t,
) -> fmi2Status {
    call(c, Function::GetEventIndicators, |i| {
        // SAFETY: module contract (an array of ni elements).
        let out = unsafe { output(eventIndicators, ni, "eventIndicators") }?;
        i.slave_mut().get_event_indicators(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: fmi2Component,
    x: *mut fmi2Real,
    nx: size_t,
) -> fmi2Status {
    call(c, Function::GetContinuousStates, |i| {
        // SAFETY: module contract (an array of nx elements).
        let out = unsafe { output(x, nx, "x") }?;
        i.slave_mut().get_continuous_states(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: size_t,
) -> fmi2Status {
    call(c, Function::GetNominalsOfContinuousStates, |i| {
        // SAFETY: module contract (an array of nx elements).
        let out = unsafe { output(x_nominal, nx, "x_nominal") }?;
        i.slave_mut().get_nominals(out)
    })
}

const _: () = assert!(FMI2_COSIMULATION == 1);

#[cfg(test)]
mod tests;
