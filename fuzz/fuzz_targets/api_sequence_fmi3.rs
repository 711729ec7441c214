//! (A fuzz target is one source file: hence its length.) Fuzzes sequences
//! of FMI 3.0 calls with random arguments on up to two
//! instances (Co-Simulation or Model Exchange, of the quarter car, the
//! corner or the chassis, as the input chooses) and their FMU states (also
//! between two models): wrong states, Configuration Mode and structural
//! parameters, NULL arrays and out-pointers, unknown value references and
//! wrong types, array lengths, NaN/Inf/huge values, bad steps, foreign and
//! freed FMU states (also between the two kinds), corrupted serializations
//! (also under the FMI 2.0 GUID), the functions that do not apply,
//! intermediate updates: a callback that reads and sets variables, calls
//! what is not allowed there and asks for an early return; and Model
//! Exchange: time, continuous states with fuzzed values and counts,
//! derivatives, event indicators, nominals, the model's sizes, completed
//! integrator steps (also whole Euler steps), Event Mode with its discrete
//! updates and Continuous-Time Mode.
//!
//! Invariants: no call returns fmi3Fatal (a panic inside the library) or an
//! unknown status; a successful getter or fmi3DoStep never leaves a
//! non-finite Float64; inside an intermediate update every function but the
//! getters and setters is refused; an early return happens only when the
//! master allowed and asked for it, at a time inside the step; successful
//! Model Exchange getters give finite values (nominals > 0), the sizes are
//! the model's, the flags written are 0 or 1 (and no event is asked for: the
//! model has state events only); every call returns (libFuzzer's -timeout
//! catches a hang).
#![no_main]

#[path = "common.rs"]
mod common;

use common::{Bytes, MODELS, real};
use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, c_char, c_int};
use std::ptr::{null, null_mut};
use tdvass_fmi2::Model;
use tdvass_fmi2::variables::{Causality, FmiVersion, VarType, variables_of};
use tdvass_fmi3::ffi::*;

const OK: fmi3Status = 0;
const ERROR: fmi3Status = 3;

/// A variable of `model` (the quarter car's value references are 1..=52,
/// 51 the array `rightmost_roots`), or an unknown value reference.
fn value_reference(b: &mut Bytes, model: Model) -> u32 {
    match b.u8() % 8 {
        0 => b.u32(),
        1 => b.pick(&[0, 53, 99, u32::MAX]),
        _ => {
            let variables = variables_of(model, FmiVersion::Fmi3);
            variables[b.u8() as usize % variables.len()].vr
        }
    }
}

/// The value references of `model`'s Float64 variables of `causality`.
fn of_causality(model: Model, causality: Causality) -> Vec<u32> {
    variables_of(model, FmiVersion::Fmi3)
        .iter()
        .filter(|v| v.causality == causality && v.var_type() == VarType::Real)
        .map(|v| v.vr)
        .collect()
}

fn vrs(b: &mut Bytes, n: usize, model: Model) -> Vec<u32> {
    (0..n).map(|_| value_reference(b, model)).collect()
}

fn maybe_null<T>(b: &mut Bytes, v: &[T]) -> *const T {
    if b.u8().is_multiple_of(16) {
        null()
    } else {
        v.as_ptr()
    }
}

fn maybe_null_mut<T>(b: &mut Bytes, v: &mut [T]) -> *mut T {
    if b.u8().is_multiple_of(16) {
        null_mut()
    } else {
        v.as_mut_ptr()
    }
}

/// A count near `n`: the right one most of the time.
fn count_near(b: &mut Bytes, n: usize) -> usize {
    match b.u8() % 8 {
        0 => n + 1,
        1 => n.saturating_sub(1),
        2 => b.u8() as usize % 16,
        _ => n,
    }
}

/// A time step of a master's integrator (or a fuzzed value).
fn time_step(b: &mut Bytes) -> f64 {
    if b.u8().is_multiple_of(8) {
        real(b)
    } else {
        b.pick(&[1e-5, 1e-4, 1e-4, 1e-3, 0.01, 0.0, -1e-4, 0.5])
    }
}

/// A flag written by the FMU: 0 or 1.
#[track_caller]
fn flag(value: u8) {
    assert!(value <= 1, "an fmi3Boolean of {value}");
}

/// A status must be one of fmi3OK .. fmi3Error: fmi3Fatal means a panic
/// inside the library (caught by the FFI layer), which is a bug.
#[track_caller]
fn check(status: fmi3Status) -> fmi3Status {
    assert!(
        (OK..=ERROR).contains(&status),
        "unexpected status {status} (fmi3Fatal = an internal panic)"
    );
    status
}

/// `FUZZ_TRACE=1`: print the calls (to minimise a finding by hand).
fn trace() -> bool {
    static TRACE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *TRACE.get_or_init(|| std::env::var_os("FUZZ_TRACE").is_some())
}

