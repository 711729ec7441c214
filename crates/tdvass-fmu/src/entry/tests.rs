//! The C glue driven with raw pointers as a front-end's C functions drive
//! it, around a made-up front-end whose state table refuses what it is
//! told to.

use super::*;
use crate::Phase;
use crate::slave::tests::{Log, initialized, new_slave};

/// The made-up front-end's functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Call {
    Step,
    State,
    Free,
}

/// A front-end around a slave: its state table refuses the functions in
/// `refused`, and every function but `Free` in `Fatal`.
struct Probe {
    slave: Slave,
    refused: Vec<Call>,
    /// How often the hooks ran.
    panics: usize,
    restored: usize,
}

impl FrontEnd for Probe {
    type Function = Call;

    fn name(function: Call) -> &'static str {
        match function {
            Call::Step => "testStep",
            Call::State => "testState",
            Call::Free => "testFree",
        }
    }

    fn check_state(&self, function: Call) -> Result<(), FmiError> {
        let fatal = self.slave.phase() == Phase::Fatal && function != Call::Free;
        if fatal || self.refused.contains(&function) {
            Err(FmiError::error(format!(
                "not allowed in state {}",
                self.slave.phase().name()
            )))
        } else {
            Ok(())
        }
    }

    fn slave(&self) -> &Slave {
        &self.slave
    }

    fn slave_mut(&mut self) -> &mut Slave {
        &mut self.slave
    }

    fn after_panic(&mut self) {
        self.panics += 1;
    }

    fn fmu_state_restored(&mut self) {
        self.restored += 1;
    }
}

impl AsMut<Probe> for Probe {
    fn as_mut(&mut self) -> &mut Probe {
        self
    }
}

const MAGIC: u64 = 0x5445_5354_5052_4F42; // "TESTPROB"

fn probe(slave: Slave) -> Probe {
    Probe {
        slave,
        refused: Vec::new(),
        panics: 0,
        restored: 0,
    }
}

/// A live handle of a probe around an initialized slave, and its log.
fn handle() -> (*mut c_void, Log) {
    let (slave, log) = initialized();
    (pointers::into_raw(MAGIC, probe(slave)), log)
}

/// The probe behind a live handle.
fn peek<'a>(c: *mut c_void) -> &'a mut Probe {
    // SAFETY: the tests pass live handles made by `handle`, one thread.
    &mut unsafe { pointers::handle::<Probe>(c, MAGIC) }
        .unwrap()
        .instance
}

fn free(c: *mut c_void) {
    // SAFETY: a live handle, not used afterwards.
    unsafe { free_instance::<Probe, Probe>(c, MAGIC, Call::Free) };
}

fn last(log: &Log) -> (Status, String, String) {
    log.borrow().last().cloned().unwrap()
}

#[test]
fn run_refuses_what_the_state_table_forbids_and_logs_failures() {
    let (slave, log) = new_slave(false);
    let mut p = probe(slave);
    p.refused.push(Call::Step);
    let mut ran = false;
    let refused = p.run(Call::Step, |_| {
        ran = true;
        Ok(())
    });
    assert_eq!(refused, Err(Status::Error));
    assert!(!ran, "a refused call runs nothing");
    assert_eq!(
        last(&log),
        (
            Status::Error,
            "logStatusError".into(),
            "testStep: not allowed in state instantiated".into()
        )
    );
    assert_eq!(p.run(Call::State, |p| Ok(p.slave.time())), Ok(0.0));
    // A failure is logged under the function's name with its status;
    // only Fatal changes the phase.
    let discard = p.run(Call::State, |_| -> Result<(), _> {
        Err(FmiError::discard("not now"))
    });
    assert_eq!(discard, Err(Status::Discard));
    assert_eq!(last(&log).2, "testState: not now");
    assert_eq!(p.slave.phase(), Phase::Instantiated);
    let fatal = p.run(Call::State, |_| -> Result<(), _> {
        Err(FmiError {
            status: Status::Fatal,
            message: "broken".into(),
        })
    });
    assert_eq!(fatal, Err(Status::Fatal));
    assert_eq!(
        last(&log),
        (
            Status::Fatal,
            "logStatusFatal".into(),
            "testState: broken".into()
        )
    );
    assert_eq!(p.slave.phase(), Phase::Fatal);
    assert_eq!(p.panics, 0);
}

