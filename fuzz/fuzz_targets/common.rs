//! Shared by the fuzz targets: the FMI C entry points of the library (the
//! same code as `tdvass.so`, linked statically and instrumented), a logger,
//! and a reader of fuzzer bytes.
#![allow(dead_code)]

use std::ffi::{CStr, c_char, c_int, c_void};
pub use tdvass_fmi2::ffi::*;

/// Status codes.
pub const OK: fmi2Status = 0;
pub const WARNING: fmi2Status = 1;
pub const DISCARD: fmi2Status = 2;
pub const ERROR: fmi2Status = 3;
pub const FATAL: fmi2Status = 4;

/// The logger, non-variadic: the FMU passes no variadic argument (every `%`
/// of the message is doubled), and on the x86-64 System V and AArch64 Linux
/// ABIs a call through a variadic pointer reaches a non-variadic function
/// with the same fixed arguments unchanged (what ctypes and most masters do).
/// Reads every string, so a dangling pointer would be caught.
extern "C" fn logger(
    _env: *mut c_void,
    name: *const c_char,
    _status: c_int,
    category: *const c_char,
    message: *const c_char,
) {
    for s in [name, category, message] {
        assert!(!s.is_null(), "the FMU logged a NULL string");
        // SAFETY: the FMU passes NUL-terminated strings valid for the call.
        let text = unsafe { CStr::from_ptr(s) };
        std::hint::black_box(text.to_bytes().len());
    }
}

/// Callbacks with [`logger`].
pub fn callbacks() -> fmi2CallbackFunctions {
    type Fixed = extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char);
    type Variadic =
        unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);
    let fixed: Fixed = logger;
    fmi2CallbackFunctions {
        // SAFETY: see `logger` (same fixed arguments, C ABI, no variadic one used).
        logger: Some(unsafe { std::mem::transmute::<Fixed, Variadic>(fixed) }),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    }
}

/// The quarter car's GUID as a C string.
pub fn guid() -> std::ffi::CString {
    guid_of(tdvass_fmi2::Model::QuarterCar)
}

/// The GUID of `model` as a C string.
pub fn guid_of(model: tdvass_fmi2::Model) -> std::ffi::CString {
    std::ffi::CString::new(tdvass_fmi2::guid(model)).unwrap()
}

/// A Co-Simulation instance of the quarter car (NULL if refused).
pub fn instantiate(callbacks: &fmi2CallbackFunctions, logging: bool) -> fmi2Component {
    instantiate_model(callbacks, logging, tdvass_fmi2::Model::QuarterCar)
}

/// A Co-Simulation instance of `model` (NULL if refused).
pub fn instantiate_model(
    callbacks: &fmi2CallbackFunctions,
    logging: bool,
    model: tdvass_fmi2::Model,
) -> fmi2Component {
    let guid = guid_of(model);
    // SAFETY: valid strings and callbacks that outlive the instance.
    unsafe {
        fmi2Instantiate(
            c"fuzz".as_ptr(),
            1,
            guid.as_ptr(),
            c"file:///tmp/resources".as_ptr(),
            callbacks,
            0,
            logging as c_int,
        )
    }
}

/// A Model Exchange instance (NULL if refused).
pub fn instantiate_model_exchange(
    callbacks: &fmi2CallbackFunctions,
    logging: bool,
) -> fmi2Component {
    let guid = guid();
    // SAFETY: valid strings and callbacks that outlive the instance.
    unsafe {
        fmi2Instantiate(
            c"fuzz".as_ptr(),
            0,
            guid.as_ptr(),
            c"file:///tmp/resources".as_ptr(),
            callbacks,
            0,
            logging as c_int,
        )
    }
}

/// A status must be one of fmi2OK .. fmi2Error: fmi2Fatal means a panic
/// inside the library (caught by the FFI layer), which is a bug.
#[track_caller]
pub fn check(status: fmi2Status) -> fmi2Status {
    assert!(
        (OK..=ERROR).contains(&status),
        "unexpected status {status} (fmi2Fatal = an internal panic)"
    );
    status
}

