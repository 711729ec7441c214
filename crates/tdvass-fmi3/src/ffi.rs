//! The C ABI: every fmi3 function of the FMI 3.0 standard, exported with C
//! linkage. The Co-Simulation and Model Exchange functions reach the safe
//! [`Instance`] through [`tdvass_fmu::entry`] ([`entry::call`],
//! [`entry::with_instance`]: the FMI 3.0 state table through
//! [`FrontEnd::run`], which logs failures, and every panic caught);
//! Scheduled Execution instantiation returns NULL with the reason logged,
//! and the functions of clocks and Scheduled Execution return `fmi3Error`
//! with the reason logged. Every entry point runs inside
//! [`std::panic::catch_unwind`]: a panic becomes `fmi3Fatal` instead of
//! unwinding into the host.
//!
//! Its length (all 75 functions of the standard, each a few lines of
//! conversions) is kept in one file on purpose: every `unsafe` of this
//! crate is then in one place.
//!
//! What both FMI versions do alike (the guarded call, `fmi3FreeInstance`,
//! `fmi3SetDebugLogging`, the FMU-state functions) is [`tdvass_fmu::entry`],
//! and pointer handling (tagged handles, arrays, strings) is
//! [`tdvass_fmu::pointers`], both shared with the FMI 2.0 FMU. This layer
//! holds the C signatures, the conversions of FMI 3.0's types and statuses,
//! and the intermediate-update loop of `fmi3DoStep`.
//!
//! # Safety
//!
//! The master must respect the FMI 3.0 calling convention: `instance` is
//! NULL or an instance returned by `fmi3InstantiateCoSimulation` and not yet
//! freed; every array argument is NULL or points to at least as many
//! elements as its count says; strings are NUL-terminated. Within that
//! contract nothing here is undefined behaviour; NULL pointers, unaligned
//! arrays and foreign FMU-state pointers are detected and refused. An
//! instance must not be used from two threads at the same time; inside the
//! `intermediateUpdate` callback the master may call the getters and
//! setters of the same instance (no reference to it is held across the
//! callback). `fmi3Boolean` is read as a byte (0 false, anything else true).
//! (The standard has about 90 functions; they stay in one file so that
//! every `unsafe` of the FMI 3.0 layer is here.)
// The only module of the crate that may use `unsafe` (denied elsewhere).
#![allow(unsafe_code)]
#![allow(non_camel_case_types, non_snake_case, clippy::missing_safety_doc)]

use crate::instance::{Instance, InstantiateRequest, IntermediatePoint};
use crate::states::Function;
use crate::types::ValueType;
use crate::{FmiError, Status};
use libc::{c_char, c_int, c_void, size_t};
use std::ffi::CStr;
use std::panic::{AssertUnwindSafe, catch_unwind};
use tdvass_fmu::entry::{self, FrontEnd, fmu_state};
use tdvass_fmu::pointers::{self, LogText, copy_str, input, out_value, output};
use tdvass_fmu::slave::LogSink;
use tdvass_fmu::variables::DependencyKind;

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
/// C99 `bool`, read and written as a byte.
pub type fmi3Boolean = u8;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const fmi3Byte;
/// C99 `bool`, read and written as a byte.
pub type fmi3Clock = u8;
pub type fmi3Status = c_int;
pub type fmi3DependencyKind = c_int;
pub type fmi3IntervalQualifier = c_int;

/// `fmi3LogMessageCallback`.
pub type fmi3LogMessageCallback =
    Option<unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String)>;
/// `fmi3IntermediateUpdateCallback`.
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        fmi3InstanceEnvironment,
        fmi3Float64,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        *mut fmi3Boolean,
        *mut fmi3Float64,
    ),
>;
/// `fmi3ClockUpdateCallback`.
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(fmi3InstanceEnvironment)>;
/// `fmi3LockPreemptionCallback` and `fmi3UnlockPreemptionCallback`.
pub type fmi3PreemptionCallback = Option<unsafe extern "C" fn()>;

const FMI3_TRUE: fmi3Boolean = 1;
const FMI3_FALSE: fmi3Boolean = 0;
/// `fmi3Fixed` of `fmi3DependencyKind`.
const FMI3_FIXED: fmi3DependencyKind = 2;
/// `fmi3Dependent` of `fmi3DependencyKind`.
const FMI3_DEPENDENT: fmi3DependencyKind = 5;

/// The tag of an FMI 3.0 instance handle (see [`pointers::Handle`]).
const HANDLE_MAGIC: u64 = 0x5444_5641_5353_4633; // "TDVASSF3"

