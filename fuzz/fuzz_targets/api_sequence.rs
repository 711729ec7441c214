//! Fuzzes sequences of FMI calls with random arguments on up to two
//! instances (Co-Simulation or Model Exchange, of the quarter car, the
//! corner or the chassis, as the input chooses) and their FMU states
//! (also between two models): wrong states, NULL arrays, unknown value references,
//! NaN/Inf/huge values, bad steps, foreign and freed FMU states (also
//! between the two kinds), corrupted serializations, and Model Exchange:
//! time, continuous states with fuzzed values and counts, derivatives,
//! event indicators, nominals, completed integrator steps (also whole
//! Euler steps), Event Mode with its event updates and Continuous-Time
//! Mode.
//!
//! Invariants: no call returns fmi2Fatal (a panic inside the library) or an
//! unknown status; a successful fmi2GetReal or fmi2DoStep never leaves a
//! non-finite output; successful Model Exchange getters give finite values
//! (nominals > 0) and the flags they write are fmi2True or fmi2False (and
//! no event is asked for: the model has state events only); every call
//! returns (libFuzzer's -timeout catches a hang).
#![no_main]

#[path = "common.rs"]
mod common;

use common::*;
use libfuzzer_sys::fuzz_target;
use std::ptr::{null, null_mut};
use tdvass_fmi2::Model;

struct Slot {
    c: fmi2Component,
    /// The time the master believes the instance is at.
    time: f64,
    /// The model its GUID names.
    model: Model,
}

struct State {
    owner: usize,
    handle: fmi2FMUstate,
    time: f64,
}

const STEPS: [f64; 12] = [
    1e-4,
    1e-3,
    0.01,
    0.1,
    0.5,
    0.0,
    -1e-3,
    f64::NAN,
    f64::INFINITY,
    1e9,
    1e-12,
    2.0,
];

/// `FUZZ_TRACE=1`: print the calls (to minimise a finding by hand).
fn trace() -> bool {
    static TRACE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *TRACE.get_or_init(|| std::env::var_os("FUZZ_TRACE").is_some())
}

fn slot_of(b: &mut Bytes) -> usize {
    b.u8() as usize % 2
}

/// `n` value references of `model`, or NULL (with `n` > 0 sometimes).
fn vrs(b: &mut Bytes, n: usize, model: Model) -> Vec<u32> {
    (0..n).map(|_| value_reference_of(b, model)).collect()
}

