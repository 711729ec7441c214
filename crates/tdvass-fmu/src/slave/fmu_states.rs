//! FMU states handed out to the master: copies of the whole slave state,
//! owned by the slave, and their serialized bytes.

use super::{Slave, SlaveState};
use crate::error::{FmiError, Status};
use crate::snapshot;

impl Slave {
    fn owned(&self, handle: usize) -> Result<&SlaveState, FmiError> {
        self.fmu_states.get(&handle).map(|b| &**b).ok_or_else(|| {
            FmiError::error(format!(
                "FMU state {handle:#x} was not created by this instance or was already freed"
            ))
        })
    }

    fn store(&mut self, model: SlaveState, reuse: Option<usize>) -> Result<usize, FmiError> {
        match reuse {
            Some(handle) => {
                self.owned(handle)?;
                if let Some(slot) = self.fmu_states.get_mut(&handle) {
                    **slot = model;
                }
                Ok(handle)
            }
            None => {
                let boxed = Box::new(model);
                let handle = &*boxed as *const SlaveState as usize;
                self.fmu_states.insert(handle, boxed);
                Ok(handle)
            }
        }
    }

    /// `GetFMUstate`: a copy of everything; `reuse` overwrites a state
    /// of this instance. Returns the handle (the `FMUstate` value).
    pub fn get_fmu_state(&mut self, reuse: Option<usize>) -> Result<usize, FmiError> {
        let handle = self.store(self.state.clone(), reuse)?;
        self.event(format_args!(
            "{}: state {handle:#x} at t = {} s",
            format_args!("{}Get{}", self.dialect.prefix, self.dialect.fmu_state),
            self.time()
        ));
        Ok(handle)
    }

    /// `SetFMUstate`: only states of this instance are accepted.
    pub fn set_fmu_state(&mut self, handle: usize) -> Result<Status, FmiError> {
        let mut restored = self.owned(handle)?.clone();
        // A state from before initialization (deserialized ones do not say
        // their kind then) takes the instance's.
        if !restored.engine.is_running() {
            restored.engine = self.state.engine.emptied();
        }
        self.state = restored;
        // A deserialized state carries no tables: build them here, not
        // in the next step.
        if let Some(sim) = self.state.engine.simulator_mut() {
            sim.reserve();
        }
        if let Some(model) = self.state.engine.exchange_mut() {
            model.reserve();
        }
        self.event(format_args!(
            "{}: state {handle:#x}, now at t = {} s in state {}",
            format_args!("{}Set{}", self.dialect.prefix, self.dialect.fmu_state),
            self.time(),
            self.state.phase.name()
        ));
        Ok(Status::Ok)
    }

    /// `FreeFMUstate`.
    pub fn free_fmu_state(&mut self, handle: usize) -> Result<Status, FmiError> {
        self.owned(handle)?;
        self.fmu_states.remove(&handle);
        Ok(Status::Ok)
    }

    /// The serialized bytes of a state of this instance.
    pub fn serialize_fmu_state(&self, handle: usize) -> Result<Vec<u8>, FmiError> {
        Ok(snapshot::serialize(self.owned(handle)?, &self.token))
    }

    /// `DeSerializeFMUstate`: a new state (or `reuse` overwritten) from
    /// bytes written by this FMU, in any instance or process.
    pub fn deserialize_fmu_state(
        &mut self,
        bytes: &[u8],
        reuse: Option<usize>,
    ) -> Result<usize, FmiError> {
        if let Some(handle) = reuse {
            self.owned(handle)?;
        }
        let model = snapshot::deserialize(bytes, &self.token, self.model())?;
        if model.engine.is_model_exchange() != self.state.engine.is_model_exchange()
            && model.phase.is_simulating()
        {
            return Err(FmiError::error(format!(
                "a {} state cannot be restored into a {} instance",
                model.engine.kind_name(),
                self.state.engine.kind_name()
            )));
        }
        let handle = self.store(model, reuse)?;
        self.event(format_args!(
            "{}: {} bytes into state {handle:#x}",
            self.call(self.dialect.deserialize_state),
            bytes.len()
        ));
        Ok(handle)
    }
}
