//! The pointers of the C interfaces of every FMI version, written once:
//! instance handles, array and string arguments, and panic messages. Each
//! function checks what can be checked (NULL, alignment, length, the
//! handle's tag) and states the rest of its contract in its `# Safety`
//! section. [`crate::entry`] and the `extern "C"` layers of the front-ends
//! call them for their pointer arguments; beyond these calls and those of
//! `entry`, the front-ends' `unsafe` calls the master's callbacks and reads
//! or writes through a few pointers after the same checks (NULL,
//! alignment).
// Converts raw pointers (with `crate::entry`, the only `unsafe` of this
// crate, which denies it elsewhere).
#![allow(unsafe_code)]

use crate::error::FmiError;
use std::ffi::{CStr, CString, c_char, c_void};

/// What an instance pointer points to: a tag (checked on every call,
/// cleared on free, so a pointer that is not a live instance of this FMU is
/// usually recognised) and the instance. `repr(C)` keeps the tag first, so
/// it can be read before a reference to the whole handle is made.
#[repr(C)]
pub struct Handle<T> {
    magic: u64,
    /// The instance.
    pub instance: T,
}

/// Boxes `instance` with the tag `magic`; the pointer goes to the master.
pub fn into_raw<T>(magic: u64, instance: T) -> *mut c_void {
    Box::into_raw(Box::new(Handle { magic, instance })) as *mut c_void
}

/// The handle behind `c`, if `c` looks like a live instance tagged `magic`.
///
/// # Safety
/// `c` is NULL or a pointer returned by [`into_raw`] with the same `T`, and
/// the master does not use the instance from two threads at once.
pub unsafe fn handle<'a, T>(c: *mut c_void, magic: u64) -> Option<&'a mut Handle<T>> {
    let h = c as *mut Handle<T>;
    if h.is_null() || !h.is_aligned() {
        return None;
    }
    // SAFETY: non-NULL and aligned; by the caller's contract it points to a
    // live `Handle<T>`, whose first field is the tag (`repr(C)`). Only the
    // tag is read here, through the raw pointer.
    let tag = unsafe { std::ptr::addr_of!((*h).magic).read() };
    if tag != magic {
        return None;
    }
    // SAFETY: the tag says this is a live handle made by `into_raw`; no
    // other reference to it exists during the call (caller's contract).
    Some(unsafe { &mut *h })
}

/// Frees the handle behind `c` (its tag cleared first, so a second free is
/// recognised and ignored).
///
/// # Safety
/// As [`handle`]; `c` is not used by the master afterwards.
pub unsafe fn free<T>(c: *mut c_void, magic: u64) {
    // SAFETY: forwarded contract.
    if let Some(h) = unsafe { handle::<T>(c, magic) } {
        h.magic = 0;
        // SAFETY: `c` was created by `Box::into_raw` in `into_raw` and is
        // freed exactly once here (its tag is now cleared).
        drop(unsafe { Box::from_raw(c as *mut Handle<T>) });
    }
}

/// A C string for a logger: interior NULs shown as `\0`.
pub fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', "\\0")).unwrap_or_default()
}

/// Bytes of a log message (or category) that [`LogText`] keeps on the
/// stack, its NUL included; a longer text is allocated.
const LOG_TEXT_CAPACITY: usize = 2048;

/// A NUL-terminated copy of a log text for the master's logger, on the
/// stack when it fits (logging a message allocates nothing): interior
/// NULs shown as `\0` and, with `double_percent`, every `%` doubled (an
/// FMI 2.0 logger is printf-like).
pub struct LogText {
    stack: [u8; LOG_TEXT_CAPACITY],
    heap: Option<CString>,
}

impl LogText {
    /// The C text of `text`.
    pub fn new(text: &str, double_percent: bool) -> LogText {
        let mut out = LogText {
            stack: [0; LOG_TEXT_CAPACITY],
            heap: None,
        };
        let mut len = 0;
        for &byte in text.as_bytes() {
            let escaped: &[u8] = match byte {
                0 => b"\\0",
                b'%' if double_percent => b"%%",
                _ => std::slice::from_ref(&byte),
            };
            if len + escaped.len() >= LOG_TEXT_CAPACITY {
                let mut owned = text.replace('\0', "\\0");
                if double_percent {
                    owned = owned.replace('%', "%%");
                }
                out.heap = Some(CString::new(owned).unwrap_or_default());
                return out;
            }
            out.stack[len..len + escaped.len()].copy_from_slice(escaped);
            len += escaped.len();
        }
        out
    }