/// The logger. Reads every string, so a dangling pointer would be caught.
unsafe extern "C" fn logger(
    _env: fmi3InstanceEnvironment,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    assert!((OK..=4).contains(&status), "logged status {status}");
    for s in [category, message] {
        assert!(!s.is_null(), "the FMU logged a NULL string");
        // SAFETY: the FMU passes NUL-terminated strings valid for the call.
        let text = unsafe { CStr::from_ptr(s) };
        std::hint::black_box(text.to_bytes().len());
    }
}

/// What the intermediate-update callback of one instance does: its own
/// fuzzer bytes (a copy taken when the step began), read at each update.
struct Master {
    instance: fmi3Instance,
    /// The model its instantiation token names.
    model: Model,
    script: Vec<u8>,
    at: usize,
    early_return_allowed: bool,
    /// Updates seen in the current step, and the last one's time.
    updates: usize,
    last_update: f64,
    /// An early return was asked for in the current step.
    asked: bool,
}

/// The getters of every FMI 3.0 type, on `vrs`, with `n` values (Float64
/// values must be finite when the call succeeds).
///
/// # Safety
/// `c` is NULL or a live instance.
unsafe fn get_all(b: &mut Bytes, c: fmi3Instance, vrs: &[u32]) {
    let n = count_near(b, vrs.len());
    let p = maybe_null(b, vrs);
    let mut reals = vec![0.0f64; n + 32];
    let out = maybe_null_mut(b, &mut reals);
    // SAFETY (every call): arrays hold at least the counts passed, or are NULL.
    unsafe {
        if check(fmi3GetFloat64(c, p, vrs.len(), out, n)) == OK {
            assert!(
                reals[..n].iter().all(|x| x.is_finite()),
                "fmi3GetFloat64 gave {:?} for {vrs:?}",
                &reals[..n]
            );
        }
        let mut i32s = vec![0i32; n];
        check(fmi3GetInt32(
            c,
            p,
            vrs.len(),
            maybe_null_mut(b, &mut i32s),
            n,
        ));
        let mut i64s = vec![0i64; n];
        check(fmi3GetInt64(
            c,
            p,
            vrs.len(),
            maybe_null_mut(b, &mut i64s),
            n,
        ));
        let mut u64s = vec![0u64; n];
        check(fmi3GetUInt64(
            c,
            p,
            vrs.len(),
            maybe_null_mut(b, &mut u64s),
            n,
        ));
        let mut bools = vec![0u8; n];
        check(fmi3GetBoolean(
            c,
            p,
            vrs.len(),
            maybe_null_mut(b, &mut bools),
            n,
        ));
        let mut f32s = vec![0f32; n];
        check(fmi3GetFloat32(c, p, vrs.len(), f32s.as_mut_ptr(), n));
        let mut strings = vec![null(); n];
        check(fmi3GetString(c, p, vrs.len(), strings.as_mut_ptr(), n));
        let mut sizes = vec![0usize; n];
        let mut binaries = vec![null(); n];
        check(fmi3GetBinary(
            c,
            p,
            vrs.len(),
            sizes.as_mut_ptr(),
            binaries.as_mut_ptr(),
            n,
        ));
    }
}

/// One setter of a random type on `vrs`.
///
/// # Safety
/// `c` is NULL or a live instance.
unsafe fn set_one(b: &mut Bytes, c: fmi3Instance, vrs: &[u32]) {
    let n = count_near(b, vrs.len());
    let p = maybe_null(b, vrs);
    let kind = b.u8() % 6;
    if trace() {
        eprintln!("  set kind {kind} {vrs:?} ({n} values)");
    }
    // SAFETY (every call): arrays hold at least the counts passed, or are NULL.
    unsafe {
        match kind {
            0 | 1 => {
                let values: Vec<f64> = (0..n).map(|_| real(b)).collect();
                check(fmi3SetFloat64(c, p, vrs.len(), maybe_null(b, &values), n));
            }
            2 => {
                let values: Vec<i64> = (0..n)
                    .map(|_| b.pick(&[0, 1, 2, 3, 4, 8, 9, -1, i64::MAX, i64::MIN, 1 << 40]))
                    .collect();
                check(fmi3SetInt64(c, p, vrs.len(), maybe_null(b, &values), n));
            }
            3 => {
                let values: Vec<i32> = (0..n)
                    .map(|_| b.pick(&[0, 1, 2, 3, 7, -1, i32::MAX, i32::MIN]))
                    .collect();
                check(fmi3SetInt32(c, p, vrs.len(), maybe_null(b, &values), n));
            }
            4 => {
                let values: Vec<u64> = (0..n)
                    .map(|_| b.pick(&[0, 1, 2, 3, 6, 16, 17, u64::MAX, 1 << 33]))
                    .collect();
                check(fmi3SetUInt64(c, p, vrs.len(), maybe_null(b, &values), n));
            }
            _ => {
                let values: Vec<u8> = (0..n).map(|_| b.u8()).collect();
                check(fmi3SetBoolean(c, p, vrs.len(), maybe_null(b, &values), n));
            }
        }
    }
}

