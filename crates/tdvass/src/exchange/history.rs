//! The delay history of Model Exchange: `(x_t, v_t)` at the instants a
//! master evaluated the derivatives or accepted a point, and the delayed
//! wheel displacement `x_t(t − tau)` interpolated from them.
//!
//! A Model Exchange master drives the model by setting a time and states
//! and asking for derivatives; only some masters say which of those points
//! their integrator kept (`CompletedIntegratorStep`), and some ask for
//! derivatives past the time they return to. The history tells two kinds
//! of points apart:
//! - **accepted** points: the start, completed integrator steps and events.
//!   No master goes back before the last of them, and a later evaluation
//!   at the same instant leaves them unchanged;
//! - **trial** points: every other derivative evaluation. When the time
//!   moves back (a rejected step, a master stepping back to an output
//!   time), the trial points at and after the new time are dropped, so the
//!   history holds only the last attempt at every instant.
//!
//! **Stages.** An explicit Runge–Kutta master evaluates stage states
//! inside its step (RK4's `t + h/2`), accurate to a lower order than the
//! step; interpolating the delay through them would lower the method's
//! order to two. The history leaves them out where it can tell them:
//! - **a completed step** ([`DelayHistory::accept`]) at `t_c` that the
//!   master did not evaluate past: its trial points since the last accepted
//!   point, at most [`STAGE_POINTS`], are that step's stages and are
//!   dropped. More are kept (the master took several steps since it last
//!   completed one), and so are the points of a master that evaluated past
//!   `t_c` (a variable-step solver returning to an output point by
//!   interpolation: its points are its own accepted steps). A master whose
//!   completions drop its stages "completes its steps": while it does, the
//!   stages of its current step are not used either, and a delay shorter
//!   than its step is continued from its last two accepted points (the
//!   cubic of the accepted steps, fourth order);
//! - **a re-evaluated step end**: a master that has never completed a step
//!   evaluates its next step's start at the instant of its last stage
//!   (RK4's `k4` then the next `k1`, a first-same-as-last method's last
//!   stage). The trial points between the previous such end (an "anchor")
//!   and this one, at most [`STAGE_POINTS`], are then superseded by it:
//!   delayed values at later times do not use them. At the anchor's own
//!   instant they still do, so that every evaluation at one instant (a
//!   solver's Newton iterations, its difference-quotient Jacobian) sees the
//!   same function. A master that completes steps, even rarely, is not
//!   second-guessed: a BDF solver evaluates each step end several times
//!   too, and every other of its points would be lost (fmpy's CVODE needed
//!   24 % more evaluations so).
//!
//! **Interpolation.** The delayed value at `s = t − tau` is the cubic
//! Hermite interpolant, through positions and velocities, of the two
//! usable points about s. Where s lies past the last usable point before t
//! (a delay shorter than the master's step) the right end is the current
//! state `(t, x_t, v_t)` itself: the history is interpolated towards the
//! present. Before the start time the delayed value is the initial `x_t`,
//! the co-simulation's initial history.
//!
//! **Memory.** The model says from which time on points are needed
//! ([`DelayHistory::trim`]); at most [`MAX_HISTORY_POINTS`] are kept (the
//! oldest give way, and [`DelayHistory::earliest_time`] moves on).

use crate::model::dynamics;
use std::collections::VecDeque;

/// Most points kept (40 MiB).
pub const MAX_HISTORY_POINTS: usize = 1 << 20;

/// Most trial points taken for the stages of one step (more than any
/// explicit Runge–Kutta method of order up to eight has distinct stage
/// times).
pub const STAGE_POINTS: usize = 16;

/// Relative difference of two times taken for the same instant (a stage
/// at `t + 1.0 h` against a step end at `(n + 1) h`).
const SAME_INSTANT: f64 = 1e-12;

/// Points room is made for at the start, and kept through copies and
/// restored states: a master that completes its steps needs about
/// tau / step + [`STAGE_POINTS`], so a real-time master's evaluations do
/// not allocate.
const INITIAL_CAPACITY: usize = 2048;

