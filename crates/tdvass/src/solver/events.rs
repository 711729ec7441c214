//! Events inside a step: the switches of the switching elements (today
//! the tire's contact), located on the exact partial steps from the
//! committed point (see `contact` for the tire's modes).
//!
//! Each element's switch function φ is the model's
//! ([`Switching::function`](crate::model::dynamics::Switching::function): the tire's contact margin g in contact, −g in
//! flight); the mode switches where φ falls through 0. Over each stretch of [`super::pieces`] up to the
//! step's end node, φ's cubic (from the ends' values and rates) brackets
//! its first fall ([`super::holding::first_fall`]); Newton's method on the
//! exact output, kept inside the bracket by bisection, locates it within
//! [`LOCATION_TOLERANCE`], on the new mode's side. Road breakpoints end
//! the stretches, so a switch is never searched across a kink of the road.
//!
//! Layer: stepping (docs/architecture.md); it imports the solver's
//! `holding`, `pieces`, `stepping` and the crate's `model`, `road`.

use super::holding;
use super::stepping::Stepping;
use crate::model::State;
use crate::model::dynamics::Switch;
use crate::road::RoadPiece;

/// The accuracy to which a switch time is located (s).
pub const LOCATION_TOLERANCE: f64 = 1e-13;

/// Newton (or bisection) iterations at most per switch: from a bracket of
/// a whole step, bisection alone reaches 2^-64 of it.
const LOCATION_ITERATIONS: usize = 64;