/// The intermediate-update callback: reads and sets variables, makes calls
/// that are refused inside an update, and asks for an early return.
unsafe extern "C" fn on_update(
    environment: fmi3InstanceEnvironment,
    time: fmi3Float64,
    _clock_active: fmi3Boolean,
    set_requested: fmi3Boolean,
    get_allowed: fmi3Boolean,
    can_return_early: fmi3Boolean,
    early_return_requested: *mut fmi3Boolean,
    early_return_time: *mut fmi3Float64,
) {
    // SAFETY: the environment is this instance's `Master` (alive until the
    // instance is freed, not otherwise referenced during fmi3DoStep).
    let master = unsafe { &mut *(environment as *mut Master) };
    assert!(
        time.is_finite() && time > master.last_update,
        "update at {time}"
    );
    assert_eq!(
        can_return_early != 0,
        master.early_return_allowed,
        "canReturnEarly"
    );
    assert!(set_requested <= 1 && get_allowed <= 1);
    master.updates += 1;
    master.last_update = time;
    let c = master.instance;
    let script = std::mem::take(&mut master.script);
    let start = master.at.min(script.len());
    let mut b = Bytes::new(&script[start..]);
    let mut ask = false;
    // SAFETY (every call): `c` is the live instance of this callback; arrays
    // hold at least the counts passed, or are NULL.
    unsafe {
        for _ in 0..(b.u8() % 3) {
            match b.u8() % 8 {
                0 | 1 => {
                    // The model's outputs.
                    let n = 1 + b.u8() as usize % 4;
                    let outputs = of_causality(master.model, Causality::Output);
                    let v: Vec<u32> = (0..n).map(|_| b.pick(&outputs)).collect();
                    get_all(&mut b, c, &v);
                }
                2 => {
                    // One of the model's inputs (the quarter car's x_g; the
                    // corner's body attachment; the chassis's forces).
                    let v = [b.pick(&of_causality(master.model, Causality::Input))];
                    let value = [real(&mut b)];
                    check(fmi3SetFloat64(c, v.as_ptr(), 1, value.as_ptr(), 1));
                }
                3 => {
                    let n = b.u8() as usize % 3;
                    let v = vrs(&mut b, n, master.model);
                    if b.u8().is_multiple_of(2) {
                        get_all(&mut b, c, &v);
                    } else {
                        set_one(&mut b, c, &v);
                    }
                }
                4 => {
                    // Everything but getters and setters is refused here.
                    let (mut e, mut t, mut r, mut l) = (0u8, 0u8, 0u8, 0.0);
                    let mut state: fmi3FMUState = null_mut();
                    let statuses = [
                        fmi3DoStep(c, time, 1e-3, 0, &mut e, &mut t, &mut r, &mut l),
                        fmi3Reset(c),
                        fmi3Terminate(c),
                        fmi3GetFMUState(c, &mut state),
                        fmi3EnterConfigurationMode(c),
                        fmi3SetDebugLogging(c, 0, 0, null()),
                        fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0),
                    ];
                    assert!(
                        statuses.iter().all(|&s| s == ERROR),
                        "allowed inside an intermediate update: {statuses:?}"
                    );
                    assert!(state.is_null());
                    // Refused too (the instance stays usable).
                    fmi3FreeInstance(c);
                }
                5 => {
                    let v = [49u32];
                    let value = [b.pick(&[0.0, 1e-4, 1e-3, 0.01, -1.0, f64::NAN])];
                    check(fmi3SetFloat64(c, v.as_ptr(), 1, value.as_ptr(), 1));
                }
                _ => ask = true,
            }
        }
        master.at = script.len() - b.remaining();
        if ask {
            *early_return_requested = 1;
            *early_return_time = time;
            master.asked |= can_return_early != 0;
        }
    }
    master.script = script;
}

struct Slot {
    c: fmi3Instance,
    /// The time the master believes the instance is at.
    time: f64,
    master: *mut Master,
    /// The model its instantiation token names.
    model: Model,
}

struct State {
    owner: usize,
    handle: fmi3FMUState,
    time: f64,
}

const STEPS: [f64; 14] = [
    1e-4,
    1e-3,
    1e-3,
    0.01,
    0.01,
    0.05,
    0.0,
    -1e-3,
    f64::NAN,
    f64::INFINITY,
    1e9,
    1e-12,
    0.3,
    2.0,
];

fn slot_of(b: &mut Bytes) -> usize {
    b.u8() as usize % 2
}

/// Frees an instance and its master.
///
/// # Safety
/// A live slot, not used again.
unsafe fn free_slot(slot: Slot) {
    // SAFETY: a live instance; the master was made by Box::into_raw and
    // the callback can no longer run.
    unsafe {
        fmi3FreeInstance(slot.c);
        drop(Box::from_raw(slot.master));
    }
}

