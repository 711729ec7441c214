//! The delay history of Model Exchange: `(x_t, v_t)` at the instants a
//! master evaluated the derivatives, and the delayed wheel displacement
//! `x_t(t − tau)` interpolated from them.
//!
//! A Model Exchange master drives the model by setting a time and states
//! and asking for derivatives; only some masters say which of those points
//! their integrator kept (`CompletedIntegratorStep`), and some ask for
//! derivatives past the time they return to. The history therefore keeps
//! every evaluated point and tells two kinds apart:
//! - **accepted** points: the start, completed integrator steps and events.
//!   The standard lets no master go back before them, so they stay;
//! - **trial** points: every other derivative evaluation. When the time
//!   moves back (a rejected step, a master stepping back to an output
//!   time), the trial points at and after the new time are dropped, so the
//!   history holds only the last attempt at every instant.
//!
//! **Interpolation.** The delayed value at `s = t − tau` is the cubic
//! Hermite interpolant, through positions and velocities, of the two
//! points about s. Where s lies past the last point before t (a delay
//! shorter than the master's step) the right end is the current state
//! `(t, x_t, v_t)` itself: the history is interpolated towards the present,
//! never extrapolated. Before the start time the delayed value is the
//! initial `x_t`, the co-simulation's initial history. With these rules
//! the delayed value at a point depends on the points evaluated before it,
//! never on whether the master called `CompletedIntegratorStep`.
//!
//! **Memory.** Points older than `max(last accepted, latest − TRIAL_REACH)
//! − tau` are dropped, all but the one before that time; at most
//! [`MAX_HISTORY_POINTS`] are kept (the oldest give way).

use std::collections::VecDeque;

/// How far back (s) a master that never completes a step may move the
/// time, from the latest point, without losing a point the delayed value
/// needs.
pub const TRIAL_REACH: f64 = 0.1;

/// Most points kept (32 MiB).
pub const MAX_HISTORY_POINTS: usize = 1 << 20;

/// Points room is made for at the start, and kept through copies and
/// restored states: a master that completes its steps needs about
/// tau / step + 2, one that never does about (tau + [`TRIAL_REACH`]) /
/// step, so a real-time master's evaluations do not allocate.
const INITIAL_CAPACITY: usize = 1024;

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
}

/// The history of `(x_t, v_t)`; see the module documentation.
#[derive(Debug, PartialEq)]
pub struct DelayHistory {
    /// Increasing in time.
    points: VecDeque<HistoryPoint>,
    /// t_0 (s).
    start_time: f64,
    /// x_t(t_0) (m): the delayed value before the start.
    initial_position: f64,
    /// tau (s), > 0.
    tau: f64,
}

/// A copy keeps the room of the original (at least `INITIAL_CAPACITY`
/// points), so a restored FMU state records points without allocating.
impl Clone for DelayHistory {
    fn clone(&self) -> DelayHistory {
        let mut points = VecDeque::with_capacity(self.points.capacity().max(INITIAL_CAPACITY));
        points.extend(self.points.iter().copied());
        DelayHistory {
            points,
            start_time: self.start_time,
            initial_position: self.initial_position,
            tau: self.tau,
        }
    }
}

/// `p(s)` of the cubic through `(t0, x0, v0)` and `(t1, x1, v1)`, `t0 < t1`.
fn hermite(s: f64, (t0, x0, v0): (f64, f64, f64), (t1, x1, v1): (f64, f64, f64)) -> f64 {
    let h = t1 - t0;
    let theta = (s - t0) / h;
    let rest = 1.0 - theta;
    x0 * (1.0 + 2.0 * theta) * rest * rest
        + h * v0 * theta * rest * rest
        + x1 * theta * theta * (3.0 - 2.0 * theta)
        - h * v1 * theta * theta * rest
}

impl DelayHistory {
    /// A history with the accepted start point `(t_0, x_t, v_t)` and delay
    /// `tau` (s, > 0).
    pub fn new(start_time: f64, position: f64, velocity: f64, tau: f64) -> DelayHistory {
        let mut points = VecDeque::with_capacity(INITIAL_CAPACITY);
        points.push_back(HistoryPoint {
            time: start_time,
            position,
            velocity,
            accepted: true,
        });
        DelayHistory {
            points,
            start_time,
            initial_position: position,
            tau,
        }
    }

