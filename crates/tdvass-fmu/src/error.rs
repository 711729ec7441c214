//! The status of a call and the error of a refused one, with the codes
//! FMI 2.0 and FMI 3.0 share; a library error becomes an Error with the
//! library's message.

/// The status of a call, with the codes FMI 2.0 and FMI 3.0 share
/// (`OK` 0 .. `Fatal` 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

impl Status {
    /// The status name without the version prefix (`OK`, `Warning`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::Warning => "Warning",
            Status::Discard => "Discard",
            Status::Error => "Error",
            Status::Fatal => "Fatal",
        }
    }
}

/// A call that did not (fully) succeed: the status to return and the
/// message to log (without the function-name prefix, which the front-end's
/// dispatcher adds).
#[derive(Debug, Clone, PartialEq)]
pub struct FmiError {
    /// Status returned to the master (Discard, Error or Fatal).
    pub status: Status,
    /// What went wrong, naming the variable and value where there is one.
    pub message: String,
}

impl FmiError {
    /// An Error with `message`.
    pub fn error(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Error,
            message: message.into(),
        }
    }

    /// A Discard with `message`.
    pub fn discard(message: impl Into<String>) -> FmiError {
        FmiError {
            status: Status::Discard,
            message: message.into(),
        }
    }
}

impl From<tdvass::Error> for FmiError {
    /// Library errors (invalid parameter, invalid state bytes, a limit...)
    /// are Errors with the library's message, which names the variable and
    /// value.
    fn from(e: tdvass::Error) -> FmiError {
        FmiError::error(e.to_string())
    }
}

impl std::fmt::Display for FmiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.status.name(), self.message)
    }
}
