//! The trajectory: the committed point (a grid node, or a point where an
//! external road input changed or the tire's contact switched), the
//! current point with its state (or the bounds of a deferred one), and the
//! tire's mode. Only the driver moves the committed point.
//!
//! Layer: observers (docs/architecture.md); it imports the solver's
//! `deferred`, `stepping`, `system` and the crate's `bytes`, `error`,
//! `model`.

use super::deferred::{Deferred, Kind};
use super::stepping::Committed;
use super::system::Filter;
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::model::State;
use crate::model::dynamics::{Mode, Switch};

/// Where the run is: the committed point (a grid node, or a point where
/// an external road input changed or the tire contact switched) and the
/// current point.
#[derive(Debug, Clone)]
pub(super) struct Trajectory {
    /// Index k of the grid node at or before the committed time.
    pub(super) grid_index: u64,
    pub(super) committed_time: f64,
    pub(super) committed_state: State,
    /// The W_k filter state at the committed point (zero without it).
    pub(super) committed_filter: Filter,
    pub(super) current_time: f64,
    /// The state at `current_time`, unless `deferred`.
    pub(super) current_state: State,
    /// `Some` while `current_state` is still to be found ([`super::deferred`]):
    /// what finds it and the bounds that showed it passes the divergence
    /// check.
    pub(super) deferred: Option<Deferred>,
    /// The mode in force: one bit per switching element (the tire in
    /// flight).
    pub(super) mode: Mode,
    /// With the tire in flight, the start of its flight (s), which the
    /// lost time counts from; `None` in contact. The flights that ended
    /// are in the road-holding accumulators' lost time.
    pub(super) flight_start: Option<f64>,
}

impl Trajectory {
    /// The committed point, as stepping takes it.
    #[inline]
    pub(super) fn committed(&self) -> Committed {
        Committed {
            k: self.grid_index,
            time: self.committed_time,
            state: self.committed_state,
            filter: self.committed_filter,
        }
    }

    /// The committed point's grid index, time and state.
    #[inline]
    pub(super) fn committed_point(&self) -> (u64, f64, &State) {
        (self.grid_index, self.committed_time, &self.committed_state)
    }

    /// Writes the grid index and the committed and current points (a
    /// deferred current state as the committed one: see
    /// [`Trajectory::write_deferral`]).
    pub(super) fn write_points(&self, w: &mut ByteWriter) {
        w.u64(self.grid_index);
        w.f64(self.committed_time);
        self.committed_state.iter().for_each(|&v| w.f64(v));
        w.f64(self.current_time);
        self.current_state.iter().for_each(|&v| w.f64(v));
    }

    /// Reads what [`Trajectory::write_points`] wrote (checked against the
    /// grid by the caller, which knows it).
    pub(super) fn read_points(&mut self, r: &mut ByteReader) -> Result<()> {
        self.grid_index = r.u64()?;
        self.committed_time = r.f64()?;
        for v in self.committed_state.iter_mut() {
            *v = r.f64()?;
        }
        self.current_time = r.f64()?;
        for v in self.current_state.iter_mut() {
            *v = r.f64()?;
        }
        Ok(())
    }

    /// Writes what finds a deferred current state (one byte,
    /// [`Kind::code`]); the bounds are found again when the bytes are read.
    pub(super) fn write_deferral(&self, w: &mut ByteWriter) {
        w.u8(Kind::code(self.deferred.map(|d| d.kind)));
    }

    /// Reads what [`Trajectory::write_deferral`] wrote. A deferred state
    /// must have been written as the committed one.
    pub(super) fn read_deferral(&self, r: &mut ByteReader) -> Result<Option<Kind>> {
        let code = r.u8()?;
        let deferral = Kind::from_code(code)
            .ok_or_else(|| Error::InvalidState(format!("deferral {code}: 0, 1 or 2 is read")))?;
        let bits = |x: &State| x.map(f64::to_bits);
        if deferral.is_some() && bits(&self.current_state) != bits(&self.committed_state) {
            return Err(Error::InvalidState(
                "a deferred current state must be written as the committed one".into(),
            ));
        }
        Ok(deferral)
    }

    /// Writes the filter state at the committed point.
    pub(super) fn write_filter(&self, w: &mut ByteWriter) {
        self.committed_filter.iter().for_each(|&v| w.f64(v));
    }

    /// Reads what [`Trajectory::write_filter`] wrote.
    pub(super) fn read_filter(&mut self, r: &mut ByteReader) -> Result<()> {
        for v in self.committed_filter.iter_mut() {
            *v = r.f64()?;
        }
        Ok(())
    }

    /// Writes the mode (its index, one word) and the start of the tire's
    /// flight in progress.
    pub(super) fn write_mode(&self, w: &mut ByteWriter) {
        w.u64(self.mode.index() as u64);
        w.optional_f64(self.flight_start);
    }

    /// Reads what [`Trajectory::write_mode`] wrote; `with_mode_word`:
    /// false for the bytes of format 4, which had no mode word (the flight
    /// in progress says the tire's mode, then the only one). The mode must
    /// be one of [`Mode::COUNT`] and agree with the flight in progress.
    pub(super) fn read_mode(&mut self, r: &mut ByteReader, with_mode_word: bool) -> Result<()> {
        let word = if with_mode_word { Some(r.u64()?) } else { None };
        self.flight_start = r.optional_f64("flight")?;
        let in_flight = self.flight_start.is_some();
        self.mode = match word {
            None => Mode::CONTACT.with(Switch::Tire, in_flight),
            Some(index) if index < Mode::COUNT as u64 => Mode::from_index(index as usize),
            Some(index) => {
                return Err(Error::InvalidState(format!(
                    "mode {index}: there are {} modes",
                    Mode::COUNT
                )));
            }
        };
        if self.mode.is(Switch::Tire) != in_flight {
            return Err(Error::InvalidState(format!(
                "mode {} says the tire is {}, the flight in progress says {}",
                self.mode.index(),
                if self.mode.is(Switch::Tire) {
                    "in flight"
                } else {
                    "in contact"
                },
                if in_flight { "in flight" } else { "in contact" }
            )));
        }
        Ok(())
    }

    /// Commits grid node k at `time` with state x and filter state w; it is
    /// the current point too.
    #[inline]
    pub(super) fn commit_node(&mut self, k: u64, time: f64, x: State, w: Filter) {
        self.grid_index = k;
        self.committed_time = time;
        self.committed_state = x;
        self.committed_filter = w;
        self.set_current(time, x);
    }

    /// Commits the current point (inside step `grid_index`, where a switch
    /// or an input change is), with filter state w there.
    #[inline]
    pub(super) fn commit_current(&mut self, w: Filter) {
        self.committed_filter = w;
        self.committed_time = self.current_time;
        self.committed_state = self.current_state;
    }

    /// Sets the current point (time, state computed).
    #[inline]
    pub(super) fn set_current(&mut self, time: f64, x: State) {
        self.current_time = time;
        self.current_state = x;
        self.deferred = None;
    }
}