/// One point of the history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HistoryPoint {
    /// t (s).
    pub time: f64,
    /// x_t(t) (m).
    pub position: f64,
    /// v_t(t) (m/s).
    pub velocity: f64,
    /// A start, completed step or event (not dropped when time moves back).
    pub accepted: bool,
    /// A re-evaluated step end (module documentation).
    pub anchor: bool,
    /// The time (s) of the anchor that superseded this stage, `+∞` if none:
    /// delayed values after it do not use the point.
    pub superseded_by: f64,
}

impl HistoryPoint {
    /// A trial point.
    fn trial((time, position, velocity): (f64, f64, f64)) -> HistoryPoint {
        HistoryPoint {
            time,
            position,
            velocity,
            accepted: false,
            anchor: false,
            superseded_by: f64::INFINITY,
        }
    }

    /// Whether a delayed value at `t` may use the point.
    fn usable_at(&self, t: f64) -> bool {
        self.time < t && self.superseded_by >= t - rounding(t)
    }
}

/// The delayed value and its partial derivatives with respect to the
/// current state: `x_t(t − tau)` (m), `∂/∂x_t` (1) and `∂/∂v_t` (s). The
/// partials are not zero only where the value interpolates towards the
/// current state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Delayed {
    /// `x_t(t − tau)` (m).
    pub value: f64,
    /// `∂ value / ∂ x_t(t)`.
    pub by_position: f64,
    /// `∂ value / ∂ v_t(t)` (s).
    pub by_velocity: f64,
}

impl Delayed {
    /// A value that does not depend on the current state.
    fn held(value: f64) -> Delayed {
        Delayed {
            value,
            by_position: 0.0,
            by_velocity: 0.0,
        }
    }
}

/// The history of `(x_t, v_t)`; see the module documentation.
#[derive(Debug, PartialEq)]
pub struct DelayHistory {
    /// Increasing in time; the first `accepted_len` are accepted, the rest
    /// trial points.
    points: VecDeque<HistoryPoint>,
    /// How many points, from the oldest, are accepted (at least 1).
    accepted_len: usize,
    /// t_0 (s).
    start_time: f64,
    /// x_t(t_0) (m): the delayed value before the start.
    initial_position: f64,
    /// tau (s), > 0.
    tau: f64,
    /// The master's last `CompletedIntegratorStep` dropped its stages (module
    /// documentation).
    completes_steps: bool,
    /// The master has called `CompletedIntegratorStep`: no anchors.
    completed_once: bool,
}

/// A copy keeps the room of the original (at least `INITIAL_CAPACITY`
/// points), so a restored FMU state records points without allocating.
impl Clone for DelayHistory {
    fn clone(&self) -> DelayHistory {
        let mut points = VecDeque::with_capacity(self.points.capacity().max(INITIAL_CAPACITY));
        points.extend(self.points.iter().copied());
        DelayHistory {
            points,
            accepted_len: self.accepted_len,
            start_time: self.start_time,
            initial_position: self.initial_position,
            tau: self.tau,
            completes_steps: self.completes_steps,
            completed_once: self.completed_once,
        }
    }
}

/// How far apart (s) two times near `t` may be and be the same instant.
fn rounding(t: f64) -> f64 {
    SAME_INSTANT * t.abs().max(1.0)
}

/// `p(s)` of the cubic through `(t0, x0, v0)` and `(t1, x1, v1)`, `t0 < t1`
/// (the model's interpolant, [`dynamics::hermite`]).
fn hermite(s: f64, (t0, x0, v0): (f64, f64, f64), (t1, x1, v1): (f64, f64, f64)) -> f64 {
    dynamics::hermite([x0, v0, x1, v1], t1 - t0, s - t0)[0]
}