fuzz_target!(|data: &[u8]| {
    let tokens = MODELS
        .map(|model| std::ffi::CString::new(tdvass_fmi3::instantiation_token(model)).unwrap());
    let fmi2_guid = tdvass_fmi2::guid(tdvass_fmi2::Model::QuarterCar);
    let mut b = Bytes::new(data);
    let mut slots: [Option<Slot>; 2] = [None, None];
    let mut states: Vec<State> = Vec::new();
    let mut calls = 0;
    while !b.is_empty() && calls < 48 {
        calls += 1;
        let op = b.u8() % 32;
        let i = slot_of(&mut b);
        // The slot's model (the quarter car for an empty slot): its value
        // references, and for Model Exchange its counts of continuous
        // states and event indicators.
        let model = slots[i].as_ref().map_or(Model::QuarterCar, |s| s.model);
        let (nx, nz) = (model.continuous_states().len(), model.event_indicators());
        if trace() {
            eprintln!("call {calls}: op {op} on slot {i}");
        }
        if op == 0 {
            if slots[i].is_none() {
                // The byte that picks the name picks the model too.
                let pick = b.u8() as usize;
                let name = [c"a".as_ptr(), c"a".as_ptr(), c"".as_ptr(), null()][pick % 4];
                let which = pick / 4 % MODELS.len();
                let (model, token) = (MODELS[which], &tokens[which]);
                if trace() {
                    eprintln!("  instantiate: {model:?}");
                }
                let t = b.pick(&[
                    token.as_ptr(),
                    token.as_ptr(),
                    token.as_ptr(),
                    c"{x}".as_ptr(),
                    null(),
                ]);
                let flags = b.u8();
                // Model Exchange (fmi3InstantiateModelExchange) for 1 in 4.
                let model_exchange = flags & 0xc0 == 0xc0;
                let early = flags & 1 != 0;
                let with_callback = flags & 2 != 0;
                let event_mode = flags & 0x1c == 0x1c;
                let required: Vec<u32> = if flags & 0x20 != 0 {
                    vrs(&mut b, 2, model)
                } else {
                    Vec::new()
                };
                let master = Box::into_raw(Box::new(Master {
                    instance: null_mut(),
                    model,
                    script: Vec::new(),
                    at: 0,
                    early_return_allowed: early,
                    updates: 0,
                    last_update: f64::NEG_INFINITY,
                    asked: false,
                }));
                let callback: fmi3IntermediateUpdateCallback =
                    if with_callback { Some(on_update) } else { None };
                let resources = b.pick(&[null(), c"file:///tmp/r".as_ptr(), c"".as_ptr()]);
                let logging = b.u8() % 2;
                // SAFETY: valid or NULL strings, a logger and a callback
                // whose environment outlives the instance.
                let c = unsafe {
                    if model_exchange {
                        fmi3InstantiateModelExchange(
                            name,
                            t,
                            resources,
                            0,
                            logging,
                            master.cast(),
                            Some(logger),
                        )
                    } else {
                        fmi3InstantiateCoSimulation(
                            name,
                            t,
                            resources,
                            0,
                            logging,
                            event_mode as u8,
                            early as u8,
                            required.as_ptr(),
                            required.len(),
                            master.cast(),
                            Some(logger),
                            callback,
                        )
                    }
                };
                if c.is_null() {
                    // SAFETY: made above, never reached by the library.
                    drop(unsafe { Box::from_raw(master) });
                } else {
                    // SAFETY: made above; the library does not run the
                    // callback before fmi3DoStep.
                    unsafe { (*master).instance = c };
                    slots[i] = Some(Slot {
                        c,
                        time: 0.0,
                        master,
                        model,
                    });
                }
            }
            continue;
        }
        // Calls on NULL when the slot is empty.
        let c = slots[i].as_ref().map_or(null_mut(), |s| s.c);
        // SAFETY (every call below): `c` is NULL or a live instance; every
        // array holds at least the count passed, or is NULL.
        unsafe {
            match op {
                1 => {
                    if let Some(slot) = slots[i].take() {
                        free_slot(slot);
                        states.retain(|s| s.owner != i);
                    } else {
                        fmi3FreeInstance(null_mut());
                    }
                }
                2 => {
                    let (start, stop) = (
                        if b.u8().is_multiple_of(4) {
                            real(&mut b)
                        } else {
                            0.0
                        },
                        real(&mut b),
                    );
                    if trace() {
                        eprintln!(
                            "  fmi3EnterInitializationMode(start = {start:e}, stop = {stop:e})"
                        );
                    }
                    let s = check(fmi3EnterInitializationMode(
                        c,
                        b.u8() % 2,
                        real(&mut b),
                        start,
                        b.u8() % 2,
                        stop,
                    ));
                    if s == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = start;
                    }
                }
                3 => {
                    check(fmi3ExitInitializationMode(c));
                }
                4 => {
                    check(fmi3Terminate(c));
                }
                5 => {
                    if check(fmi3Reset(c)) == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = 0.0;
                    }
                }
                6 | 7 => {
                    let n = b.u8() as usize % 4;
                    let v = vrs(&mut b, n, model);
                    set_one(&mut b, c, &v);
                }
                8 => {
                    let n = b.u8() as usize % 5;
                    let v = vrs(&mut b, n, model);
                    get_all(&mut b, c, &v);
                }
                9 => {
                    // rightmost_roots (root_count x 2), alone or with scalars.
                    let mut v = vec![51u32];
                    if b.u8().is_multiple_of(2) {
                        v.push(value_reference(&mut b, model));
                    }
                    let n = b.u8() as usize % 40;
                    let mut out = vec![0.0; n];
                    if check(fmi3GetFloat64(c, v.as_ptr(), v.len(), out.as_mut_ptr(), n)) == OK {
                        assert!(out.iter().all(|x| x.is_finite()), "{out:?}");
                    }
                }
                10..=12 => {
                    let slot_time = slots[i].as_ref().map_or(0.0, |s| s.time);
                    let t = if b.u8().is_multiple_of(8) {
                        real(&mut b)
                    } else {
                        slot_time
                    };
                    let h = if b.u8().is_multiple_of(8) {
                        real(&mut b)
                    } else {
                        b.pick(&STEPS)
                    };
                    let nulls = b.u8();
                    let script_len = b.u8() as usize;
                    let script = b.take(script_len).to_vec();
                    if let Some(slot) = slots[i].as_ref() {
                        let m = &mut *slot.master;
                        m.script = script;
                        m.at = 0;
                        m.updates = 0;
                        m.last_update = f64::NEG_INFINITY;
                        m.asked = false;
                    }
                    if trace() {
                        eprintln!("  fmi3DoStep(t = {t:e}, h = {h:e}, nulls {nulls:#x})");
                    }
                    let (mut event, mut terminate, mut early, mut last) = (7u8, 7u8, 7u8, f64::NAN);
                    let pick = |bit: u8, p: *mut u8| {
                        if nulls & bit == bit && nulls > 0xf0 {
                            null_mut()
                        } else {
                            p
                        }
                    };
                    let s = check(fmi3DoStep(
                        c,
                        t,
                        h,
                        b.u8() % 2,
                        pick(1, &mut event),
                        pick(2, &mut terminate),
                        pick(4, &mut early),
                        if nulls & 8 == 8 && nulls > 0xf0 {
                            null_mut()
                        } else {
                            &mut last as *mut f64
                        },
                    ));
                    if let Some(slot) = slots[i].as_mut() {
                        let m = &*slot.master;
                        if s == OK {
                            assert!(
                                event == 0 && terminate <= 1,
                                "fmi3DoStep flags {event} {terminate}"
                            );
                            assert!(early <= 1, "earlyReturn = {early}");
                            if early == 1 {
                                assert!(
                                    m.early_return_allowed && m.asked,
                                    "an early return nobody asked for"
                                );
                                assert!(
                                    last > t && last < t + h && last == m.last_update,
                                    "early return at {last} in [{t}, {}]",
                                    t + h
                                );
                                slot.time = last;
                            } else {
                                assert!(
                                    last == t + h
                                        || (last - (t + h)).abs() <= 1e-9 * (t + h).abs().max(h),
                                    "lastSuccessfulTime {last} after a step to {}",
                                    t + h
                                );
                                slot.time = t + h;
                            }
                            get_all(&mut b, c, &(31..=45).collect::<Vec<u32>>());
                        } else if s == 2 {
                            assert!(
                                last.is_finite() && terminate == 1,
                                "discard: {last} {terminate}"
                            );
                            get_all(&mut b, c, &(31..=45).collect::<Vec<u32>>());
                        }
                    }
                }
                13 => {
                    let mut handle: fmi3FMUState = null_mut();
                    let reuse = states
                        .iter()
                        .position(|s| s.owner == i && b.u8().is_multiple_of(2));
                    if let Some(k) = reuse {
                        handle = states[k].handle;
                    }
                    if check(fmi3GetFMUState(c, &mut handle)) == OK {
                        let time = slots[i].as_ref().map_or(0.0, |s| s.time);
                        match reuse {
                            Some(k) => states[k].time = time,
                            None => states.push(State {
                                owner: i,
                                handle,
                                time,
                            }),
                        }
                    }
                }
                14 => {
                    // Own, foreign (another instance's) or NULL states.
                    let pick = (!states.is_empty()).then(|| b.u8() as usize % states.len());
                    let handle = pick.map_or(null_mut(), |k| states[k].handle);
                    if check(fmi3SetFMUState(c, handle)) == OK
                        && let (Some(k), Some(slot)) = (pick, slots[i].as_mut())
                    {
                        slot.time = states[k].time;
                    }
                }
                15 => {
                    if states.is_empty() {
                        check(fmi3FreeFMUState(c, null_mut()));
                    } else {
                        let k = b.u8() as usize % states.len();
                        let mut handle = states[k].handle;
                        if check(fmi3FreeFMUState(c, &mut handle)) == OK && handle.is_null() {
                            states.remove(k);
                        }
                    }
                }
                16 => {
                    if let Some(k) = (!states.is_empty()).then(|| b.u8() as usize % states.len()) {
                        let handle = states[k].handle;
                        let mut size = 0usize;
                        if check(fmi3SerializedFMUStateSize(c, handle, &mut size)) == OK {
                            let mut bytes = vec![0u8; size];
                            let n = if b.u8().is_multiple_of(4) {
                                size / 2
                            } else {
                                size
                            };
                            if check(fmi3SerializeFMUState(c, handle, bytes.as_mut_ptr(), n)) == OK
                            {
                                match b.u8() % 4 {
                                    0 if size > 0 => {
                                        let at = b.u32() as usize % size;
                                        bytes[at] ^= b.u8() | 1;
                                    }
                                    1 => {
                                        // The FMI 2.0 FMU's header: same format, its GUID.
                                        let token = tdvass_fmi3::instantiation_token(
                                            tdvass_fmi2::Model::QuarterCar,
                                        );
                                        if token.len() == fmi2_guid.len()
                                            && let Some(at) = bytes
                                                .windows(token.len())
                                                .position(|w| w == token.as_bytes())
                                        {
                                            bytes[at..at + token.len()]
                                                .copy_from_slice(fmi2_guid.as_bytes());
                                        }
                                    }
                                    _ => {}
                                }
                                let cut = if b.u8().is_multiple_of(4) {
                                    b.u32() as usize % (size + 1)
                                } else {
                                    size
                                };
                                let target = slot_of(&mut b);
                                let tc = slots[target].as_ref().map_or(null_mut(), |s| s.c);
                                let mut out: fmi3FMUState = null_mut();
                                if check(fmi3DeserializeFMUState(tc, bytes.as_ptr(), cut, &mut out))
                                    == OK
                                {
                                    states.push(State {
                                        owner: target,
                                        handle: out,
                                        time: states[k].time,
                                    });
                                }
                            }
                        }
                    }
                }
                17 => {
                    let n = b.u8() as usize % 3;
                    let m = b.u8() as usize % 3;
                    let unknowns = vrs(&mut b, n, model);
                    let knowns = vrs(&mut b, m, model);
                    let adjoint = b.u8().is_multiple_of(2);
                    let (n_seed, n_out) = if adjoint { (n, m) } else { (m, n) };
                    let (n_seed, n_out) = (count_near(&mut b, n_seed), count_near(&mut b, n_out));
                    let seed: Vec<f64> = (0..n_seed).map(|_| real(&mut b)).collect();
                    let mut result = vec![0.0; n_out];
                    let f = if adjoint {
                        fmi3GetAdjointDerivative
                    } else {
                        fmi3GetDirectionalDerivative
                    };
                    if check(f(
                        c,
                        maybe_null(&mut b, &unknowns),
                        n,
                        maybe_null(&mut b, &knowns),
                        m,
                        maybe_null(&mut b, &seed),
                        n_seed,
                        maybe_null_mut(&mut b, &mut result),
                        n_out,
                    )) == OK
                    {
                        assert!(result.iter().all(|x| x.is_finite()), "{result:?}");
                    }
                }
                18 => {
                    let n = b.u8() as usize % 3;
                    let v = vrs(&mut b, n, model);
                    let orders: Vec<i32> = (0..n).map(|_| b.pick(&[1, 1, 2, 0, -1])).collect();
                    let mut out = vec![0.0; n];
                    if check(fmi3GetOutputDerivatives(
                        c,
                        maybe_null(&mut b, &v),
                        n,
                        maybe_null(&mut b, &orders),
                        out.as_mut_ptr(),
                        count_near(&mut b, n).min(n),
                    )) == OK
                    {
                        assert!(out.iter().all(|x| x.is_finite()), "{out:?}");
                    }
                    let vr = value_reference(&mut b, model);
                    let mut k = 0usize;
                    if check(fmi3GetNumberOfVariableDependencies(c, vr, &mut k)) == OK {
                        let k = count_near(&mut b, k);
                        let (mut e, mut v, mut ei, mut kinds) = (
                            vec![0usize; k],
                            vec![0u32; k],
                            vec![0usize; k],
                            vec![0 as c_int; k],
                        );
                        check(fmi3GetVariableDependencies(
                            c,
                            vr,
                            e.as_mut_ptr(),
                            v.as_mut_ptr(),
                            ei.as_mut_ptr(),
                            kinds.as_mut_ptr(),
                            k,
                        ));
                    }
                }
                19 => {
                    if check(fmi3EnterConfigurationMode(c)) == OK {
                        // root_count, sometimes out of range or with another variable.
                        let mut v = vec![50u32];
                        if b.u8().is_multiple_of(4) {
                            v.push(value_reference(&mut b, model));
                        }
                        let values: Vec<u64> =
                            v.iter().map(|_| b.pick(&[1, 3, 4, 6, 16, 0, 17])).collect();
                        check(fmi3SetUInt64(
                            c,
                            v.as_ptr(),
                            v.len(),
                            values.as_ptr(),
                            v.len(),
                        ));
                        let mut out = [0u64; 2];
                        check(fmi3GetUInt64(
                            c,
                            v.as_ptr(),
                            v.len(),
                            out.as_mut_ptr(),
                            v.len(),
                        ));
                        if !b.u8().is_multiple_of(4) {
                            check(fmi3ExitConfigurationMode(c));
                        }
                    } else {
                        check(fmi3ExitConfigurationMode(c));
                    }
                }
                20 => {
                    let categories: [*const c_char; 4] = [
                        c"logEvents".as_ptr(),
                        c"logAll".as_ptr(),
                        c"nope".as_ptr(),
                        null(),
                    ];
                    let n = b.u8() as usize % 3;
                    let list: Vec<fmi3String> = (0..n).map(|_| b.pick(&categories)).collect();
                    check(fmi3SetDebugLogging(
                        c,
                        b.u8() % 2,
                        n,
                        maybe_null(&mut b, &list),
                    ));
                }
                21 => {
                    // The functions that do not apply: refused in every state.
                    let mut flag = 0u8;
                    let statuses = [
                        fmi3EnterStepMode(c),
                        fmi3GetClock(c, [1u32].as_ptr(), 1, &mut flag),
                        fmi3ActivateModelPartition(c, 1, 0.0),
                        fmi3EvaluateDiscreteStates(c),
                    ];
                    assert!(statuses.iter().all(|&s| s == ERROR), "{statuses:?}");
                    // Model Exchange functions with wrong lengths, anywhere.
                    let mut x = [0.0f64; 2];
                    check(fmi3SetTime(c, real(&mut b)));
                    check(fmi3GetContinuousStates(c, x.as_mut_ptr(), 2));
                    check(fmi3CompletedIntegratorStep(c, 1, &mut flag, &mut flag));
                }
                24 => {
                    // Model Exchange: the time, forward from where the
                    // master believes the instance is (or anywhere).
                    let slot_time = slots[i].as_ref().map_or(0.0, |s| s.time);
                    let t = slot_time + time_step(&mut b);
                    if trace() {
                        eprintln!("  fmi3SetTime({t:e})");
                    }
                    if check(fmi3SetTime(c, t)) == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = t;
                    }
                }
                25 => {
                    // Continuous states: the current ones perturbed, or
                    // fuzzed values; a count near the model's, sometimes
                    // NULL.
                    let mut x = vec![0.0; nx + 4];
                    if check(fmi3GetContinuousStates(c, x.as_mut_ptr(), nx)) != OK {
                        x = vec![0.0; nx + 4];
                    }
                    for _ in 0..b.u8() % 4 {
                        let k = b.u8() as usize % x.len();
                        x[k] = match b.u8() % 3 {
                            0 => real(&mut b),
                            1 => x[k] * b.pick(&[1.0001, -1.0, 1e3, 1e9]),
                            _ => x[k] + b.pick(&[1e-3, -1e-2, 0.1, 1e9]),
                        };
                    }
                    let n = count_near(&mut b, nx).min(x.len());
                    if trace() {
                        eprintln!("  fmi3SetContinuousStates({:?}, {n})", &x[..n]);
                    }
                    check(fmi3SetContinuousStates(c, maybe_null(&mut b, &x), n));
                }
                26 => {
                    let n = count_near(&mut b, nx);
                    let mut dx = vec![f64::NAN; n.max(1)];
                    if check(fmi3GetContinuousStateDerivatives(
                        c,
                        maybe_null_mut(&mut b, &mut dx),
                        n,
                    )) == OK
                    {
                        assert_eq!(n, nx);
                        assert!(dx[..n].iter().all(|v| v.is_finite()), "derivatives {dx:?}");
                    }
                    let n = count_near(&mut b, nz);
                    let mut z = vec![f64::NAN; n.max(1)];
                    if check(fmi3GetEventIndicators(c, maybe_null_mut(&mut b, &mut z), n)) == OK {
                        assert_eq!(n, nz);
                        assert!(
                            z[..n].iter().all(|v| v.is_finite()),
                            "event indicators {z:?}"
                        );
                    }
                }
                27 => {
                    let (mut enter, mut terminate) = (7u8, 7u8);
                    let nulls = b.u8();
                    let e = if nulls % 8 == 1 {
                        null_mut()
                    } else {
                        &mut enter as *mut u8
                    };
                    let t = if nulls % 8 == 2 {
                        null_mut()
                    } else {
                        &mut terminate as *mut u8
                    };
                    if check(fmi3CompletedIntegratorStep(c, (nulls >> 4) % 2, e, t)) == OK {
                        assert_eq!(enter, 0, "enterEventMode: the model has state events only");
                        flag(terminate);
                    }
                }
                28 => {
                    // Event Mode: enter it, discrete updates, back to
                    // Continuous-Time Mode, in an order the input picks.
                    for _ in 0..1 + b.u8() % 4 {
                        match b.u8() % 3 {
                            0 => {
                                check(fmi3EnterEventMode(c));
                            }
                            1 => {
                                let mut flags = [7u8; 5];
                                let mut next = f64::NAN;
                                let nulls = b.u8();
                                let out = |k: usize, p: *mut u8| {
                                    if nulls > 0xf0 && nulls % 6 == k as u8 {
                                        null_mut()
                                    } else {
                                        p
                                    }
                                };
                                let [f0, f1, f2, f3, f4] = &mut flags;
                                let s = check(fmi3UpdateDiscreteStates(
                                    c,
                                    out(0, f0),
                                    out(1, f1),
                                    out(2, f2),
                                    out(3, f3),
                                    out(4, f4),
                                    if nulls > 0xf0 && nulls % 6 == 5 {
                                        null_mut()
                                    } else {
                                        &mut next as *mut f64
                                    },
                                ));
                                if s == OK {
                                    assert_eq!(flags[0], 0, "discreteStatesNeedUpdate");
                                    flags.iter().for_each(|&f| flag(f));
                                    assert!(next.is_finite());
                                }
                            }
                            _ => {
                                check(fmi3EnterContinuousTimeMode(c));
                            }
                        }
                    }
                }
                29 => {
                    let n = count_near(&mut b, nx);
                    let mut x = vec![f64::NAN; n.max(1)];
                    if check(fmi3GetContinuousStates(
                        c,
                        maybe_null_mut(&mut b, &mut x),
                        n,
                    )) == OK
                    {
                        assert!(x[..n].iter().all(|v| v.is_finite()), "states {x:?}");
                    }
                    let n = count_near(&mut b, nx);
                    let mut nominal = vec![f64::NAN; n.max(1)];
                    if check(fmi3GetNominalsOfContinuousStates(
                        c,
                        maybe_null_mut(&mut b, &mut nominal),
                        n,
                    )) == OK
                    {
                        assert!(
                            nominal[..n].iter().all(|v| v.is_finite() && *v > 0.0),
                            "nominals {nominal:?}"
                        );
                    }
                }
                30 => {
                    let mut n = 7usize;
                    let p = if b.u8().is_multiple_of(16) {
                        null_mut()
                    } else {
                        &mut n as *mut usize
                    };
                    if check(fmi3GetNumberOfContinuousStates(c, p)) == OK {
                        assert_eq!(n, nx);
                    }
                    let mut n = 7usize;
                    let p = if b.u8().is_multiple_of(16) {
                        null_mut()
                    } else {
                        &mut n as *mut usize
                    };
                    if check(fmi3GetNumberOfEventIndicators(c, p)) == OK {
                        assert_eq!(n, nz);
                    }
                }
                31 => {
                    // Explicit Euler steps of the master's integrator, as a
                    // master makes them (the way deep into a run).
                    let h = b.pick(&[1e-5, 1e-4, 1e-4, 1e-3, 0.01]);
                    for _ in 0..1 + b.u8() % 8 {
                        let mut x = vec![0.0; nx];
                        let mut dx = vec![0.0; nx];
                        if check(fmi3GetContinuousStates(c, x.as_mut_ptr(), nx)) != OK
                            || check(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), nx))
                                != OK
                        {
                            break;
                        }
                        let t = slots[i].as_ref().map_or(0.0, |s| s.time) + h;
                        if check(fmi3SetTime(c, t)) != OK {
                            break;
                        }
                        if let Some(slot) = slots[i].as_mut() {
                            slot.time = t;
                        }
                        for (v, d) in x.iter_mut().zip(dx) {
                            *v += h * d;
                        }
                        let (mut enter, mut terminate) = (7u8, 7u8);
                        if check(fmi3SetContinuousStates(c, x.as_ptr(), nx)) != OK
                            || check(fmi3CompletedIntegratorStep(
                                c,
                                1,
                                &mut enter,
                                &mut terminate,
                            )) != OK
                        {
                            break;
                        }
                        assert_eq!(enter, 0);
                        flag(terminate);
                        if terminate == 1 {
                            break;
                        }
                    }
                    get_all(&mut b, c, &(31..=45).collect::<Vec<u32>>());
                }
                _ => {
                    // Tunable parameters and the input while simulating.
                    let vr = b.pick(&[10u32, 21, 22, 23, 30, 30, 49]);
                    let value = real(&mut b);
                    if trace() {
                        eprintln!("  fmi3SetFloat64([{vr}], [{value:e}])");
                    }
                    check(fmi3SetFloat64(c, &vr, 1, &value, 1));
                }
            }
        }
    }
    for slot in slots.iter_mut() {
        if let Some(s) = slot.take() {
            // SAFETY: a live slot, not used again.
            unsafe { free_slot(s) };
        }
    }
});