/// The values a master sets while simulating: `model`'s inputs and tunable
/// parameters.
fn settable(model: Model) -> Vec<u32> {
    use tdvass_fmi2::variables::{Causality, FmiVersion, Variability, variables_of};
    variables_of(model, FmiVersion::Fmi2)
        .iter()
        .filter(|v| v.causality == Causality::Input || v.variability == Variability::Tunable)
        .map(|v| v.vr)
        .collect()
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
        2 => b.u8() as usize % 24,
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

/// A flag written by the FMU: fmi2True or fmi2False.
#[track_caller]
fn flag(value: fmi2Boolean) {
    assert!(value == 0 || value == 1, "an fmi2Boolean of {value}");
}

fuzz_target!(|data: &[u8]| {
    let callbacks = callbacks();
    let mut b = Bytes::new(data);
    let mut slots: [Option<Slot>; 2] = [None, None];
    let mut states: Vec<State> = Vec::new();
    let mut calls = 0;
    while !b.is_empty() && calls < 64 {
        calls += 1;
        let op = b.u8() % 30;
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
                let name = b.pick(&[c"a".as_ptr(), c"".as_ptr(), null()]);
                // fmi2CoSimulation, fmi2ModelExchange, or an unknown type;
                // the same byte picks the model.
                let pick = b.u8() as usize;
                let kind = [1, 1, 0, 0, 7][pick % 5];
                let model = MODELS[pick / 5 % MODELS.len()];
                let guid = guid_of(model);
                if trace() {
                    eprintln!("  fmi2Instantiate: {model:?}, fmi2Type {kind}");
                }
                let g = b.pick(&[guid.as_ptr(), guid.as_ptr(), c"{x}".as_ptr(), null()]);
                let uri = b.pick(&[
                    null(),
                    c"file:///tmp/r".as_ptr(),
                    c"http://x/y".as_ptr(),
                    c"file:///%zz".as_ptr(),
                    c"".as_ptr(),
                ]);
                // SAFETY: valid or NULL strings, callbacks outliving the instance.
                let c = unsafe {
                    fmi2Instantiate(name, kind, g, uri, &callbacks, 0, b.u8() as i32 % 2)
                };
                if !c.is_null() {
                    slots[i] = Some(Slot {
                        c,
                        time: 0.0,
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
                    fmi2FreeInstance(c);
                    if slots[i].take().is_some() {
                        states.retain(|s| s.owner != i);
                    }
                }
                2 => {
                    let (start, stop) = (real(&mut b), real(&mut b));
                    if trace() {
                        eprintln!("  fmi2SetupExperiment(start = {start:e}, stop = {stop:e})");
                    }
                    let s = check(fmi2SetupExperiment(
                        c,
                        1,
                        real(&mut b),
                        start,
                        b.u8() as i32 % 2,
                        stop,
                    ));
                    if s == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = start;
                    }
                }
                3 => {
                    check(fmi2EnterInitializationMode(c));
                }
                4 => {
                    check(fmi2ExitInitializationMode(c));
                }
                5 => {
                    check(fmi2Terminate(c));
                }
                6 => {
                    if check(fmi2Reset(c)) == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = 0.0;
                    }
                }
                7 => {
                    let n = b.u8() as usize % 4;
                    let v = vrs(&mut b, n, model);
                    let values: Vec<f64> = (0..n).map(|_| real(&mut b)).collect();
                    if trace() {
                        eprintln!("  fmi2SetReal({v:?}, {values:?})");
                    }
                    check(fmi2SetReal(
                        c,
                        maybe_null(&mut b, &v),
                        n,
                        maybe_null(&mut b, &values),
                    ));
                }
                8 => {
                    let n = b.u8() as usize % 4;
                    let v = vrs(&mut b, n, model);
                    let values: Vec<i32> = (0..n)
                        .map(|_| b.pick(&[0, 1, 2, 3, 4, 8, 9, -1, i32::MAX, i32::MIN]))
                        .collect();
                    if trace() {
                        eprintln!("  fmi2SetInteger({v:?}, {values:?})");
                    }
                    check(fmi2SetInteger(
                        c,
                        maybe_null(&mut b, &v),
                        n,
                        maybe_null(&mut b, &values),
                    ));
                }
                9 => {
                    let n = b.u8() as usize % 3;
                    let v = vrs(&mut b, n, model);
                    let values: Vec<i32> = (0..n).map(|_| b.u8() as i32 - 1).collect();
                    check(fmi2SetBoolean(
                        c,
                        maybe_null(&mut b, &v),
                        n,
                        maybe_null(&mut b, &values),
                    ));
                }
                10 => {
                    let n = b.u8() as usize % 5;
                    let v = vrs(&mut b, n, model);
                    let mut reals = vec![0.0; n];
                    let p = maybe_null(&mut b, &v);
                    let out = maybe_null_mut(&mut b, &mut reals);
                    if check(fmi2GetReal(c, p, n, out)) == OK {
                        assert!(
                            reals.iter().all(|x| x.is_finite()),
                            "fmi2GetReal gave {reals:?} for {v:?}"
                        );
                    }
                    let mut ints = vec![0; n];
                    check(fmi2GetInteger(c, p, n, maybe_null_mut(&mut b, &mut ints)));
                    check(fmi2GetBoolean(c, p, n, maybe_null_mut(&mut b, &mut ints)));
                    let mut strings = vec![null(); n];
                    check(fmi2GetString(c, p, n, maybe_null_mut(&mut b, &mut strings)));
                }
                11 => {
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
                    if trace() {
                        eprintln!("  fmi2DoStep(t = {t:e}, h = {h:e})");
                    }
                    let s = check(fmi2DoStep(c, t, h, 0));
                    if s == OK {
                        if let Some(slot) = slots[i].as_mut() {
                            slot.time = t + h;
                        }
                        assert_outputs_of_finite(c, model);
                    }
                }
                12 => {
                    let mut handle: fmi2FMUstate = null_mut();
                    let reuse = states
                        .iter()
                        .position(|s| s.owner == i && b.u8().is_multiple_of(2));
                    if let Some(k) = reuse {
                        handle = states[k].handle;
                    }
                    if check(fmi2GetFMUstate(c, &mut handle)) == OK {
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
                13 => {
                    // Own, foreign (another instance's) or NULL states.
                    let pick = if states.is_empty() {
                        None
                    } else {
                        Some(b.u8() as usize % states.len())
                    };
                    let handle = pick.map_or(null_mut(), |k| states[k].handle);
                    if check(fmi2SetFMUstate(c, handle)) == OK
                        && let (Some(k), Some(slot)) = (pick, slots[i].as_mut())
                    {
                        slot.time = states[k].time;
                    }
                }
                14 => {
                    if states.is_empty() {
                        check(fmi2FreeFMUstate(c, null_mut()));
                    } else {
                        let k = b.u8() as usize % states.len();
                        let mut handle = states[k].handle;
                        if check(fmi2FreeFMUstate(c, &mut handle)) == OK && handle.is_null() {
                            states.remove(k);
                        }
                    }
                }
                15 => {
                    if let Some(k) = (!states.is_empty()).then(|| b.u8() as usize % states.len()) {
                        let handle = states[k].handle;
                        let mut size = 0usize;
                        if check(fmi2SerializedFMUstateSize(c, handle, &mut size)) == OK {
                            let mut bytes = vec![0u8; size];
                            let short = (b.u8() as usize).is_multiple_of(4);
                            let n = if short { size / 2 } else { size };
                            if check(fmi2SerializeFMUstate(
                                c,
                                handle,
                                bytes.as_mut_ptr().cast(),
                                n,
                            )) == OK
                            {
                                if b.u8().is_multiple_of(2) && size > 0 {
                                    let at = b.u32() as usize % size;
                                    bytes[at] ^= b.u8() | 1;
                                }
                                let cut = if b.u8().is_multiple_of(4) {
                                    b.u32() as usize % (size + 1)
                                } else {
                                    size
                                };
                                let target = slot_of(&mut b);
                                let tc = slots[target].as_ref().map_or(null_mut(), |s| s.c);
                                let mut out: fmi2FMUstate = null_mut();
                                if check(fmi2DeSerializeFMUstate(
                                    tc,
                                    bytes.as_ptr().cast(),
                                    cut,
                                    &mut out,
                                )) == OK
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
                16 => {
                    let kind = b.pick(&[0, 1, 2, 3, -1, 99]);
                    let mut status = 0;
                    let mut real_value = 0.0;
                    let mut int = 0;
                    let mut string: fmi2String = null();
                    check(fmi2GetStatus(
                        c,
                        kind,
                        maybe_null_mut(&mut b, std::slice::from_mut(&mut status)),
                    ));
                    check(fmi2GetRealStatus(
                        c,
                        kind,
                        maybe_null_mut(&mut b, std::slice::from_mut(&mut real_value)),
                    ));
                    check(fmi2GetIntegerStatus(c, kind, &mut int));
                    check(fmi2GetBooleanStatus(c, kind, &mut int));
                    check(fmi2GetStringStatus(c, kind, &mut string));
                }
                17 => {
                    let n = b.u8() as usize % 3;
                    let m = b.u8() as usize % 3;
                    let unknowns = vrs(&mut b, n, model);
                    let knowns = vrs(&mut b, m, model);
                    let seed: Vec<f64> = (0..m).map(|_| real(&mut b)).collect();
                    let mut result = vec![0.0; n];
                    if check(fmi2GetDirectionalDerivative(
                        c,
                        maybe_null(&mut b, &unknowns),
                        n,
                        maybe_null(&mut b, &knowns),
                        m,
                        maybe_null(&mut b, &seed),
                        maybe_null_mut(&mut b, &mut result),
                    )) == OK
                    {
                        assert!(result.iter().all(|x| x.is_finite()), "{result:?}");
                    }
                }
                18 => {
                    let n = b.u8() as usize % 3;
                    let v = vrs(&mut b, n, model);
                    let orders: Vec<i32> = (0..n).map(|_| b.pick(&[1, 1, 2, 0, -1, 3])).collect();
                    let values: Vec<f64> = (0..n).map(|_| real(&mut b)).collect();
                    check(fmi2SetRealInputDerivatives(
                        c,
                        maybe_null(&mut b, &v),
                        n,
                        orders.as_ptr(),
                        values.as_ptr(),
                    ));
                    let mut out = vec![0.0; n];
                    if check(fmi2GetRealOutputDerivatives(
                        c,
                        v.as_ptr(),
                        n,
                        orders.as_ptr(),
                        out.as_mut_ptr(),
                    )) == OK
                    {
                        assert!(out.iter().all(|x| x.is_finite()), "{out:?}");
                    }
                }
                19 => {
                    let categories = [
                        c"logEvents".as_ptr(),
                        c"logAll".as_ptr(),
                        c"nope".as_ptr(),
                        null(),
                    ];
                    let n = b.u8() as usize % 3;
                    let list: Vec<fmi2String> = (0..n).map(|_| b.pick(&categories)).collect();
                    check(fmi2SetDebugLogging(
                        c,
                        b.u8() as i32 % 2,
                        n,
                        maybe_null(&mut b, &list),
                    ));
                }
                20 => {
                    check(fmi2CancelStep(c));
                    check(fmi2SetTime(c, real(&mut b)));
                    check(fmi2EnterEventMode(c));
                }
                22 => {
                    // Model Exchange: the time, forward from where the
                    // master believes the instance is (or anywhere).
                    let slot_time = slots[i].as_ref().map_or(0.0, |s| s.time);
                    let t = slot_time + time_step(&mut b);
                    if trace() {
                        eprintln!("  fmi2SetTime({t:e})");
                    }
                    if check(fmi2SetTime(c, t)) == OK
                        && let Some(slot) = slots[i].as_mut()
                    {
                        slot.time = t;
                    }
                }
                23 => {
                    // Continuous states: the current ones perturbed, or
                    // fuzzed values; a count near the model's, sometimes
                    // NULL.
                    let mut x = vec![0.0; nx + 4];
                    if check(fmi2GetContinuousStates(c, x.as_mut_ptr(), nx)) != OK {
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
                        eprintln!("  fmi2SetContinuousStates({:?}, {n})", &x[..n]);
                    }
                    check(fmi2SetContinuousStates(c, maybe_null(&mut b, &x), n));
                }
                24 => {
                    let n = count_near(&mut b, nx);
                    let mut dx = vec![f64::NAN; n.max(1)];
                    if check(fmi2GetDerivatives(c, maybe_null_mut(&mut b, &mut dx), n)) == OK {
                        assert_eq!(n, nx);
                        assert!(
                            dx[..n].iter().all(|v| v.is_finite()),
                            "fmi2GetDerivatives gave {dx:?}"
                        );
                    }
                }
                25 => {
                    let n = count_near(&mut b, nz);
                    let mut z = vec![f64::NAN; n.max(1)];
                    if check(fmi2GetEventIndicators(c, maybe_null_mut(&mut b, &mut z), n)) == OK {
                        assert_eq!(n, nz);
                        assert!(
                            z[..n].iter().all(|v| v.is_finite()),
                            "fmi2GetEventIndicators gave {z:?}"
                        );
                    }
                }
                26 => {
                    let (mut enter, mut terminate) = (7, 7);
                    let nulls = b.u8();
                    let e = if nulls % 8 == 1 {
                        null_mut()
                    } else {
                        &mut enter as *mut _
                    };
                    let t = if nulls % 8 == 2 {
                        null_mut()
                    } else {
                        &mut terminate as *mut _
                    };
                    if check(fmi2CompletedIntegratorStep(
                        c,
                        (nulls >> 4) as i32 % 2,
                        e,
                        t,
                    )) == OK
                    {
                        assert_eq!(enter, 0, "enterEventMode: the model has state events only");
                        flag(terminate);
                    }
                }
                27 => {
                    // Event Mode: enter it, event updates, back to
                    // Continuous-Time Mode, in an order the input picks.
                    for _ in 0..1 + b.u8() % 4 {
                        match b.u8() % 3 {
                            0 => {
                                check(fmi2EnterEventMode(c));
                            }
                            1 => {
                                let mut info = fmi2EventInfo {
                                    newDiscreteStatesNeeded: 7,
                                    terminateSimulation: 7,
                                    nominalsOfContinuousStatesChanged: 7,
                                    valuesOfContinuousStatesChanged: 7,
                                    nextEventTimeDefined: 7,
                                    nextEventTime: f64::NAN,
                                };
                                let p = if b.u8().is_multiple_of(16) {
                                    null_mut()
                                } else {
                                    &mut info as *mut _
                                };
                                if check(fmi2NewDiscreteStates(c, p)) == OK {
                                    assert_eq!(info.newDiscreteStatesNeeded, 0);
                                    flag(info.terminateSimulation);
                                    flag(info.nominalsOfContinuousStatesChanged);
                                    flag(info.valuesOfContinuousStatesChanged);
                                    flag(info.nextEventTimeDefined);
                                    assert!(info.nextEventTime.is_finite());
                                }
                            }
                            _ => {
                                check(fmi2EnterContinuousTimeMode(c));
                            }
                        }
                    }
                }
                28 => {
                    let n = count_near(&mut b, nx);
                    let mut x = vec![f64::NAN; n.max(1)];
                    if check(fmi2GetContinuousStates(
                        c,
                        maybe_null_mut(&mut b, &mut x),
                        n,
                    )) == OK
                    {
                        assert!(x[..n].iter().all(|v| v.is_finite()), "states {x:?}");
                    }
                    let n = count_near(&mut b, nx);
                    let mut nominal = vec![f64::NAN; n.max(1)];
                    if check(fmi2GetNominalsOfContinuousStates(
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
                29 => {
                    // Explicit Euler steps of the master's integrator, as a
                    // master makes them (the way deep into a run).
                    let h = b.pick(&[1e-5, 1e-4, 1e-4, 1e-3, 0.01]);
                    for _ in 0..1 + b.u8() % 8 {
                        let mut x = vec![0.0; nx];
                        let mut dx = vec![0.0; nx];
                        if check(fmi2GetContinuousStates(c, x.as_mut_ptr(), nx)) != OK
                            || check(fmi2GetDerivatives(c, dx.as_mut_ptr(), nx)) != OK
                        {
                            break;
                        }
                        let t = slots[i].as_ref().map_or(0.0, |s| s.time) + h;
                        if check(fmi2SetTime(c, t)) != OK {
                            break;
                        }
                        if let Some(slot) = slots[i].as_mut() {
                            slot.time = t;
                        }
                        for (v, d) in x.iter_mut().zip(dx) {
                            *v += h * d;
                        }
                        let (mut enter, mut terminate) = (7, 7);
                        if check(fmi2SetContinuousStates(c, x.as_ptr(), nx)) != OK
                            || check(fmi2CompletedIntegratorStep(
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
                    assert_outputs_of_finite(c, model);
                }
                _ => {
                    // Tunable and input values while simulating.
                    let vr = b.pick(&settable(model));
                    let value = real(&mut b);
                    if trace() {
                        eprintln!("  fmi2SetReal([{vr}], [{value:e}])");
                    }
                    check(fmi2SetReal(c, &vr, 1, &value));
                }
            }
        }
    }
    for slot in slots.iter_mut() {
        if let Some(s) = slot.take() {
            // SAFETY: a live instance.
            unsafe { fmi2FreeInstance(s.c) };
        }
    }
});