/// `(∂p/∂x1, ∂p/∂v1)` of [`hermite`]: the weights of the right end.
fn hermite_right_weights(s: f64, t0: f64, t1: f64) -> (f64, f64) {
    let h = t1 - t0;
    let theta = (s - t0) / h;
    let rest = 1.0 - theta;
    (
        theta * theta * (3.0 - 2.0 * theta),
        -h * theta * theta * rest,
    )
}

impl DelayHistory {
    /// A history with the accepted start point `(t_0, x_t, v_t)` and delay
    /// `tau` (s, > 0).
    pub fn new(start_time: f64, position: f64, velocity: f64, tau: f64) -> DelayHistory {
        let mut points = VecDeque::with_capacity(INITIAL_CAPACITY);
        points.push_back(HistoryPoint {
            accepted: true,
            ..HistoryPoint::trial((start_time, position, velocity))
        });
        DelayHistory {
            points,
            accepted_len: 1,
            start_time,
            initial_position: position,
            tau,
            completes_steps: false,
            completed_once: false,
        }
    }

    /// A history of `points` (restored from a saved state), checked: times
    /// finite, increasing and not before `start_time`, values finite, the
    /// first point accepted and no accepted point after a trial point, each
    /// stage superseded by a later time.
    pub fn from_points(
        start_time: f64,
        initial_position: f64,
        tau: f64,
        points: Vec<HistoryPoint>,
        (completes_steps, completed_once): (bool, bool),
    ) -> Result<DelayHistory, String> {
        let Some(first) = points.first() else {
            return Err("a delay history without points".into());
        };
        if !first.accepted {
            return Err("a delay history whose first point is not accepted".into());
        }
        for (i, p) in points.iter().enumerate() {
            if !(p.time.is_finite() && p.position.is_finite() && p.velocity.is_finite()) {
                return Err(format!("delay history point {i} is not finite"));
            }
            if p.time < start_time || (i > 0 && p.time <= points[i - 1].time) {
                return Err(format!(
                    "delay history point {i} at {} s is not after the one before it and the start time",
                    p.time
                ));
            }
            if p.superseded_by.is_nan() || p.superseded_by <= p.time {
                return Err(format!(
                    "delay history point {i} at {} s is superseded at {} s",
                    p.time, p.superseded_by
                ));
            }
        }
        let accepted_len = points.iter().take_while(|p| p.accepted).count();
        if points[accepted_len..].iter().any(|p| p.accepted) {
            return Err("a delay history with an accepted point after a trial point".into());
        }
        if points.len() > MAX_HISTORY_POINTS {
            return Err(format!(
                "a delay history of {} points (at most {MAX_HISTORY_POINTS})",
                points.len()
            ));
        }
        let mut deque = VecDeque::with_capacity(points.len().max(INITIAL_CAPACITY));
        deque.extend(points);
        Ok(DelayHistory {
            points: deque,
            accepted_len,
            start_time,
            initial_position,
            tau,
            completes_steps,
            completed_once,
        })
    }

    /// The delay tau (s).
    pub fn tau(&self) -> f64 {
        self.tau
    }

    /// x_t(t_0) (m).
    pub fn initial_position(&self) -> f64 {
        self.initial_position
    }

    /// Whether the master's last completed step dropped its stages, and
    /// whether it has completed a step (module documentation).
    pub fn habits(&self) -> (bool, bool) {
        (self.completes_steps, self.completed_once)
    }

    /// The points, oldest first.
    pub fn points(&self) -> impl ExactSizeIterator<Item = &HistoryPoint> {
        self.points.iter()
    }

    /// The time of the last accepted point (s).
    pub fn accepted_time(&self) -> f64 {
        self.points
            .get(self.accepted_len.wrapping_sub(1))
            .map_or(self.start_time, |p| p.time)
    }

    /// The time of the latest point (s).
    pub fn latest_time(&self) -> f64 {
        self.points.back().map_or(self.start_time, |p| p.time)
    }

    /// The earliest time whose delayed value the points kept determine:
    /// any while the start point is kept, else the oldest point's time
    /// plus tau.
    pub fn earliest_time(&self) -> f64 {
        match self.points.front() {
            Some(p) if p.time > self.start_time => p.time + self.tau,
            _ => f64::NEG_INFINITY,
        }
    }

