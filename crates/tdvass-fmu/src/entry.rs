//! What the C entry points of every FMI version do around an instance,
//! written once: a front-end's instance is a [`FrontEnd`], which runs every
//! call under the front-end's state table ([`FrontEnd::run`]) and makes the
//! instance fatal after a panic ([`FrontEnd::on_panic`]).

use crate::{FmiError, Slave, Status};

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

    /// The slave.
    fn slave(&self) -> &Slave;

    /// The slave, to call it.
    fn slave_mut(&mut self) -> &mut Slave;

    /// After a panic: drops what the front-end holds of the call in
    /// progress (nothing by default; the slave goes to `Fatal` anyway).
    fn after_panic(&mut self) {}

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

    /// After a panic inside `function` (caught by the front-end's C layer): the
    /// instance may be inconsistent, so it goes to `Fatal`.
    fn on_panic(&mut self, function: Self::Function, message: &str) {
        self.after_panic();
        self.slave_mut().report_panic(Self::name(function), message);
    }
}
