//! What the C entry points of every FMI version do around an instance,
//! written once: find the instance behind a handle, run the call under the
//! front-end's state table with every panic caught ([`with_instance`],
//! [`call`]), and the bodies of the functions that are the same in every
//! version: [`free_instance`], [`set_debug_logging`], [`log_refusal`] and
//! the six FMU-state functions ([`fmu_state`]).
//!
//! A front-end's `extern "C"` functions keep their C signatures, convert
//! their statuses and types, and hold what is particular to their FMI
//! version; the instance they pass implements [`FrontEnd`]. The pointer
//! arguments are checked by [`crate::pointers`] (NULL, alignment, length,
//! the handle's tag); what cannot be checked is the `# Safety` contract of
//! each function, which the front-end's C calling convention guarantees.
// Calls the pointer conversions of `crate::pointers` (the crate denies
// `unsafe` elsewhere).
#![allow(unsafe_code)]

use crate::Slave;
use crate::error::{FmiError, Status};
use crate::pointers::{self, copy_str, input, panic_text};
use std::ffi::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// An FMI version's instance around a [`Slave`], as the C glue sees it:
/// its state table, its slave, and what it holds beyond the slave.
pub trait FrontEnd: Sized {
    /// The functions of the front-end's state table.
    type Function: Copy;

    /// The C name of `function` (`fmi2DoStep`, ...), which prefixes the
    /// messages of a failed call.
    fn name(function: Self::Function) -> &'static str;

    /// The front-end's state table: an error "not allowed in state Y"
    /// when `function` may not be called in the current state.
    fn check_state(&self, function: Self::Function) -> Result<(), FmiError>;

    /// The slave. (Each front-end's instance holds its slave beside what
    /// its version adds, so these two accessors are all the glue asks of
    /// its layout; what instantiation checks alike is
    /// [`crate::instantiation`].)
    fn slave(&self) -> &Slave;

    /// The slave, to call it.
    fn slave_mut(&mut self) -> &mut Slave;

    /// After a panic: drops what the front-end holds of the call in
    /// progress (nothing by default; the slave goes to `Fatal` anyway).
    fn after_panic(&mut self) {}

    /// After [`fmu_state::set`] restored an FMU state into the slave:
    /// brings what the front-end holds beyond the slave in line (nothing by
    /// default).
    fn fmu_state_restored(&mut self) {}

    /// Runs `op` as `function`: refuses it (`Error`, logged "X: not allowed
    /// in state Y") when the state table forbids it in the current state,
    /// and logs any failure with the function name. A refused call changes
    /// nothing; `Fatal` moves the slave to `Fatal`.
    fn run<T>(
        &mut self,
        function: Self::Function,
        op: impl FnOnce(&mut Self) -> Result<T, FmiError>,
    ) -> Result<T, Status> {
        let result = self.check_state(function).and_then(|()| op(self));
        result.map_err(|e| self.slave_mut().report_failure(Self::name(function), &e))
    }

    /// After a panic inside `function` (caught by [`with_instance`]): the
    /// instance may be inconsistent, so it goes to `Fatal`.
    fn on_panic(&mut self, function: Self::Function, message: &str) {
        self.after_panic();
        self.slave_mut().report_panic(Self::name(function), message);
    }
}

/// Runs `op` on the instance behind the handle `c` (tagged `magic`, holding
/// an `H` that holds the instance) as `function` ([`FrontEnd::run`]: state
/// table, logging), with panics caught: a panic makes the instance fatal
/// ([`FrontEnd::on_panic`]) and gives `Fatal`. A `c` that is not a live
/// handle gives `Error`.
///
/// # Safety
/// As [`pointers::handle`]: `c` is NULL or a pointer returned by
/// [`pointers::into_raw`] with the same `H`, and the master does not use
/// the instance from two threads at once.
pub unsafe fn with_instance<H: AsMut<I>, I: FrontEnd, T>(
    c: *mut c_void,
    magic: u64,
    function: I::Function,
    op: impl FnOnce(&mut I) -> Result<T, FmiError>,
) -> Result<T, Status> {
    // SAFETY: forwarded contract.
    let Some(h) = (unsafe { pointers::handle::<H>(c, magic) }) else {
        return Err(Status::Error);
    };
    let instance = h.instance.as_mut();
    match catch_unwind(AssertUnwindSafe(|| instance.run(function, op))) {
        Ok(result) => result,
        Err(payload) => {
            let text = panic_text(&*payload);
            let _ = catch_unwind(AssertUnwindSafe(|| instance.on_panic(function, &text)));
            Err(Status::Fatal)
        }
    }
}