    /// The NUL-terminated text, valid while `self` lives.
    pub fn as_ptr(&self) -> *const c_char {
        match &self.heap {
            Some(text) => text.as_ptr(),
            None => self.stack.as_ptr().cast(),
        }
    }
}

/// Copies a C string (lossy UTF-8), `None` for NULL.
///
/// # Safety
/// `s` is NULL or a NUL-terminated string.
pub unsafe fn copy_str(s: *const c_char) -> Option<String> {
    if s.is_null() {
        return None;
    }
    // SAFETY: non-NULL and NUL-terminated by the caller's contract; the
    // bytes are copied before returning.
    Some(unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned())
}

/// A read-only array argument: empty for `n == 0` (the pointer may then be
/// NULL), refused when NULL, unaligned or absurdly long.
///
/// # Safety
/// `ptr` is NULL or points to `n` initialised elements that stay valid and
/// unmodified during the call.
pub unsafe fn input<'a, T>(ptr: *const T, n: usize, what: &str) -> Result<&'a [T], FmiError> {
    if n == 0 {
        return Ok(&[]);
    }
    if ptr.is_null() {
        return Err(FmiError::error(format!(
            "{what} is NULL while its length is {n}"
        )));
    }
    if !ptr.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(FmiError::error(format!(
            "{what} is not a valid array of {n} elements"
        )));
    }
    // SAFETY: non-NULL, aligned, size in range; the caller guarantees `n`
    // initialised elements that stay valid and unmodified during the call.
    Ok(unsafe { std::slice::from_raw_parts(ptr, n) })
}

/// A writable array argument (same rules as [`input`]).
///
/// # Safety
/// `ptr` is NULL or points to `n` writable elements not aliased by another
/// argument.
pub unsafe fn output<'a, T>(ptr: *mut T, n: usize, what: &str) -> Result<&'a mut [T], FmiError> {
    if n == 0 {
        return Ok(&mut []);
    }
    if ptr.is_null() {
        return Err(FmiError::error(format!(
            "{what} is NULL while its length is {n}"
        )));
    }
    if !ptr.is_aligned() || n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(FmiError::error(format!(
            "{what} is not a valid array of {n} elements"
        )));
    }
    // SAFETY: non-NULL, aligned, size in range; the caller guarantees `n`
    // writable elements, exclusively ours during the call.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, n) })
}

/// A single output value.
///
/// # Safety
/// `ptr` is NULL or points to a writable `T`.
pub unsafe fn out_value<'a, T>(ptr: *mut T, what: &str) -> Result<&'a mut T, FmiError> {
    // SAFETY: forwarded contract; a length of one.
    unsafe { output(ptr, 1, what) }.map(|s| &mut s[0])
}

/// The message of a caught panic.
pub fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text_of(log: &LogText) -> String {
        // SAFETY: `as_ptr` is NUL-terminated and lives as long as `log`.
        unsafe { CStr::from_ptr(log.as_ptr()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn log_texts_escape_nuls_and_double_percent_signs_on_the_stack_and_beyond() {
        let short = LogText::new("a\0b 5%", true);
        assert!(short.heap.is_none());
        assert_eq!(text_of(&short), "a\\0b 5%%");
        assert_eq!(text_of(&LogText::new("5%", false)), "5%");
        // Longer than the stack buffer: allocated, escaped the same way.
        let long = "x%".repeat(LOG_TEXT_CAPACITY);
        let heap = LogText::new(&long, true);
        assert!(heap.heap.is_some());
        assert_eq!(text_of(&heap), long.replace('%', "%%"));
        // Exactly filling the buffer but for the NUL stays on the stack.
        let fits = "y".repeat(LOG_TEXT_CAPACITY - 1);
        let stack = LogText::new(&fits, true);
        assert!(stack.heap.is_none());
        assert_eq!(text_of(&stack), fits);
    }
}