/// Consumes fuzzer bytes; zeros when exhausted.
pub struct Bytes<'a> {
    data: &'a [u8],
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data }
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// How many bytes are left.
    pub fn remaining(&self) -> usize {
        self.data.len()
    }
    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    pub fn u64(&mut self) -> u64 {
        (self.u32() as u64) | ((self.u32() as u64) << 32)
    }
    pub fn pick<T: Copy>(&mut self, options: &[T]) -> T {
        options[self.u8() as usize % options.len()]
    }
    pub fn take(&mut self, n: usize) -> &'a [u8] {
        let n = n.min(self.data.len());
        let (head, rest) = self.data.split_at(n);
        self.data = rest;
        head
    }
    pub fn rest(&mut self) -> &'a [u8] {
        self.take(self.data.len())
    }
}

/// Interesting Real values: specials, bounds, defaults, and raw bits.
pub fn real(b: &mut Bytes) -> f64 {
    const INTERESTING: [f64; 24] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MAX,
        f64::MIN_POSITIVE,
        1e-300,
        1e300,
        1e-12,
        1e-4,
        2e-4,
        0.001,
        0.1,
        5386.0,
        -40000.0,
        0.11,
        345.0,
        1e3,
        1e6,
        1e12,
        1e13,
    ];
    match b.u8() % 4 {
        0 => f64::from_bits(b.u64()),
        1 => (b.u32() as i32) as f64 * 1e-3,
        _ => b.pick(&INTERESTING),
    }
}

/// The value references of every variable, plus unknown ones.
pub fn value_reference(b: &mut Bytes) -> u32 {
    match b.u8() % 8 {
        0 => b.u32(),
        1 => b.pick(&[0, 48, 99, u32::MAX]),
        _ => 1 + b.u8() as u32 % 47,
    }
}

/// The models a call-sequence target instantiates, picked by a byte it
/// reads anyway (the quarter car twice as often).
pub const MODELS: [tdvass_fmi2::Model; 4] = [
    tdvass_fmi2::Model::QuarterCar,
    tdvass_fmi2::Model::QuarterCar,
    tdvass_fmi2::Model::Corner,
    tdvass_fmi2::Model::Chassis,
];

/// A value reference for `model`: mostly one of its variables', sometimes
/// another model's or none at all.
pub fn value_reference_of(b: &mut Bytes, model: tdvass_fmi2::Model) -> u32 {
    use tdvass_fmi2::variables::{FmiVersion, variables_of};
    match b.u8() % 4 {
        0 => value_reference(b),
        _ => {
            let variables = variables_of(model, FmiVersion::Fmi2);
            variables[b.u8() as usize % variables.len()].vr
        }
    }
}

/// Every output of the quarter car is finite.
pub fn assert_outputs_finite(c: fmi2Component) {
    assert_outputs_of_finite(c, tdvass_fmi2::Model::QuarterCar);
}

/// Every Real output of `model` is finite.
pub fn assert_outputs_of_finite(c: fmi2Component, model: tdvass_fmi2::Model) {
    use tdvass_fmi2::variables::{Causality, FmiVersion, VarType, variables_of};
    let vrs: Vec<u32> = variables_of(model, FmiVersion::Fmi2)
        .iter()
        .filter(|v| v.causality == Causality::Output && v.var_type() == VarType::Real)
        .map(|v| v.vr)
        .collect();
    let mut values = vec![f64::NAN; vrs.len()];
    for (vr, value) in vrs.iter().zip(values.iter_mut()) {
        // SAFETY: one value reference, one value.
        let s = check(unsafe { fmi2GetReal(c, vr, 1, value) });
        if s == OK {
            assert!(value.is_finite(), "fmi2GetReal gave {value} for vr {vr}");
        }
    }
}
