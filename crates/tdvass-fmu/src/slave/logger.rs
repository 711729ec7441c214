//! Logging of a slave: the master's sink and the categories switched on.

use crate::defaults::LOG_CATEGORIES;
use crate::error::{FmiError, Status};
use std::fmt;

/// Bytes of a message formatted on the stack; a longer one is allocated.
const MESSAGE_CAPACITY: usize = 1536;

/// A message formatted on the stack ([`Logger::log_lazily`]): writing
/// fails, without a partial character, when it does not fit.
struct MessageText {
    bytes: [u8; MESSAGE_CAPACITY],
    len: usize,
}

impl fmt::Write for MessageText {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        if end > MESSAGE_CAPACITY {
            return Err(fmt::Error);
        }
        self.bytes[self.len..end].copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Receives log messages: `(status, category, message)`.
pub type LogSink = Box<dyn Fn(Status, &str, &str)>;

/// The log sink and which categories are on: Discard, Error and Fatal are
/// always reported; events and warnings only when enabled.
pub struct Logger {
    sink: LogSink,
    /// Enabled flags of the categories of [`LOG_CATEGORIES`] (without `logAll`).
    enabled: [bool; 5],
}

impl Logger {
    /// A logger with events on or off (warnings on).
    pub fn new(sink: LogSink, events: bool) -> Logger {
        Logger {
            sink,
            enabled: [events, true, true, true, true],
        }
    }

    fn category_of(status: Status) -> usize {
        match status {
            Status::Ok => 0,
            Status::Warning => 1,
            Status::Discard => 2,
            Status::Error => 3,
            Status::Fatal => 4,
        }
    }

    /// Logs `message` under the category of `status`, when enabled.
    pub fn log(&self, status: Status, message: &str) {
        let category = Self::category_of(status);
        if category >= 2 || self.enabled[category] {
            (self.sink)(status, LOG_CATEGORIES[category].0, message);
        }
    }

    /// Whether messages of `status` reach the sink.
    pub fn enabled(&self, status: Status) -> bool {
        let category = Self::category_of(status);
        category >= 2 || self.enabled[category]
    }

    /// Logs `message` under the category of `status`, formatting it only
    /// when the category is on: a message nobody reads allocates nothing.
    pub fn log_lazily(&self, status: Status, message: fmt::Arguments) {
        if !self.enabled(status) {
            return;
        }
        let mut text = MessageText {
            bytes: [0; MESSAGE_CAPACITY],
            len: 0,
        };
        if fmt::write(&mut text, message).is_ok() {
            // Only whole UTF-8 characters are written.
            self.log(
                status,
                std::str::from_utf8(&text.bytes[..text.len]).unwrap_or(""),
            );
        } else {
            self.log(status, &message.to_string());
        }
    }

    /// Switches `categories` (empty: all) on or off. Unknown categories
    /// refuse the whole call.
    pub fn set_categories(&mut self, on: bool, categories: &[&str]) -> Result<Status, FmiError> {
        let mut enabled = self.enabled;
        if categories.is_empty() {
            enabled = [on; 5];
        }
        for &category in categories {
            match LOG_CATEGORIES
                .iter()
                .position(|(name, _)| *name == category)
            {
                Some(5) => enabled = [on; 5],
                Some(i) => enabled[i] = on,
                None => {
                    let known: Vec<_> = LOG_CATEGORIES.iter().map(|(n, _)| *n).collect();
                    return Err(FmiError::error(format!(
                        "unknown log category `{category}` (known: {})",
                        known.join(", ")
                    )));
                }
            }
        }
        self.enabled = enabled;
        Ok(Status::Ok)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;
    use std::rc::Rc;

    #[test]
    fn lazy_messages_reach_the_sink_whole_and_only_when_their_category_is_on() {
        let seen = Rc::new(RefCell::new(Vec::new()));
        let sink = Rc::clone(&seen);
        let logger = Logger::new(
            Box::new(move |status, _, message: &str| {
                sink.borrow_mut().push((status, message.to_string()))
            }),
            false,
        );
        logger.log_lazily(Status::Ok, format_args!("event {}", 1));
        logger.log_lazily(Status::Warning, format_args!("warning {}", 2));
        let long = "z".repeat(MESSAGE_CAPACITY + 10);
        logger.log_lazily(Status::Warning, format_args!("{long}"));
        let seen = seen.borrow();
        assert_eq!(seen.len(), 2, "events are off");
        assert_eq!(seen[0], (Status::Warning, "warning 2".to_string()));
        assert_eq!(seen[1].1, long, "a message beyond the stack is whole");
    }
}