impl Stepping<'_> {
    /// The switch function `[φ, φ']` of `switch` in the mode in force at
    /// time t with state x ([`Switching::function`](crate::model::dynamics::Switching::function)); the element switches
    /// where φ falls through 0.
    fn switch_function(&self, switch: Switch, t: f64, x: &State, piece: &RoadPiece) -> [f64; 2] {
        let (road, road_rate) = (piece.value(t), piece.slope(t));
        let switching = &self.modes.grid_step.switching;
        switching.function(switch, self.mode, x.as_slice(), road, road_rate)
    }

    /// The rounding level of `switch`'s φ at state x
    /// ([`Switching::rounding`](crate::model::dynamics::Switching::rounding)): below it a φ of the other sign is taken
    /// for 0.
    fn switch_rounding(&self, switch: Switch, t: f64, x: &State, piece: &RoadPiece) -> f64 {
        let switching = &self.modes.grid_step.switching;
        switching.rounding(switch, x.as_slice(), piece.value(t))
    }

    /// The first switch in grid step k after the committed point among the
    /// elements of [`crate::model::dynamics::SWITCHES`] that apply, searched up to the step's end
    /// node in the current mode: its time and element (`None` if there is
    /// none).
    pub(super) fn next_switch(&mut self, k: u64, from: (f64, State)) -> Option<(f64, Switch)> {
        let mut first: Option<(f64, Switch)> = None;
        let switching = self.modes.grid_step.switching;
        for switch in switching.elements() {
            if let Some(time) = self.next_switch_of(switch, k, from)
                && first.is_none_or(|(earliest, _)| time < earliest)
            {
                first = Some((time, switch));
            }
        }
        first
    }

    /// The first switch of `switch` in grid step k after the committed
    /// point, up to the step's end node (`None` if there is none).
    fn next_switch_of(&mut self, switch: Switch, k: u64, (tc, xc): (f64, State)) -> Option<f64> {
        let node = self.inputs.node_time(k + 1);
        let (mut start, mut x_start) = (tc, xc);
        while start < node {
            let super::pieces::Stretch { piece, end, .. } = self.inputs.stretch(start, node, None);
            let x_end = self.integrate_within_step(k, tc, xc, end);
            let a = self.switch_function(switch, start, &x_start, &piece);
            let b = self.switch_function(switch, end, &x_end, &piece);
            // A start on the other side by rounding only, and leaving it,
            // is a switch just made (or a graze), not a new one.
            let skip_start = start == tc
                && a[0] >= -self.switch_rounding(switch, start, &x_start, &piece)
                && a[1] >= 0.0;
            if let Some([lo, root, hi]) = holding::first_fall(end - start, a, b, skip_start) {
                if hi == 0.0 {
                    return Some(start);
                }
                let bracket = [start + lo, start + root, start + hi];
                if let Some(time) = self.locate_switch(switch, k, (tc, xc), bracket, &piece) {
                    return Some(time);
                }
            }
            (start, x_start) = (end, x_end);
        }
        None
    }

    /// φ at time t in step k on the exact dense output from the committed
    /// point: `[φ, φ']`.
    fn exact_switch_function(
        &mut self,
        switch: Switch,
        k: u64,
        (tc, xc): (f64, State),
        t: f64,
        piece: &RoadPiece,
    ) -> [f64; 2] {
        let x = if t == tc {
            xc
        } else {
            self.integrate_within_step(k, tc, xc, t)
        };
        self.switch_function(switch, t, &x, piece)
    }

    /// The root of φ where the cubic falls through 0, given as `[lo, root,
    /// hi]` (times of step k: the cubic's root and a bracket of it), on the
    /// exact dense output: the first time past it by at most
    /// [`LOCATION_TOLERANCE`] where φ is below 0, so that the new mode
    /// starts on its side; `None` when φ does not fall through 0 there (a
    /// graze).
    ///
    /// The cubic's root is within its error (some 1e-14 m in φ) of the
    /// exact one, so Newton's method from it usually converges in two
    /// steps; otherwise the bracket is checked on the exact output and
    /// narrowed by Newton steps kept inside it by bisection.
    fn locate_switch(
        &mut self,
        switch: Switch,
        k: u64,
        from: (f64, State),
        [lo, root, hi]: [f64; 3],
        piece: &RoadPiece,
    ) -> Option<f64> {
        let mut t = root;
        for _ in 0..2 {
            let [phi, rate] = self.exact_switch_function(switch, k, from, t, piece);
            let next = t - phi / rate;
            if !(rate < 0.0 && next >= lo && next <= hi) {
                break;
            }
            if (next - t).abs() <= 0.25 * LOCATION_TOLERANCE {
                let past = (next + 0.5 * LOCATION_TOLERANCE).min(hi);
                if self.exact_switch_function(switch, k, from, past, piece)[0] < 0.0 {
                    return Some(past);
                }
                break;
            }
            t = next;
        }
        self.locate_switch_in_bracket(switch, k, from, (lo, hi), piece)
    }

    /// [`Self::locate_switch`] from the bracket alone.
    fn locate_switch_in_bracket(
        &mut self,
        switch: Switch,
        k: u64,
        from: (f64, State),
        (mut lo, mut hi): (f64, f64),
        piece: &RoadPiece,
    ) -> Option<f64> {
        let at_lo = self.exact_switch_function(switch, k, from, lo, piece);
        let at_hi = self.exact_switch_function(switch, k, from, hi, piece);
        if at_hi[0] >= 0.0 || at_lo[0] < 0.0 {
            return None;
        }
        // Start from the secant root.
        let mut t = lo + (hi - lo) * at_lo[0] / (at_lo[0] - at_hi[0]);
        for _ in 0..LOCATION_ITERATIONS {
            if hi - lo <= LOCATION_TOLERANCE {
                break;
            }
            if !(t > lo && t < hi) {
                t = 0.5 * (lo + hi);
            }
            let [phi, rate] = self.exact_switch_function(switch, k, from, t, piece);
            if phi < 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let newton = t - phi / rate;
            let step = (newton - t).abs();
            t = newton;
            if step <= 0.25 * LOCATION_TOLERANCE && t > lo && t < hi {
                let past = (t + LOCATION_TOLERANCE / 2.0).min(hi);
                if self.exact_switch_function(switch, k, from, past, piece)[0] < 0.0 {
                    hi = past;
                }
                break;
            }
        }
        Some(hi)
    }
}
