//! Going back and bounded work (module documentation of
//! [`super`]): the floor [`ModelExchange::set_time`] keeps, what the
//! history and the road keep for it, and the times it refuses.

use super::instance::{Delay, ModelExchange, TRIAL_REACH};
use crate::error::{Error, Result};
use crate::exchange::MAX_HISTORY_POINTS;
use crate::limits::MAX_WORK_PER_CALL;
use crate::road::Road;
use crate::solver::accuracy::LARGEST_STEP;
use crate::solver::{MIN_RESOLVED_DELAY, SimulationConfig, Simulator};

impl ModelExchange {
    /// The largest |time| (s) the model of `config` resolves: `2^42` times
    /// the finest time it resolves (the delay of the history, a random
    /// road's node interval, at most [`LARGEST_STEP`]), so that the time
    /// still resolves it to about 1e-3 of itself.
    pub(super) fn time_bound(config: &SimulationConfig) -> f64 {
        let tau = config.params.tau;
        let mut finest = LARGEST_STEP;
        if config.variant.has_control() && tau >= MIN_RESOLVED_DELAY {
            finest = finest.min(tau);
        }
        if let Ok(road) = Road::new(&config.road, 0.0)
            && let Some(interval) = road.node_interval()
        {
            finest = finest.min(interval);
        }
        finest * Simulator::MAX_START_TIME_IN_STEPS
    }

    /// The earliest time [`Self::set_time`] takes (module documentation).
    pub fn earliest_time(&self) -> f64 {
        self.floor
    }

    /// The largest |time| (s) [`Self::set_time`] takes.
    pub fn time_limit(&self) -> f64 {
        self.max_time
    }

    /// Sets the time: finite, resolved ([`Self::time_limit`]), not before
    /// the floor ([`Self::earliest_time`]), and within the random road's
    /// work per call (module documentation). A master that has never
    /// completed a step moves the floor to [`TRIAL_REACH`] before the time.
    pub fn set_time(&mut self, time: f64) -> Result<()> {
        if !(time.is_finite() && time.abs() <= self.max_time) {
            return Err(Error::Refused(format!(
                "time {time} s is not finite or beyond {:e} s, 2^42 times the finest time the model resolves (the delay, the road's node interval, 0.01 s)",
                self.max_time
            )));
        }
        if time < self.floor {
            return Err(Error::Refused(self.before_floor_message(time)));
        }
        let floor = if self.completes {
            self.floor
        } else {
            self.floor.max(time - TRIAL_REACH)
        };
        let (generated, kept) = self.road.node_work(floor, time);
        if generated > MAX_WORK_PER_CALL || kept > MAX_WORK_PER_CALL {
            return Err(Error::Refused(format!(
                "time {time} s needs {:e} road nodes generated and {:e} kept (from {} s on), more than the limit of {MAX_WORK_PER_CALL} per call; move the time on in smaller steps{}",
                generated,
                kept,
                floor.max(self.road.earliest_time()),
                if self.completes {
                    ""
                } else {
                    " or call CompletedIntegratorStep at the solver's accepted steps"
                }
            )));
        }
        self.time = time;
        self.latest = self.latest.max(time);
        self.move_floor(floor);
        Ok(())
    }

    /// Why `time` is before the floor, and what to do.
    fn before_floor_message(&self, time: f64) -> String {
        let floor = self.floor;
        if floor == self.accepted {
            format!(
                "time {time} s is before {floor} s, the last completed integrator step or event: no master goes back before it"
            )
        } else if !self.completes && floor >= self.latest - TRIAL_REACH {
            format!(
                "time {time} s is before {floor} s, the earliest time kept: a master that does not call CompletedIntegratorStep may go back at most {TRIAL_REACH} s from the latest time it set ({} s); call CompletedIntegratorStep at the solver's accepted steps, and go back no further than the last of them",
                self.latest
            )
        } else {
            format!(
                "time {time} s is before {floor} s, the earliest time kept: the delay history holds at most {MAX_HISTORY_POINTS} points and the road {MAX_WORK_PER_CALL} nodes since the last completed integrator step or event ({} s); call CompletedIntegratorStep at the solver's accepted steps",
                self.accepted
            )
        }
    }

    /// Moves the floor on to `floor` (s) and frees what no time from there
    /// on needs.
    pub(super) fn move_floor(&mut self, floor: f64) {
        self.floor = self.floor.max(floor);
        if let Delay::History(h) = &mut self.delay {
            h.trim(self.floor);
        }
        self.road.release_before(self.floor);
    }

    /// After the history gave its oldest points way to its bound: the
    /// floor follows the earliest time it still determines.
    pub(super) fn follow_history_bound(&mut self) {
        if let Delay::History(h) = &self.delay {
            self.floor = self.floor.max(h.earliest_time());
        }
    }
}
