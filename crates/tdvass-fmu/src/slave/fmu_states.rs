//! FMU states handed out to the master: copies of the whole slave state,
//! owned by the slave, and their serialized bytes.

use super::{Slave, SlaveState};
use crate::phase::Phase;
use crate::snapshot;
use crate::{FmiError, Status};

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
        self.state = self.owned(handle)?.clone();
        // A deserialized state carries no tables: build them here, not
        // in the next step.
        if let Some(sim) = self.state.sim.as_mut() {
            sim.reserve();
        }
        if let Some(model) = self.state.exchange.as_mut() {
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
        let model = snapshot::deserialize(bytes, &self.token)?;
        let model_exchange_state = model.exchange.is_some()
            || matches!(model.phase, Phase::EventMode | Phase::ContinuousTimeMode);
        if model_exchange_state != self.model_exchange && model.phase.is_simulating() {
            let kind = |me: bool| {
                if me {
                    "Model Exchange"
                } else {
                    "Co-Simulation"
                }
            };
            return Err(FmiError::error(format!(
                "a {} state cannot be restored into a {} instance",
                kind(model_exchange_state),
                kind(self.model_exchange)
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