/// [`with_instance`] for the functions that return a status.
///
/// # Safety
/// As [`with_instance`].
pub unsafe fn call<H: AsMut<I>, I: FrontEnd>(
    c: *mut c_void,
    magic: u64,
    function: I::Function,
    op: impl FnOnce(&mut I) -> Result<Status, FmiError>,
) -> Status {
    // SAFETY: forwarded contract.
    match unsafe { with_instance::<H, I, Status>(c, magic, function, op) } {
        Ok(s) | Err(s) => s,
    }
}

/// `FreeInstance` (the front-end's `function`): frees the handle `c` when
/// the state table allows it; a NULL or foreign `c` is ignored.
///
/// # Safety
/// As [`with_instance`]; the master does not use `c` afterwards.
pub unsafe fn free_instance<H: AsMut<I>, I: FrontEnd>(
    c: *mut c_void,
    magic: u64,
    function: I::Function,
) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: forwarded contract.
        if let Some(h) = unsafe { pointers::handle::<H>(c, magic) }
            && h.instance.as_mut().run(function, |_| Ok(())).is_ok()
        {
            // SAFETY: a live handle of this FMU; the master passes it no
            // more (forwarded contract).
            unsafe { pointers::free::<H>(c, magic) };
        }
    }));
}

/// Logs `message()` as an `Error` of the instance behind `c`, if `c` is a
/// live handle, and returns `Error`: for the functions this FMU does not
/// offer.
///
/// # Safety
/// As [`with_instance`].
pub unsafe fn log_refusal<H: AsMut<I>, I: FrontEnd>(
    c: *mut c_void,
    magic: u64,
    message: impl FnOnce() -> String,
) -> Status {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: forwarded contract.
        if let Some(h) = unsafe { pointers::handle::<H>(c, magic) } {
            let slave = h.instance.as_mut().slave();
            slave.logger().log(Status::Error, &message());
        }
    }));
    Status::Error
}