#[test]
fn panics_are_caught_and_make_the_instance_fatal() {
    let (c, log) = handle();
    // SAFETY: a live handle.
    let s = unsafe { call::<Probe, Probe>(c, MAGIC, Call::Step, |_| panic!("deliberate")) };
    assert_eq!(s, Status::Fatal);
    let (status, category, message) = last(&log);
    assert_eq!(
        (status, category.as_str()),
        (Status::Fatal, "logStatusFatal")
    );
    assert_eq!(
        message,
        "testStep: internal error (panic: deliberate); the instance is unusable, free it"
    );
    assert_eq!(peek(c).slave.phase(), Phase::Fatal);
    assert_eq!(peek(c).panics, 1);
    // SAFETY: a live handle.
    let s = unsafe { call::<Probe, Probe>(c, MAGIC, Call::State, |_| Ok(Status::Ok)) };
    assert_eq!(s, Status::Error, "refused in Fatal");
    free(c);
}

#[test]
fn null_foreign_and_unaligned_handles_are_refused() {
    let mut not_a_handle = [0u64; 8];
    let foreign = not_a_handle.as_mut_ptr() as *mut c_void;
    let unaligned = not_a_handle.as_mut_ptr().cast::<u8>().wrapping_add(1) as *mut c_void;
    for c in [std::ptr::null_mut(), foreign, unaligned] {
        let mut ran = false;
        // SAFETY: NULL, or readable memory the size of a handle tag
        // (refused by its tag or alignment before anything else is read).
        let s = unsafe {
            call::<Probe, Probe>(c, MAGIC, Call::State, |_| {
                ran = true;
                Ok(Status::Ok)
            })
        };
        assert_eq!(s, Status::Error);
        assert!(!ran);
        let mut asked = false;
        // SAFETY: as above; nothing is logged or freed.
        unsafe {
            let message = || {
                asked = true;
                String::new()
            };
            assert_eq!(
                log_refusal::<Probe, Probe>(c, MAGIC, message),
                Status::Error
            );
            free_instance::<Probe, Probe>(c, MAGIC, Call::Free);
        }
        assert!(!asked);
    }
    // A live handle of another tag is foreign too.
    let (c, _) = handle();
    // SAFETY: a live handle (of the tag MAGIC).
    let other = unsafe { with_instance::<Probe, Probe, ()>(c, MAGIC ^ 1, Call::State, |_| Ok(())) };
    assert_eq!(other, Err(Status::Error));
    free(c);
}

#[test]
fn free_instance_asks_the_state_table_and_refusals_are_logged() {
    let (c, log) = handle();
    peek(c).refused.push(Call::Free);
    free(c);
    assert_eq!(last(&log).2, "testFree: not allowed in state stepComplete");
    // Still alive: a function that does not apply is refused and logged.
    // SAFETY: a live handle.
    let s = unsafe { log_refusal::<Probe, Probe>(c, MAGIC, || "testNothing: no".into()) };
    assert_eq!(s, Status::Error);
    assert_eq!(
        last(&log),
        (
            Status::Error,
            "logStatusError".into(),
            "testNothing: no".into()
        )
    );
    peek(c).refused.clear();
    free(c);
}

#[test]
fn debug_logging_reads_the_category_names() {
    let (slave, log) = new_slave(false);
    let mut p = probe(slave);
    let names = [c"logEvents".as_ptr(), std::ptr::null()];
    // SAFETY: an array of two pointers, one NULL.
    let e = unsafe { set_debug_logging(&mut p, true, 2, names.as_ptr()) }.unwrap_err();
    assert_eq!(e.message, "categories[1] is NULL");
    // SAFETY: NULL with a length: refused before reading.
    let e = unsafe { set_debug_logging(&mut p, true, 1, std::ptr::null()) }.unwrap_err();
    assert_eq!(e.message, "categories is NULL while its length is 1");
    let unknown = [c"logNothing".as_ptr()];
    // SAFETY: an array of one string.
    let e = unsafe { set_debug_logging(&mut p, true, 1, unknown.as_ptr()) }.unwrap_err();
    assert!(e.message.contains("logNothing"), "{}", e.message);
    p.slave.reset().unwrap();
    assert!(log.borrow().is_empty(), "events still off");
    // SAFETY: an array of one string.
    unsafe { set_debug_logging(&mut p, true, 1, names.as_ptr()) }.unwrap();
    p.slave.reset().unwrap();
    assert_eq!(log.borrow().len(), 1);
    // None: all categories.
    // SAFETY: NULL with length 0 is an empty array.
    unsafe { set_debug_logging(&mut p, false, 0, std::ptr::null()) }.unwrap();
    p.slave.reset().unwrap();
    assert_eq!(log.borrow().len(), 1);
}