    /// A history of `points` (restored from a saved state), checked: times
    /// finite, increasing and not before `start_time`, values finite, the
    /// first point accepted.
    pub fn from_points(
        start_time: f64,
        initial_position: f64,
        tau: f64,
        points: Vec<HistoryPoint>,
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
            start_time,
            initial_position,
            tau,
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

    /// The points, oldest first.
    pub fn points(&self) -> impl ExactSizeIterator<Item = &HistoryPoint> {
        self.points.iter()
    }

    /// The time of the last accepted point (s).
    pub fn accepted_time(&self) -> f64 {
        self.points
            .iter()
            .rev()
            .find(|p| p.accepted)
            .map_or(self.start_time, |p| p.time)
    }

    /// `x_t(t − tau)` (m) for the current point `now = (t, x_t, v_t)`: the
    /// Hermite interpolant of the points before t and `now` (module
    /// documentation). Points at or after t are not used.
    pub fn delayed(&self, (t, position, velocity): (f64, f64, f64)) -> f64 {
        let s = t - self.tau;
        if s < self.start_time {
            return self.initial_position;
        }
        let after = self.points.partition_point(|p| p.time <= s);
        if after == 0 {
            // Only after the bound on the number of points dropped the
            // point before s: the oldest point held.
            return self.points.front().map_or(position, |p| p.position);
        }
        let left = self.points[after - 1];
        if left.time == s {
            return left.position;
        }
        let right = match self.points.get(after) {
            Some(p) if p.time < t => (p.time, p.position, p.velocity),
            _ => (t, position, velocity),
        };
        hermite(s, (left.time, left.position, left.velocity), right)
    }

    /// Records the point `(t, x_t, v_t)`: the trial points at and after t
    /// are dropped first (the time moved back, or the same instant is
    /// evaluated again); an accepted point at t takes the new values.
    /// `accepted` marks it (and every point before it) accepted.
    pub fn record(&mut self, (t, position, velocity): (f64, f64, f64), accepted: bool) {
        while let Some(last) = self.points.back() {
            if last.time >= t && !last.accepted {
                self.points.pop_back();
            } else {
                break;
            }
        }
        match self.points.back_mut() {
            Some(last) if last.time == t => {
                last.position = position;
                last.velocity = velocity;
                last.accepted |= accepted;
            }
            Some(last) if last.time > t => {
                // An accepted point after t: the caller refuses such times
                // (`ModelExchange::set_time`); nothing is recorded.
            }
            _ => self.points.push_back(HistoryPoint {
                time: t,
                position,
                velocity,
                accepted,
            }),
        }
        if accepted {
            for p in self.points.iter_mut().rev().skip(1) {
                if p.accepted {
                    break;
                }
                p.accepted = true;
            }
        }
        self.trim();
    }

    /// Drops the points no delayed value can need any more (module
    /// documentation).
    fn trim(&mut self) {
        let latest = self.points.back().map_or(self.start_time, |p| p.time);
        let keep_from = self.accepted_time().max(latest - TRIAL_REACH) - self.tau;
        while (self.points.len() > 1 && self.points[1].time <= keep_from)
            || self.points.len() > MAX_HISTORY_POINTS
        {
            self.points.pop_front();
            // No master goes back this far: the oldest point stays.
            if let Some(first) = self.points.front_mut() {
                first.accepted = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(t: f64) -> (f64, f64, f64) {
        (t, (3.0 * t).sin(), 3.0 * (3.0 * t).cos())
    }

    #[test]
    fn before_the_start_the_initial_position_is_held() {
        let h = DelayHistory::new(1.0, 0.5, 2.0, 0.1);
        assert_eq!(h.delayed((1.05, 9.0, 9.0)), 0.5);
    }

    #[test]
    fn a_delay_shorter_than_the_step_interpolates_towards_the_current_state() {
        let tau = 2e-4;
        let mut h = DelayHistory::new(0.0, 0.0, 3.0, tau);
        let mut t = 0.0;
        while t < 0.5 {
            t += 1e-3;
            h.record(sine(t), true);
        }
        let now = sine(t + 1e-3);
        let exact = (3.0 * (now.0 - tau)).sin();
        let error = (h.delayed(now) - exact).abs();
        assert!(error < 1e-10, "{error}");
        // Extrapolating from the last point alone would be far off.
        assert!((h.points.back().unwrap().position - exact).abs() > 1e-4);
    }

    #[test]
    fn hermite_interpolation_is_fourth_order() {
        let tau = 0.011;
        let error = |step: f64| {
            let mut h = DelayHistory::new(0.0, 0.0, 3.0, tau);
            let mut t = 0.0;
            while t < 0.3 {
                t += step;
                h.record(sine(t), false);
            }
            let now = sine(t + 0.37 * step);
            (h.delayed(now) - (3.0 * (now.0 - tau)).sin()).abs()
        };
        let (coarse, fine) = (error(4e-3), error(2e-3));
        assert!(coarse / fine > 12.0, "{coarse} {fine}");
    }

    #[test]
    fn time_moving_back_drops_the_trial_points_after_it_and_keeps_the_accepted_ones() {
        let mut h = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
        h.record((0.1, 1.0, 0.0), true);
        h.record((0.2, 2.0, 0.0), false);
        h.record((0.3, 3.0, 0.0), false);
        h.record((0.15, 1.5, 0.0), false);
        let times: Vec<f64> = h.points().map(|p| p.time).collect();
        assert_eq!(times, [0.0, 0.1, 0.15]);
        // The same instant again replaces the point.
        h.record((0.15, 7.0, 0.0), false);
        assert_eq!(h.points().last().unwrap().position, 7.0);
        assert_eq!(h.accepted_time(), 0.1);
        // Accepting a point accepts the trial points before it.
        h.record((0.2, 2.0, 0.0), true);
        assert!(h.points().all(|p| p.accepted));
    }

    #[test]
    fn the_values_do_not_depend_on_which_points_were_accepted() {
        let run = |accept_every: usize| {
            let mut h = DelayHistory::new(0.0, 0.0, 3.0, 0.011);
            let mut values = Vec::new();
            for i in 1..400 {
                let t = i as f64 * 7e-4;
                // A trial past the point, then the point itself.
                h.record(sine(t + 3e-4), false);
                values.push(h.delayed(sine(t)));
                h.record(sine(t), accept_every > 0 && i % accept_every == 0);
            }
            values
        };
        assert_eq!(run(1), run(0));
        assert_eq!(run(1), run(10));
    }

    #[test]
    fn old_points_are_dropped() {
        let mut h = DelayHistory::new(0.0, 0.0, 3.0, 0.01);
        for i in 1..100_000 {
            h.record(sine(i as f64 * 1e-4), true);
        }
        // tau / step + the one before.
        assert!(h.points.len() <= 102, "{}", h.points.len());
        let never = {
            let mut h = DelayHistory::new(0.0, 0.0, 3.0, 0.01);
            for i in 1..100_000 {
                h.record(sine(i as f64 * 1e-4), false);
            }
            h.points.len()
        };
        assert!(never <= 1102, "{never}");
    }

    #[test]
    fn restored_points_are_checked() {
        let p = |time, accepted| HistoryPoint {
            time,
            position: 0.0,
            velocity: 0.0,
            accepted,
        };
        assert!(
            DelayHistory::from_points(0.0, 0.0, 0.1, vec![p(0.0, true), p(0.1, false)]).is_ok()
        );
        assert!(DelayHistory::from_points(0.0, 0.0, 0.1, vec![]).is_err());
        assert!(DelayHistory::from_points(0.0, 0.0, 0.1, vec![p(0.0, false)]).is_err());
        assert!(
            DelayHistory::from_points(0.0, 0.0, 0.1, vec![p(0.0, true), p(0.0, false)]).is_err()
        );
        assert!(DelayHistory::from_points(0.0, 0.0, 0.1, vec![p(-1.0, true)]).is_err());
    }
}