/// `SetDebugLogging`: the `n` category names at `categories` (none: all)
/// switched on or off. An unknown or NULL name refuses the whole call.
///
/// # Safety
/// `categories` is NULL or points to `n` pointers, each NULL or a
/// NUL-terminated string.
pub unsafe fn set_debug_logging(
    instance: &mut impl FrontEnd,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> Result<Status, FmiError> {
    // SAFETY: forwarded contract: `categories` holds `n` strings.
    let pointers = unsafe { input(categories, n, "categories") }?;
    let mut names = Vec::with_capacity(pointers.len());
    for (k, &p) in pointers.iter().enumerate() {
        // SAFETY: forwarded contract: each entry is NULL or a
        // NUL-terminated string.
        let name = unsafe { copy_str(p) }
            .ok_or_else(|| FmiError::error(format!("categories[{k}] is NULL")))?;
        names.push(name);
    }
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    instance.slave_mut().logger_mut().set_categories(on, &names)
}

/// The six FMU-state functions. An FMU-state value (`fmi2FMUstate`,
/// `fmi3FMUState`) is the address of a state the slave owns (its handle),
/// or NULL; the messages spell it as the slave's dialect does.
pub mod fmu_state {
    use super::FrontEnd;
    use crate::Slave;
    use crate::error::{FmiError, Status};
    use crate::pointers::{input, out_value, output};
    use std::ffi::c_void;

    /// The handle in an FMU-state value, `None` for NULL.
    fn handle_of(state: *mut c_void) -> Option<usize> {
        (!state.is_null()).then_some(state as usize)
    }

    /// The FMU-state value of a handle.
    fn value_of(handle: usize) -> *mut c_void {
        handle as *mut c_void
    }

    /// The handle in the FMU-state argument, refused when NULL.
    fn required(slave: &Slave, state: *mut c_void) -> Result<usize, FmiError> {
        handle_of(state)
            .ok_or_else(|| FmiError::error(format!("{} is NULL", slave.dialect().fmu_state)))
    }

    /// `GetFMUstate`: a copy of the slave's state into `*state` (a state of
    /// this instance, overwritten, or NULL for a new one).
    ///
    /// # Safety
    /// `state` is NULL (refused) or points to an FMU-state value.
    pub unsafe fn get(
        instance: &mut impl FrontEnd,
        state: *mut *mut c_void,
    ) -> Result<Status, FmiError> {
        let slave = instance.slave_mut();
        // SAFETY: forwarded contract: `state` points to an FMU-state value.
        let slot = unsafe { out_value(state, slave.dialect().fmu_state) }?;
        *slot = value_of(slave.get_fmu_state(handle_of(*slot))?);
        Ok(Status::Ok)
    }

    /// `SetFMUstate`: restores `state`, a state of this instance, then
    /// [`FrontEnd::fmu_state_restored`].
    pub fn set(instance: &mut impl FrontEnd, state: *mut c_void) -> Result<Status, FmiError> {
        let handle = required(instance.slave(), state)?;
        let status = instance.slave_mut().set_fmu_state(handle)?;
        instance.fmu_state_restored();
        Ok(status)
    }

    /// `FreeFMUstate`: frees `*state` (NULL: nothing to do) and sets it to
    /// NULL.
    ///
    /// # Safety
    /// `state` is NULL or points to an FMU-state value.
    pub unsafe fn free(
        instance: &mut impl FrontEnd,
        state: *mut *mut c_void,
    ) -> Result<Status, FmiError> {
        if state.is_null() {
            return Ok(Status::Ok);
        }
        let slave = instance.slave_mut();
        // SAFETY: forwarded contract: `state` points to an FMU-state value.
        let slot = unsafe { out_value(state, slave.dialect().fmu_state) }?;
        let Some(handle) = handle_of(*slot) else {
            return Ok(Status::Ok);
        };
        slave.free_fmu_state(handle)?;
        *slot = std::ptr::null_mut();
        Ok(Status::Ok)
    }

    /// `SerializedFMUstateSize`: the length of `state`'s bytes into
    /// `*size`.
    ///
    /// # Safety
    /// `size` is NULL (refused) or points to a `size_t`.
    pub unsafe fn serialized_size(
        instance: &mut impl FrontEnd,
        state: *mut c_void,
        size: *mut usize,
    ) -> Result<Status, FmiError> {
        let slave = instance.slave();
        // SAFETY: forwarded contract: `size` points to a size_t.
        let size = unsafe { out_value(size, "size") }?;
        *size = slave.serialize_fmu_state(required(slave, state)?)?.len();
        Ok(Status::Ok)
    }

    /// `SerializeFMUstate`: `state`'s bytes into the `size` bytes at
    /// `buffer` (refused when they are fewer than the state needs).
    ///
    /// # Safety
    /// `buffer` is NULL (refused) or holds `size` writable bytes.
    pub unsafe fn serialize(
        instance: &mut impl FrontEnd,
        state: *mut c_void,
        buffer: *mut u8,
        size: usize,
    ) -> Result<Status, FmiError> {
        let slave = instance.slave();
        let bytes = slave.serialize_fmu_state(required(slave, state)?)?;
        if size < bytes.len() {
            return Err(FmiError::error(format!(
                "the buffer has {size} bytes, the state needs {} ({})",
                bytes.len(),
                format_args!(
                    "{}Serialized{}Size",
                    slave.dialect().prefix,
                    slave.dialect().fmu_state
                )
            )));
        }
        // SAFETY: forwarded contract: `buffer` holds `size` writable bytes,
        // at least the state's.
        let out = unsafe { output(buffer, bytes.len(), "serializedState") }?;
        out.copy_from_slice(&bytes);
        Ok(Status::Ok)
    }

    /// `DeSerializeFMUstate`: the `size` bytes at `bytes` into `*state` (a
    /// state of this instance, overwritten, or NULL for a new one).
    ///
    /// # Safety
    /// `bytes` is NULL (refused unless `size` is 0) or holds `size`
    /// readable bytes; `state` is NULL (refused) or points to an FMU-state
    /// value.
    pub unsafe fn deserialize(
        instance: &mut impl FrontEnd,
        bytes: *const u8,
        size: usize,
        state: *mut *mut c_void,
    ) -> Result<Status, FmiError> {
        let slave = instance.slave_mut();
        // SAFETY: forwarded contract: `size` readable bytes and a state
        // value.
        let (bytes, slot) = unsafe {
            (
                input(bytes, size, "serializedState")?,
                out_value(state, slave.dialect().fmu_state)?,
            )
        };
        *slot = value_of(slave.deserialize_fmu_state(bytes, handle_of(*slot))?);
        Ok(Status::Ok)
    }
}

#[cfg(test)]
mod tests;