    /// Whether the trial points past the last accepted one are the stages
    /// of a step in progress of a master that completes its steps (module
    /// documentation).
    fn in_step(&self) -> bool {
        self.completes_steps && self.points.len() - self.accepted_len <= STAGE_POINTS
    }

    /// `x_t(t − tau)` (m) for the current point `now = (t, x_t, v_t)`, with
    /// its partials with respect to the current `x_t`, `v_t` (module
    /// documentation). Points at or after t are not used.
    pub fn delayed(&self, (t, position, velocity): (f64, f64, f64)) -> Delayed {
        let s = t - self.tau;
        if s < self.start_time {
            return Delayed::held(self.initial_position);
        }
        let in_step = self.in_step();
        let limit = if in_step {
            self.accepted_len
        } else {
            self.points.len()
        };
        let usable = |i: usize| self.points[i].usable_at(t);
        let after = self.points.partition_point(|p| p.time <= s).min(limit);
        let mut left = after;
        while left > 0 && !usable(left - 1) {
            left -= 1;
        }
        let Some(left) = left.checked_sub(1).map(|i| self.points[i]) else {
            // Only after the bound on the number of points dropped the
            // point before s (the model refuses such times): the oldest
            // point held.
            return Delayed::held(self.points.front().map_or(position, |p| p.position));
        };
        if left.time == s {
            return Delayed::held(left.position);
        }
        let left_end = (left.time, left.position, left.velocity);
        let right = (after..limit)
            .take_while(|&i| self.points[i].time < t)
            .find(|&i| usable(i));
        if let Some(p) = right.map(|i| self.points[i]) {
            return Delayed::held(hermite(s, left_end, (p.time, p.position, p.velocity)));
        }
        if in_step && self.accepted_time() < t {
            return Delayed::held(self.extrapolated(s));
        }
        let (by_position, by_velocity) = hermite_right_weights(s, left.time, t);
        Delayed {
            value: hermite(s, left_end, (t, position, velocity)),
            by_position,
            by_velocity,
        }
    }

    /// `x_t(s)` past the last accepted point, inside a step in progress:
    /// the cubic of the last two accepted points continued (the first
    /// step: the start's Taylor line). A stage of a step shorter than the
    /// delay never gets here; one of a longer step gets a value of the
    /// accepted steps alone, fourth order like them.
    fn extrapolated(&self, s: f64) -> f64 {
        let last = self.points[self.accepted_len - 1];
        match self.accepted_len.checked_sub(2).map(|i| self.points[i]) {
            Some(before) => hermite(
                s,
                (before.time, before.position, before.velocity),
                (last.time, last.position, last.velocity),
            ),
            None => last.position + last.velocity * (s - last.time),
        }
    }

    /// The trial points between the last anchor or accepted point and the
    /// latest point, if they are at most [`STAGE_POINTS`].
    fn stages_before_latest(&self) -> Option<usize> {
        let length = self.points.len();
        (1..length.min(STAGE_POINTS + 2))
            .find(|&k| {
                let p = &self.points[length - 1 - k];
                p.accepted || p.anchor
            })
            .map(|k| k - 1)
    }

    /// Records the evaluated point `(t, x_t, v_t)` (module documentation):
    /// a re-evaluation of the latest trial point's instant after stages
    /// makes it an anchor; otherwise the trial points at and after t are
    /// dropped first (the time moved back, or the same instant is evaluated
    /// again). An accepted point at t stays as it is.
    pub fn record(&mut self, now: (f64, f64, f64)) {
        let t = now.0;
        let r = rounding(t);
        let length = self.points.len();
        let latest = self.points.back().copied();
        let reevaluated =
            length > self.accepted_len && latest.is_some_and(|p| (p.time - t).abs() <= r);
        if reevaluated
            && !self.completed_once
            && let Some(stages @ 1..) = self.stages_before_latest()
        {
            for p in self.points.range_mut(length - 1 - stages..length - 1) {
                p.superseded_by = t;
            }
            self.points[length - 1] = HistoryPoint {
                anchor: true,
                ..HistoryPoint::trial(now)
            };
            return;
        }
        let anchor_again = self.drop_trial_points_from(t);
        match self.points.back() {
            // An accepted point at or after t: it stays (the model refuses
            // times before the last accepted point).
            Some(last) if last.time >= t => {}
            _ => self.points.push_back(HistoryPoint {
                anchor: anchor_again,
                ..HistoryPoint::trial(now)
            }),
        }
        if self.points.len() > MAX_HISTORY_POINTS {
            self.pop_oldest();
        }
    }