/// What an instance pointer points to: the safe instance and the master's
/// callback for intermediate updates (with its environment).
pub struct Component {
    instance: Instance,
    environment: fmi3InstanceEnvironment,
    intermediate_update: fmi3IntermediateUpdateCallback,
}

impl AsMut<Instance> for Component {
    fn as_mut(&mut self) -> &mut Instance {
        &mut self.instance
    }
}

fn status(s: Status) -> fmi3Status {
    s as fmi3Status
}

/// The master's logger as a [`LogSink`] (a NULL logger logs nothing).
fn c_logger(logger: fmi3LogMessageCallback, environment: fmi3InstanceEnvironment) -> LogSink {
    let Some(logger) = logger else {
        return Box::new(|_, _, _| {});
    };
    Box::new(move |s: Status, category: &str, message: &str| {
        let category = LogText::new(category, false);
        let message = LogText::new(message, false);
        // SAFETY: `logger` is the master's callback with the FMI 3.0
        // signature; both strings are NUL-terminated and outlive the call.
        unsafe { logger(environment, status(s), category.as_ptr(), message.as_ptr()) }
    })
}

/// The component behind `instance`, if it looks like a live one.
///
/// # Safety
/// Module contract.
unsafe fn component<'a>(instance: fmi3Instance) -> Option<&'a mut Component> {
    // SAFETY: forwarded contract (a pointer from fmi3InstantiateCoSimulation).
    unsafe { pointers::handle::<Component>(instance, HANDLE_MAGIC) }.map(|h| &mut h.instance)
}

/// Runs `op` on the instance behind `instance` as `function`
/// ([`entry::with_instance`]: state table, logging, panics caught, then
/// `fmi3Fatal`). An invalid `instance` gives `fmi3Error`.
fn with_instance<T>(
    instance: fmi3Instance,
    function: Function,
    op: impl FnOnce(&mut Instance) -> Result<T, FmiError>,
) -> Result<T, Status> {
    // SAFETY: module contract.
    unsafe { entry::with_instance::<Component, Instance, T>(instance, HANDLE_MAGIC, function, op) }
}

/// [`with_instance`] for functions returning `fmi3Status`.
fn call(
    instance: fmi3Instance,
    function: Function,
    op: impl FnOnce(&mut Instance) -> Result<Status, FmiError>,
) -> fmi3Status {
    match with_instance(instance, function, op) {
        Ok(s) | Err(s) => status(s),
    }
}

/// For functions that do not apply to this FMU: logs why (when `instance`
/// is valid) and returns `fmi3Error`.
fn not_applicable(instance: fmi3Instance, function: &str, reason: &str) -> fmi3Status {
    let message = || {
        format!(
            "{function}: {reason}; this FMU implements Co-Simulation and Model Exchange, without clocks"
        )
    };
    // SAFETY: module contract.
    status(unsafe { entry::log_refusal::<Component, Instance>(instance, HANDLE_MAGIC, message) })
}

fn bools_from(values: &[fmi3Boolean]) -> Vec<bool> {
    values.iter().map(|&v| v != FMI3_FALSE).collect()
}

// ------------------------------------------------------------------ common

/// `FMI_VERSION` as a C string.
const FMI_VERSION_C: &CStr = c"3.0";

#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    catch_unwind(|| FMI_VERSION_C.as_ptr()).unwrap_or(std::ptr::null())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: size_t,
    categories: *const fmi3String,
) -> fmi3Status {
    call(instance, Function::SetDebugLogging, |i| {
        // SAFETY: module contract: `categories` holds `nCategories` strings.
        unsafe { entry::set_debug_logging(i, loggingOn != FMI3_FALSE, nCategories, categories) }
    })
}

