//! Fuzzes `fmi2DeSerializeFMUstate`.
//!
//! The first byte chooses how the rest is used: as a whole serialized state
//! (envelope included), or (most of the time) as a payload put behind a
//! valid header with the right CRC, so that the fuzzer reaches the checks of
//! the content; (bit 0x20) whether a Co-Simulation or a Model Exchange
//! instance reads it; and (bits 0xc0) the model of the instance and of the
//! header: the quarter car, the corner or the chassis (these two
//! Co-Simulation only). An accepted state must serialize again to bytes that
//! are accepted and reproduce themselves; it is then set and stepped
//! (fmi2DoStep, or explicit Euler steps of a Model Exchange master, after
//! whatever event handling its state allows), and every output must stay
//! finite. No call may return fmi2Fatal (a panic).
#![no_main]

#[path = "common.rs"]
mod common;

use common::*;
use libfuzzer_sys::fuzz_target;
use tdvass_fmi2::Model;
use tdvass_fmi2::snapshot;

/// `payload` behind a valid header of the FMU of `model`.
fn envelope(payload: &[u8], model: Model) -> Vec<u8> {
    let guid = tdvass_fmi2::guid(model);
    let mut out = Vec::with_capacity(payload.len() + 64);
    out.extend_from_slice(snapshot::MAGIC);
    out.extend_from_slice(&snapshot::FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(guid.len() as u32).to_le_bytes());
    out.extend_from_slice(guid.as_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&snapshot::crc32(payload).to_le_bytes());
    out.extend_from_slice(payload);
    out
}

fn deserialize(c: fmi2Component, bytes: &[u8]) -> (fmi2Status, fmi2FMUstate) {
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    // SAFETY: `bytes.len()` readable bytes and a state slot.
    let s = unsafe { fmi2DeSerializeFMUstate(c, bytes.as_ptr().cast(), bytes.len(), &mut state) };
    (check(s), state)
}

fn serialize(c: fmi2Component, state: fmi2FMUstate) -> Vec<u8> {
    let mut size = 0usize;
    // SAFETY: a state of `c` and a size slot; then a buffer of that size.
    unsafe {
        assert_eq!(check(fmi2SerializedFMUstateSize(c, state, &mut size)), OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(
            check(fmi2SerializeFMUstate(
                c,
                state,
                bytes.as_mut_ptr().cast(),
                size
            )),
            OK
        );
        bytes
    }
}

/// Model Exchange: continuous states.
const NX: usize = 20;

/// A few explicit Euler steps of h from `t`, as a Model Exchange master
/// makes them, with event handling before them (every call may be refused
/// by the state the instance is in, none may panic). A successful getter
/// gives finite values.
fn model_exchange_steps(c: fmi2Component, mut t: f64, steps: u8) {
    // SAFETY (every call): a live instance, arrays of NX values.
    unsafe {
        let mut info = std::mem::MaybeUninit::<fmi2EventInfo>::zeroed().assume_init();
        check(fmi2NewDiscreteStates(c, &mut info));
        check(fmi2EnterContinuousTimeMode(c));
        let h = [1e-5, 1e-4, 1e-3, 0.01][steps as usize % 4];
        for _ in 0..steps % 8 {
            let (mut x, mut dx) = ([0.0; NX], [0.0; NX]);
            if check(fmi2GetContinuousStates(c, x.as_mut_ptr(), NX)) != OK
                || check(fmi2GetDerivatives(c, dx.as_mut_ptr(), NX)) != OK
            {
                break;
            }
            assert!(x.iter().chain(&dx).all(|v| v.is_finite()), "{x:?} {dx:?}");
            t += h;
            for (v, d) in x.iter_mut().zip(dx) {
                *v += h * d;
            }
            let (mut enter, mut terminate) = (7, 7);
            if check(fmi2SetTime(c, t)) != OK
                || check(fmi2SetContinuousStates(c, x.as_ptr(), NX)) != OK
                || check(fmi2CompletedIntegratorStep(
                    c,
                    1,
                    &mut enter,
                    &mut terminate,
                )) != OK
            {
                break;
            }
            assert!(enter == 0 && terminate <= 1, "{enter} {terminate}");
            assert_outputs_finite(c);
        }
        // What a Co-Simulation master would do next: refused, not a panic.
        check(fmi2DoStep(c, t, 1e-3, 0));
    }
}

fuzz_target!(|data: &[u8]| {
    let callbacks = callbacks();
    let mut input = Bytes::new(data);
    let mode = input.u8();
    let model = [
        Model::QuarterCar,
        Model::Corner,
        Model::Chassis,
        Model::QuarterCar,
    ][(mode >> 6) as usize];
    let c = if mode & 0x20 != 0 && model == Model::QuarterCar {
        instantiate_model_exchange(&callbacks, false)
    } else {
        instantiate_model(&callbacks, false, model)
    };
    assert!(!c.is_null());
    let steps = input.u8();
    let bytes = if mode.is_multiple_of(4) {
        input.rest().to_vec()
    } else {
        envelope(input.rest(), model)
    };
    let (status, state) = deserialize(c, &bytes);
    if status == OK {
        assert!(!state.is_null());
        let first = serialize(c, state);
        let (again_status, again) = deserialize(c, &first);
        assert_eq!(again_status, OK, "the FMU refuses its own serialization");
        assert_eq!(serialize(c, again), first, "serialization is not stable");
        // SAFETY: states of this instance.
        unsafe {
            assert_eq!(check(fmi2SetFMUstate(c, state)), OK);
        }
        let restored = snapshot::deserialize(&bytes, &tdvass_fmi2::guid(model), model)
            .expect("accepted above");
        let stepper_time = restored
            .engine
            .simulator()
            .map(|sim| sim.time())
            .or(restored.engine.chassis().map(|chassis| chassis.time()));
        if let Some(exchange) = restored.engine.exchange() {
            assert_outputs_finite(c);
            model_exchange_steps(c, exchange.time(), steps);
        } else if let Some(mut t) = stepper_time {
            assert_outputs_of_finite(c, model);
            // A few short steps from where the state stands.
            for k in 0..steps % 4 {
                let h = [1e-4, 1e-3, 0.01, 0.05][(steps as usize >> (2 * k)) % 4];
                // SAFETY: a live instance.
                let s = check(unsafe { fmi2DoStep(c, t, h, 0) });
                if s != OK {
                    break;
                }
                t += h;
                assert_outputs_of_finite(c, model);
            }
        }
    }
    // SAFETY: the live instance; its states go with it.
    unsafe { fmi2FreeInstance(c) };
});
