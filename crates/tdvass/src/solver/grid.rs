//! The internal grid of the solver: the step h and how the delay is
//! resolved on it (section 4.1: the step divides tau, or the delay lies
//! inside one step, or it is folded into the plant).

use super::{MAX_HISTORY_NODES, MIN_RESOLVED_DELAY};
use crate::error::{Error, Result};

/// How the delay is resolved on the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayGrid {
    /// Internal step h (s).
    pub step: f64,
    /// The delayed nodes are `m` steps back: `tau = m h` for a delay of at
    /// least one step, `m = 1` for a delay shorter than a step (see
    /// `inner_delay`), 0 when the delay is folded into the plant.
    pub delay_steps: u64,
    /// The delay when it is shorter than the step (`0 < tau < h`), else 0.
    /// Then the delayed argument of the first `tau` of each step lies in the
    /// step before (nodes k − 1, k) and that of the rest in the step itself
    /// (nodes k, k + 1): node k + 1 follows from a 2×2 linear solve.
    pub inner_delay: f64,
}

impl DelayGrid {
    /// `h = tau / m` with `m = ceil(tau / h_max)` when `tau >= h_max`;
    /// `h = h_max` with the delay inside the step when
    /// [`MIN_RESOLVED_DELAY`] `<= tau < h_max`; `h = h_max` with the delay
    /// folded when tau is zero or below [`MIN_RESOLVED_DELAY`].
    pub fn new(tau: f64, max_internal_step: f64) -> Result<DelayGrid> {
        if !(max_internal_step.is_finite() && max_internal_step > 0.0) {
            return Err(Error::InvalidParameter {
                name: "max_internal_step",
                value: max_internal_step,
                reason: "must be finite and > 0",
            });
        }
        if !(tau.is_finite() && tau >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                reason: "the delay must be finite and >= 0",
            });
        }
        if tau < MIN_RESOLVED_DELAY {
            return Ok(DelayGrid {
                step: max_internal_step,
                delay_steps: 0,
                inner_delay: 0.0,
            });
        }
        let ratio = (tau / max_internal_step * (1.0 - 1e-12)).ceil().max(1.0);
        if ratio > MAX_HISTORY_NODES as f64 {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                reason: "the delay needs more than 8388608 history nodes at this max_internal_step",
            });
        }
        if ratio == 1.0 && tau < max_internal_step * (1.0 - 1e-12) {
            return Ok(DelayGrid {
                step: max_internal_step,
                delay_steps: 1,
                inner_delay: tau,
            });
        }
        let delay_steps = ratio as u64;
        Ok(DelayGrid {
            step: tau / delay_steps as f64,
            delay_steps,
            inner_delay: 0.0,
        })
    }

    /// Whether the delay is resolved on the grid (not folded).
    pub fn resolves_delay(&self) -> bool {
        self.delay_steps > 0
    }

    /// Whether the delay is shorter than the step (see `inner_delay`).
    pub fn delay_inside_step(&self) -> bool {
        self.inner_delay > 0.0
    }
}