/// Logs the refusal of an instantiation that this FMU does not offer.
fn refuse_instantiation(
    logger: fmi3LogMessageCallback,
    environment: fmi3InstanceEnvironment,
    function: &str,
    reason: &str,
) -> fmi3Instance {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        c_logger(logger, environment)(
            Status::Error,
            "logStatusError",
            &format!("{function}: {reason}"),
        )
    }));
    std::ptr::null_mut()
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    let made = catch_unwind(AssertUnwindSafe(|| {
        let sink = c_logger(logMessage, instanceEnvironment);
        // SAFETY: by contract NULL or a NUL-terminated string; copied.
        let name = unsafe { copy_str(instanceName) };
        // SAFETY: as above.
        let token = unsafe { copy_str(instantiationToken) };
        // SAFETY: as above.
        let resources = unsafe { copy_str(resourcePath) };
        let request = InstantiateRequest {
            instance_name: name.as_deref(),
            instantiation_token: token.as_deref(),
            resource_path: resources.as_deref(),
            logging_on: loggingOn != FMI3_FALSE,
            event_mode_used: false,
            early_return_allowed: false,
            required_intermediate_variables: &[],
            intermediate_update: false,
            model_exchange: true,
        };
        match Instance::instantiate(request, sink) {
            Some(instance) => pointers::into_raw(
                HANDLE_MAGIC,
                Component {
                    instance,
                    environment: instanceEnvironment,
                    intermediate_update: None,
                },
            ),
            None => std::ptr::null_mut(),
        }
    }));
    made.unwrap_or(std::ptr::null_mut())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    _clockUpdate: fmi3ClockUpdateCallback,
    _lockPreemption: fmi3PreemptionCallback,
    _unlockPreemption: fmi3PreemptionCallback,
) -> fmi3Instance {
    refuse_instantiation(
        logMessage,
        instanceEnvironment,
        "fmi3InstantiateScheduledExecution",
        "Scheduled Execution is not supported: this FMU implements Co-Simulation and Model Exchange",
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    earlyReturnAllowed: fmi3Boolean,
    requiredIntermediateVariables: *const fmi3ValueReference,
    nRequiredIntermediateVariables: size_t,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let made = catch_unwind(AssertUnwindSafe(|| {
        let sink = c_logger(logMessage, instanceEnvironment);
        // SAFETY: by contract NULL or a NUL-terminated string; copied.
        let name = unsafe { copy_str(instanceName) };
        // SAFETY: as above.
        let token = unsafe { copy_str(instantiationToken) };
        // SAFETY: as above.
        let resources = unsafe { copy_str(resourcePath) };
        // SAFETY: module contract: an array of the given length.
        let required = match unsafe {
            input(
                requiredIntermediateVariables,
                nRequiredIntermediateVariables,
                "requiredIntermediateVariables",
            )
        } {
            Ok(vrs) => vrs,
            Err(e) => {
                sink(
                    Status::Error,
                    "logStatusError",
                    &format!("fmi3InstantiateCoSimulation: {}", e.message),
                );
                return std::ptr::null_mut();
            }
        };
        let request = InstantiateRequest {
            instance_name: name.as_deref(),
            instantiation_token: token.as_deref(),
            resource_path: resources.as_deref(),
            logging_on: loggingOn != FMI3_FALSE,
            event_mode_used: eventModeUsed != FMI3_FALSE,
            early_return_allowed: earlyReturnAllowed != FMI3_FALSE,
            required_intermediate_variables: required,
            intermediate_update: intermediateUpdate.is_some(),
            model_exchange: false,
        };
        match Instance::instantiate(request, sink) {
            Some(instance) => pointers::into_raw(
                HANDLE_MAGIC,
                Component {
                    instance,
                    environment: instanceEnvironment,
                    intermediate_update: intermediateUpdate,
                },
            ),
            None => std::ptr::null_mut(),
        }
    }));
    made.unwrap_or(std::ptr::null_mut())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    // SAFETY: module contract; the master passes `instance` no more.
    unsafe {
        entry::free_instance::<Component, Instance>(instance, HANDLE_MAGIC, Function::FreeInstance)
    }
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    toleranceDefined: fmi3Boolean,
    tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    call(instance, Function::EnterInitializationMode, |i| {
        i.enter_initialization_mode(
            (toleranceDefined != FMI3_FALSE).then_some(tolerance),
            startTime,
            (stopTimeDefined != FMI3_FALSE).then_some(stopTime),
        )
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::ExitInitializationMode, |i| {
        i.slave_mut().exit_initialization_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::EnterEventMode, |i| {
        i.slave_mut().enter_event_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::Terminate, |i| i.slave_mut().terminate())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::Reset, |i| i.reset())
}

// --------------------------------------------------------- getters, setters

/// A getter whose values go through `get` (which checks the types).
fn getter<T>(
    instance: fmi3Instance,
    ty: ValueType,
    vrs: *const fmi3ValueReference,
    n_vrs: size_t,
    values: *mut T,
    n_values: size_t,
    get: impl FnOnce(&mut Instance, &[u32], &mut [T]) -> Result<Status, FmiError>,
) -> fmi3Status {
    call(instance, Function::Get(ty), |i| {
        // SAFETY: module contract (arrays of the given lengths).
        let (vrs, values) = unsafe {
            (
                input(vrs, n_vrs, "valueReferences")?,
                output(values, n_values, "values")?,
            )
        };
        get(i, vrs, values)
    })
}

/// A setter whose values go through `set` (which checks the types).
fn setter<T>(
    instance: fmi3Instance,
    ty: ValueType,
    vrs: *const fmi3ValueReference,
    n_vrs: size_t,
    values: *const T,
    n_values: size_t,
    set: impl FnOnce(&mut Instance, &[u32], &[T]) -> Result<Status, FmiError>,
) -> fmi3Status {
    call(instance, Function::Set(ty), |i| {
        // SAFETY: module contract (arrays of the given lengths).
        let (vrs, values) = unsafe {
            (
                input(vrs, n_vrs, "valueReferences")?,
                input(values, n_values, "values")?,
            )
        };
        set(i, vrs, values)
    })
}

/// `fmi3Get<Type>` and `fmi3Set<Type>` of one value type: the arrays go to
/// `$get_op` / `$set_op` through [`getter`] / [`setter`].
macro_rules! accessors {
    ($get:ident, $set:ident, $t:ty, $vt:expr, $get_op:expr, $set_op:expr) => {
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $get(
            instance: fmi3Instance,
            valueReferences: *const fmi3ValueReference,
            nValueReferences: size_t,
            values: *mut $t,
            nValues: size_t,
        ) -> fmi3Status {
            getter(
                instance,
                $vt,
                valueReferences,
                nValueReferences,
                values,
                nValues,
                $get_op,
            )
        }

        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $set(
            instance: fmi3Instance,
            valueReferences: *const fmi3ValueReference,
            nValueReferences: size_t,
            values: *const $t,
            nValues: size_t,
        ) -> fmi3Status {
            setter(
                instance,
                $vt,
                valueReferences,
                nValueReferences,
                values,
                nValues,
                $set_op,
            )
        }
    };
}

/// Getters and setters of the types no variable has: only an empty call
/// succeeds; every value reference is refused, naming its type.
macro_rules! unused_type {
    ($get:ident, $set:ident, $t:ty, $vt:expr) => {
        accessors!(
            $get,
            $set,
            $t,
            $vt,
            |i: &mut Instance, vrs: &[u32], _: &mut [$t]| i.no_variable_of(vrs, $vt),
            |i: &mut Instance, vrs: &[u32], _: &[$t]| i.no_variable_of(vrs, $vt)
        );
    };
}

unused_type!(
    fmi3GetFloat32,
    fmi3SetFloat32,
    fmi3Float32,
    ValueType::Float32
);
unused_type!(fmi3GetInt8, fmi3SetInt8, fmi3Int8, ValueType::Int8);
unused_type!(fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, ValueType::UInt8);
unused_type!(fmi3GetInt16, fmi3SetInt16, fmi3Int16, ValueType::Int16);
unused_type!(fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, ValueType::UInt16);
unused_type!(fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, ValueType::UInt32);
unused_type!(fmi3GetString, fmi3SetString, fmi3String, ValueType::String);

accessors!(
    fmi3GetFloat64,
    fmi3SetFloat64,
    fmi3Float64,
    ValueType::Float64,
    Instance::get_float64,
    Instance::set_float64
);
accessors!(
    fmi3GetInt32,
    fmi3SetInt32,
    fmi3Int32,
    ValueType::Int32,
    Instance::get_int32,
    Instance::set_int32
);
accessors!(
    fmi3GetInt64,
    fmi3SetInt64,
    fmi3Int64,
    ValueType::Int64,
    Instance::get_int64,
    Instance::set_int64
);
accessors!(
    fmi3GetUInt64,
    fmi3SetUInt64,
    fmi3UInt64,
    ValueType::UInt64,
    Instance::get_uint64,
    Instance::set_uint64
);
accessors!(
    fmi3GetBoolean,
    fmi3SetBoolean,
    fmi3Boolean,
    ValueType::Boolean,
    |i: &mut Instance, vrs: &[u32], out: &mut [fmi3Boolean]| {
        let mut flags = vec![false; out.len()];
        let s = i.get_boolean(vrs, &mut flags)?;
        for (o, f) in out.iter_mut().zip(flags) {
            *o = if f { FMI3_TRUE } else { FMI3_FALSE };
        }
        Ok(s)
    },
    |i: &mut Instance, vrs: &[u32], values: &[fmi3Boolean]| i.set_boolean(vrs, &bools_from(values))
);

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: size_t,
    _valueSizes: *mut size_t,
    values: *mut fmi3Binary,
    nValues: size_t,
) -> fmi3Status {
    getter(
        instance,
        ValueType::Binary,
        valueReferences,
        nValueReferences,
        values,
        nValues,
        |i, vrs, _| i.no_variable_of(vrs, ValueType::Binary),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: size_t,
    _valueSizes: *const size_t,
    values: *const fmi3Binary,
    nValues: size_t,
) -> fmi3Status {
    setter(
        instance,
        ValueType::Binary,
        valueReferences,
        nValueReferences,
        values,
        nValues,
        |i, vrs, _| i.no_variable_of(vrs, ValueType::Binary),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: size_t,
    _values: *mut fmi3Clock,
) -> fmi3Status {
    not_applicable(instance, "fmi3GetClock", "this FMU has no clocks")
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: size_t,
    _values: *const fmi3Clock,
) -> fmi3Status {
    not_applicable(instance, "fmi3SetClock", "this FMU has no clocks")
}

// ------------------------------------------------------------ dependencies

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    valueReference: fmi3ValueReference,
    nDependencies: *mut size_t,
) -> fmi3Status {
    call(instance, Function::GetNumberOfVariableDependencies, |i| {
        // SAFETY: module contract: a pointer to one size_t.
        let n = unsafe { out_value(nDependencies, "nDependencies") }?;
        *n = i.number_of_dependencies(valueReference)?;
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    dependent: fmi3ValueReference,
    elementIndicesOfDependent: *mut size_t,
    independents: *mut fmi3ValueReference,
    elementIndicesOfIndependents: *mut size_t,
    dependencyKinds: *mut fmi3DependencyKind,
    nDependencies: size_t,
) -> fmi3Status {
    call(instance, Function::GetVariableDependencies, |i| {
        let found = i.dependencies(dependent)?;
        if nDependencies != found.len() {
            return Err(FmiError::error(format!(
                "nDependencies = {nDependencies}, but the variable has {} (fmi3GetNumberOfVariableDependencies)",
                found.len()
            )));
        }
        // SAFETY: module contract: four arrays of nDependencies elements.
        let (element_of_dependent, vrs, element_of_independent, kinds) = unsafe {
            (
                output(
                    elementIndicesOfDependent,
                    nDependencies,
                    "elementIndicesOfDependent",
                )?,
                output(independents, nDependencies, "independents")?,
                output(
                    elementIndicesOfIndependents,
                    nDependencies,
                    "elementIndicesOfIndependents",
                )?,
                output(dependencyKinds, nDependencies, "dependencyKinds")?,
            )
        };
        for (k, (vr, kind)) in found.into_iter().enumerate() {
            element_of_dependent[k] = 0;
            vrs[k] = vr;
            element_of_independent[k] = 0;
            kinds[k] = match kind {
                DependencyKind::Fixed => FMI3_FIXED,
                DependencyKind::Dependent => FMI3_DEPENDENT,
            };
        }
        Ok(Status::Ok)
    })
}

// -------------------------------------------------------------- FMU states

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    call(instance, Function::GetFmuState, |i| {
        // SAFETY: module contract: FMUState points to an fmi3FMUState.
        unsafe { fmu_state::get(i, FMUState) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
) -> fmi3Status {
    call(instance, Function::SetFmuState, |i| {
        fmu_state::set(i, FMUState)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    call(instance, Function::FreeFmuState, |i| {
        // SAFETY: module contract: FMUState is NULL or points to an
        // fmi3FMUState.
        unsafe { fmu_state::free(i, FMUState) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut size_t,
) -> fmi3Status {
    call(instance, Function::SerializedFmuStateSize, |i| {
        // SAFETY: module contract: size points to a size_t.
        unsafe { fmu_state::serialized_size(i, FMUState, size) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: size_t,
) -> fmi3Status {
    call(instance, Function::SerializeFmuState, |i| {
        // SAFETY: module contract: serializedState holds `size` writable bytes.
        unsafe { fmu_state::serialize(i, FMUState, serializedState, size) }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: size_t,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    call(instance, Function::DeserializeFmuState, |i| {
        // SAFETY: module contract: `size` readable bytes and a state slot.
        unsafe { fmu_state::deserialize(i, serializedState, size, FMUState) }
    })
}

// ------------------------------------------------------------- derivatives

/// The arguments of the directional and adjoint derivatives, as slices;
/// `sensitivity` holds `n_sensitivity` values.
#[allow(clippy::too_many_arguments)]
fn derivative(
    instance: fmi3Instance,
    function: Function,
    unknowns: *const fmi3ValueReference,
    n_unknowns: size_t,
    knowns: *const fmi3ValueReference,
    n_knowns: size_t,
    seed: *const fmi3Float64,
    n_seed: size_t,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: size_t,
    adjoint: bool,
) -> fmi3Status {
    call(instance, function, |i| {
        let (seed_len, result_len) = if adjoint {
            (n_unknowns, n_knowns)
        } else {
            (n_knowns, n_unknowns)
        };
        if n_seed != seed_len || n_sensitivity != result_len {
            return Err(FmiError::error(format!(
                "nSeed = {n_seed} and nSensitivity = {n_sensitivity}, expected {seed_len} and {result_len} for {n_unknowns} unknowns and {n_knowns} knowns"
            )));
        }
        // SAFETY: module contract (arrays of the given lengths).
        let (unknowns, knowns, seed, result) = unsafe {
            (
                input(unknowns, n_unknowns, "unknowns")?,
                input(knowns, n_knowns, "knowns")?,
                input(seed, n_seed, "seed")?,
                output(sensitivity, n_sensitivity, "sensitivity")?,
            )
        };
        let slave = i.slave_mut();
        if adjoint {
            slave.adjoint_derivative(unknowns, knowns, seed, result)
        } else {
            slave.directional_derivative(unknowns, knowns, seed, result)
        }
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: size_t,
    knowns: *const fmi3ValueReference,
    nKnowns: size_t,
    seed: *const fmi3Float64,
    nSeed: size_t,
    sensitivity: *mut fmi3Float64,
    nSensitivity: size_t,
) -> fmi3Status {
    derivative(
        instance,
        Function::GetDirectionalDerivative,
        unknowns,
        nUnknowns,
        knowns,
        nKnowns,
        seed,
        nSeed,
        sensitivity,
        nSensitivity,
        false,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: size_t,
    knowns: *const fmi3ValueReference,
    nKnowns: size_t,
    seed: *const fmi3Float64,
    nSeed: size_t,
    sensitivity: *mut fmi3Float64,
    nSensitivity: size_t,
) -> fmi3Status {
    derivative(
        instance,
        Function::GetAdjointDerivative,
        unknowns,
        nUnknowns,
        knowns,
        nKnowns,
        seed,
        nSeed,
        sensitivity,
        nSensitivity,
        true,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: size_t,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: size_t,
) -> fmi3Status {
    call(instance, Function::GetOutputDerivatives, |i| {
        if nValues != nValueReferences {
            return Err(FmiError::error(format!(
                "nValues = {nValues} for {nValueReferences} value references"
            )));
        }
        // SAFETY: module contract (arrays of the given lengths).
        let (vrs, orders, values) = unsafe {
            (
                input(valueReferences, nValueReferences, "valueReferences")?,
                input(orders, nValueReferences, "orders")?,
                output(values, nValues, "values")?,
            )
        };
        i.slave_mut()
            .get_real_output_derivatives(vrs, orders, values)
    })
}

// ------------------------------------------------------ configuration mode

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::EnterConfigurationMode, |i| {
        i.enter_configuration_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::ExitConfigurationMode, |i| {
        i.exit_configuration_mode()
    })
}

// ----------------------------------------------------------------- stepping

/// The time of the next intermediate update, or `None` at the end of the
/// step; advances the instance there. `from`: the previous update (or the
/// step start).
fn advance_part(instance: fmi3Instance, from: f64, target: f64) -> Result<Option<f64>, Status> {
    with_instance(instance, Function::DoStep, |i| {
        let next = if i.has_intermediate_update() {
            i.slave().next_intermediate_time(from, target)
        } else {
            None
        };
        let until = next.unwrap_or(target);
        let slave = i.slave_mut();
        let span = until - slave.time();
        slave.advance_within_step(until, span)?;
        Ok(next)
    })
}

/// Calls the master's `intermediateUpdate` at `time` with no reference to
/// the instance held (the master may call getters and setters from it).
/// Returns whether the master asks to return early (only when allowed).
fn intermediate_update(instance: fmi3Instance, time: f64) -> Result<bool, Status> {
    // SAFETY: module contract.
    let Some(c) = (unsafe { component(instance) }) else {
        return Err(Status::Error);
    };
    let Some(callback) = c.intermediate_update else {
        return Ok(false);
    };
    let environment = c.environment;
    let can_return_early = c.instance.early_return_allowed();
    c.instance.enter_intermediate_update(IntermediatePoint {
        set_requested: true,
        get_allowed: true,
    });
    let mut requested = FMI3_FALSE;
    let mut requested_time = time;
    // SAFETY: the master's callback with the FMI 3.0 signature; the two
    // out-pointers point to locals; `c` is not used again before the call
    // returns (the master may reach the instance through its pointer).
    unsafe {
        callback(
            environment,
            time,
            FMI3_TRUE,
            FMI3_TRUE,
            FMI3_TRUE,
            if can_return_early {
                FMI3_TRUE
            } else {
                FMI3_FALSE
            },
            &mut requested,
            &mut requested_time,
        )
    };
    // SAFETY: module contract; a fresh reference after the callback.
    let Some(c) = (unsafe { component(instance) }) else {
        return Err(Status::Error);
    };
    c.instance.exit_intermediate_update();
    Ok(can_return_early && requested != FMI3_FALSE)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        let begun = with_instance(instance, Function::DoStep, |i| {
            // SAFETY: module contract: four pointers to single values.
            unsafe {
                out_value(eventHandlingNeeded, "eventHandlingNeeded")?;
                out_value(terminateSimulation, "terminateSimulation")?;
                out_value(earlyReturn, "earlyReturn")?;
                out_value(lastSuccessfulTime, "lastSuccessfulTime")?;
            }
            let slave = i.slave_mut();
            let start = slave.time();
            Ok((
                slave.begin_step(currentCommunicationPoint, communicationStepSize)?,
                start,
            ))
        });
        let (target, mut from) = match begun {
            Ok(plan) => plan,
            Err(s) => return (s, false, false),
        };
        loop {
            match advance_part(instance, from, target) {
                Ok(Some(time)) => match intermediate_update(instance, time) {
                    Ok(true) => return (Status::Ok, true, true),
                    Ok(false) => from = time,
                    Err(s) => return (s, false, true),
                },
                Ok(None) => return (Status::Ok, false, true),
                Err(s) => return (s, false, true),
            }
        }
    }));
    let (result, early, reported) = outcome.unwrap_or((Status::Fatal, false, false));
    if reported {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: module contract; the pointers were checked above.
            if let Some(c) = unsafe { component(instance) } {
                // SAFETY: the output pointers were checked non-NULL and
                // aligned above, and point to the caller's variables.
                unsafe {
                    *eventHandlingNeeded = FMI3_FALSE;
                    *terminateSimulation = if c.instance.slave().terminate_requested() {
                        FMI3_TRUE
                    } else {
                        FMI3_FALSE
                    };
                    *earlyReturn = if early { FMI3_TRUE } else { FMI3_FALSE };
                    *lastSuccessfulTime = c.instance.slave().last_successful_time();
                }
            }
        }));
    }
    status(result)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    not_applicable(
        instance,
        "fmi3EnterStepMode",
        "this FMU has no event mode (Step Mode follows fmi3ExitInitializationMode)",
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    _clockReference: fmi3ValueReference,
    _activationTime: fmi3Float64,
) -> fmi3Status {
    not_applicable(
        instance,
        "fmi3ActivateModelPartition",
        "Scheduled Execution is not supported",
    )
}

// ------------------------------------------ clocks and discrete evaluation

/// The functions of clocks and of discrete-state evaluation: refused with
/// the reason logged.
macro_rules! refused {
    ($name:ident ( $($arg:ident : $t:ty),* ), $reason:expr) => {
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            not_applicable(instance, stringify!($name), $reason)
        }
    };
}

const NO_CLOCKS: &str = "this FMU has no clocks";
const NO_EVENT_MODE: &str = "this FMU has no event mode";

refused!(fmi3GetIntervalDecimal(vrs: *const fmi3ValueReference, n: size_t, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier), NO_CLOCKS);
refused!(fmi3GetIntervalFraction(vrs: *const fmi3ValueReference, n: size_t, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier), NO_CLOCKS);
refused!(fmi3GetShiftDecimal(vrs: *const fmi3ValueReference, n: size_t, shifts: *mut fmi3Float64), NO_CLOCKS);
refused!(fmi3GetShiftFraction(vrs: *const fmi3ValueReference, n: size_t, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64), NO_CLOCKS);
refused!(fmi3SetIntervalDecimal(vrs: *const fmi3ValueReference, n: size_t, intervals: *const fmi3Float64), NO_CLOCKS);
refused!(fmi3SetIntervalFraction(vrs: *const fmi3ValueReference, n: size_t, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64), NO_CLOCKS);
refused!(fmi3SetShiftDecimal(vrs: *const fmi3ValueReference, n: size_t, shifts: *const fmi3Float64), NO_CLOCKS);
refused!(fmi3SetShiftFraction(vrs: *const fmi3ValueReference, n: size_t, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64), NO_CLOCKS);
refused!(fmi3EvaluateDiscreteStates(), NO_EVENT_MODE);

// ---------------------------------------------------------- Model Exchange

/// Writes an `fmi3Boolean` out-argument.
fn set_flag(target: &mut fmi3Boolean, value: bool) {
    *target = if value { FMI3_TRUE } else { FMI3_FALSE };
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    call(instance, Function::UpdateDiscreteStates, |i| {
        // SAFETY: module contract: each points to one value of its type.
        let (again, terminate, nominals, values, defined, next) = unsafe {
            (
                out_value(discreteStatesNeedUpdate, "discreteStatesNeedUpdate")?,
                out_value(terminateSimulation, "terminateSimulation")?,
                out_value(
                    nominalsOfContinuousStatesChanged,
                    "nominalsOfContinuousStatesChanged",
                )?,
                out_value(
                    valuesOfContinuousStatesChanged,
                    "valuesOfContinuousStatesChanged",
                )?,
                out_value(nextEventTimeDefined, "nextEventTimeDefined")?,
                out_value(nextEventTime, "nextEventTime")?,
            )
        };
        let update = i.slave_mut().update_discrete_states()?;
        set_flag(again, false);
        set_flag(terminate, update.terminate_simulation);
        set_flag(nominals, false);
        set_flag(values, update.values_of_continuous_states_changed);
        set_flag(defined, update.next_event_time.is_some());
        *next = update.next_event_time.unwrap_or(0.0);
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    call(instance, Function::EnterContinuousTimeMode, |i| {
        i.slave_mut().enter_continuous_time_mode()
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    enterEventMode: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    call(instance, Function::CompletedIntegratorStep, |i| {
        // SAFETY: module contract: both point to an fmi3Boolean.
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
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    call(instance, Function::SetTime, |i| {
        i.slave_mut().set_time(time)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *const fmi3Float64,
    nContinuousStates: size_t,
) -> fmi3Status {
    call(instance, Function::SetContinuousStates, |i| {
        // SAFETY: module contract (an array of nContinuousStates elements).
        let states = unsafe { input(continuousStates, nContinuousStates, "continuousStates") }?;
        i.slave_mut().set_continuous_states(states)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    derivatives: *mut fmi3Float64,
    nContinuousStates: size_t,
) -> fmi3Status {
    call(instance, Function::GetContinuousStateDerivatives, |i| {
        // SAFETY: module contract (an array of nContinuousStates elements).
        let out = unsafe { output(derivatives, nContinuousStates, "derivatives") }?;
        i.slave_mut().get_derivatives(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    eventIndicators: *mut fmi3Float64,
    nEventIndicators: size_t,
) -> fmi3Status {
    call(instance, Function::GetEventIndicators, |i| {
        // SAFETY: module contract (an array of nEventIndicators elements).
        let out = unsafe { output(eventIndicators, nEventIndicators, "eventIndicators") }?;
        i.slave_mut().get_event_indicators(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *mut fmi3Float64,
    nContinuousStates: size_t,
) -> fmi3Status {
    call(instance, Function::GetContinuousStates, |i| {
        // SAFETY: module contract (an array of nContinuousStates elements).
        let out = unsafe { output(continuousStates, nContinuousStates, "continuousStates") }?;
        i.slave_mut().get_continuous_states(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    nContinuousStates: size_t,
) -> fmi3Status {
    call(instance, Function::GetNominalsOfContinuousStates, |i| {
        // SAFETY: module contract (an array of nContinuousStates elements).
        let out = unsafe { output(nominals, nContinuousStates, "nominals") }?;
        i.slave_mut().get_nominals(out)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    nEventIndicators: *mut size_t,
) -> fmi3Status {
    call(instance, Function::GetNumberOfEventIndicators, |i| {
        // SAFETY: module contract: points to a size_t.
        *unsafe { out_value(nEventIndicators, "nEventIndicators") }? =
            i.slave().model().event_indicators();
        Ok(Status::Ok)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    nContinuousStates: *mut size_t,
) -> fmi3Status {
    call(instance, Function::GetNumberOfContinuousStates, |i| {
        // SAFETY: module contract: points to a size_t.
        *unsafe { out_value(nContinuousStates, "nContinuousStates") }? =
            i.slave().model().continuous_states().len();
        Ok(Status::Ok)
    })
}

#[cfg(test)]
mod tests;