    /// Drops the trial points at and after `t` (the same instant too); the
    /// stages their anchors superseded are stages no more, but for those of
    /// an anchor at `t` itself, which the point recorded there replaces.
    /// Returns whether it does.
    fn drop_trial_points_from(&mut self, t: f64) -> bool {
        let r = rounding(t);
        let mut anchor_again = false;
        while self.points.len() > self.accepted_len
            && self.points.back().is_some_and(|p| p.time >= t - r)
        {
            if let Some(p) = self.points.pop_back() {
                anchor_again |= p.anchor && (p.time - t).abs() <= r;
            }
        }
        for p in self.points.iter_mut().rev().take(STAGE_POINTS + 1) {
            if p.superseded_by == f64::INFINITY {
                break;
            }
            if p.superseded_by >= t - r && !(anchor_again && (p.superseded_by - t).abs() <= r) {
                p.superseded_by = f64::INFINITY;
            }
        }
        anchor_again
    }

    /// Accepts the point `(t, x_t, v_t)` (a completed integrator step when
    /// `completed`, else an event), with the rule of the module
    /// documentation; every point before it is accepted too. A master whose
    /// completion drops its stages completes its steps from now on
    /// ([`Self::habits`]); one whose completion keeps its points does not.
    pub fn accept(&mut self, now: (f64, f64, f64), completed: bool) {
        let t = now.0;
        let r = rounding(t);
        let latest = self.latest_time();
        let mut stages_dropped = false;
        if latest <= t + r {
            let stages = self.points.len() - self.accepted_len;
            let at_end = usize::from(stages > 0 && latest >= t - r);
            if stages - at_end <= STAGE_POINTS {
                self.points.truncate(self.accepted_len);
                stages_dropped = true;
            }
        }
        // Where the point goes: after the points before t.
        let at = self.points.partition_point(|p| p.time < t - r);
        let point = HistoryPoint {
            accepted: true,
            ..HistoryPoint::trial(now)
        };
        match self.points.get_mut(at) {
            Some(p) if p.time <= t + r => *p = point,
            _ => self.points.insert(at, point),
        }
        for p in self.points.range_mut(..at) {
            p.accepted = true;
            // A stage of a step end after t is a point of the accepted past.
            if p.superseded_by > t + r {
                p.superseded_by = f64::INFINITY;
            }
        }
        self.accepted_len = self.accepted_len.max(at + 1);
        if completed {
            self.completes_steps = stages_dropped;
            self.completed_once = true;
        }
        if self.points.len() > MAX_HISTORY_POINTS {
            self.pop_oldest();
        }
    }

    /// Drops the points no delayed value at or after `from` (s) needs: all
    /// wholly before `from − tau` but the last of them.
    pub fn trim(&mut self, from: f64) {
        let keep_from = from - self.tau;
        while self.points.len() > 1 && self.points[1].time <= keep_from {
            self.pop_oldest();
        }
    }

    /// Drops the oldest point; the next becomes the oldest accepted one.
    fn pop_oldest(&mut self) {
        self.points.pop_front();
        self.accepted_len = self.accepted_len.saturating_sub(1).max(1);
        if let Some(first) = self.points.front_mut() {
            first.accepted = true;
            first.superseded_by = f64::INFINITY;
        }
    }
}

#[cfg(test)]
mod tests;