#[test]
fn fmu_state_values_through_pointers() {
    let (slave, _) = initialized();
    let mut p = probe(slave);
    let null: *mut c_void = std::ptr::null_mut();
    // SAFETY: NULL pointers, refused before reading.
    unsafe {
        let e = fmu_state::get(&mut p, null.cast()).unwrap_err();
        assert_eq!(e.message, "FMUstate is NULL while its length is 1");
        let e = fmu_state::serialized_size(&mut p, null, std::ptr::null_mut()).unwrap_err();
        assert_eq!(e.message, "size is NULL while its length is 1");
    }
    let e = fmu_state::set(&mut p, null).unwrap_err();
    assert_eq!(e.message, "FMUstate is NULL");
    // A NULL value asks for a new state; a state's value re-uses it.
    let mut state: *mut c_void = null;
    // SAFETY: a pointer to a local FMU-state value.
    unsafe { fmu_state::get(&mut p, &mut state) }.unwrap();
    assert!(!state.is_null());
    let first = state;
    // SAFETY: as above.
    unsafe { fmu_state::get(&mut p, &mut state) }.unwrap();
    assert_eq!(state, first);
    assert_eq!(p.slave.fmu_state_count(), 1);
    // Set restores it and tells the front-end.
    p.slave.do_step(0.0, 0.1).unwrap();
    assert_eq!(fmu_state::set(&mut p, state), Ok(Status::Ok));
    assert_eq!((p.slave.time(), p.restored), (0.0, 1));
    // Bytes: the size, a buffer too small, then the state's bytes.
    let mut size = 0;
    // SAFETY: a pointer to a local size_t.
    unsafe { fmu_state::serialized_size(&mut p, state, &mut size) }.unwrap();
    let expected = p.slave.serialize_fmu_state(state as usize).unwrap();
    assert_eq!(size, expected.len());
    let mut buffer = vec![0u8; size];
    // SAFETY: a buffer of `size - 1` writable bytes (nothing is written).
    let e =
        unsafe { fmu_state::serialize(&mut p, state, buffer.as_mut_ptr(), size - 1) }.unwrap_err();
    assert_eq!(
        e.message,
        format!(
            "the buffer has {} bytes, the state needs {size} (testSerializedFMUstateSize)",
            size - 1
        )
    );
    // SAFETY: a buffer of `size` writable bytes.
    unsafe { fmu_state::serialize(&mut p, state, buffer.as_mut_ptr(), size) }.unwrap();
    assert_eq!(buffer, expected);
    // Deserialized into a new state, or over an existing one.
    let mut copy: *mut c_void = null;
    // SAFETY: `size` readable bytes and a local FMU-state value.
    unsafe { fmu_state::deserialize(&mut p, buffer.as_ptr(), size, &mut copy) }.unwrap();
    assert!(!copy.is_null() && copy != state);
    let over = copy;
    // SAFETY: as above.
    unsafe { fmu_state::deserialize(&mut p, buffer.as_ptr(), size, &mut copy) }.unwrap();
    assert_eq!(copy, over);
    // SAFETY: NULL bytes with a length, refused before reading.
    let e = unsafe { fmu_state::deserialize(&mut p, std::ptr::null(), 4, &mut copy) }.unwrap_err();
    assert_eq!(e.message, "serializedState is NULL while its length is 4");
    // Free: NULL pointer and NULL value are no-ops; a freed value is
    // cleared, and freeing it again is refused.
    // SAFETY: NULL, then pointers to local FMU-state values.
    unsafe {
        assert_eq!(fmu_state::free(&mut p, null.cast()), Ok(Status::Ok));
        let mut none: *mut c_void = null;
        assert_eq!(fmu_state::free(&mut p, &mut none), Ok(Status::Ok));
        fmu_state::free(&mut p, &mut copy).unwrap();
        assert!(copy.is_null());
        let mut again = over;
        let e = fmu_state::free(&mut p, &mut again).unwrap_err();
        assert!(e.message.contains("was already freed"), "{}", e.message);
        assert_eq!(again, over, "a refused free leaves the value");
        fmu_state::free(&mut p, &mut state).unwrap();
    }
    assert_eq!(p.slave.fmu_state_count(), 0);
}
