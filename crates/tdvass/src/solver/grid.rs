//! The internal grid of the solver: the step h and how the delay is
//! resolved on it (section 4.1: the step divides tau, or the delay lies
//! inside one step, or it is folded into the plant).
//!
//! Layer: system (docs/architecture.md); it imports the crate's `error`.

use crate::error::{Error, Result};

/// Most grid nodes of delay history kept (8 M nodes, 64 MiB); a delay
/// needing more is refused.
pub const MAX_HISTORY_NODES: u64 = 1 << 23;
/// Delays below this (s) are folded into the plant as
/// `x_t(t − tau) ≈ x_t(t) − tau v_t(t)` (error ≤ tau²/2 |d²x_t/dt²|, below
/// 5e-15 |d²x_t/dt²|) instead of forcing a grid step of tau.
pub const MIN_RESOLVED_DELAY: f64 = 1e-7;

/// How the delay is resolved on the grid (section 4.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DelayRegime {
    /// tau is zero or below [`MIN_RESOLVED_DELAY`]: `x_t(t − tau)` is taken
    /// as `x_t(t)`, the feedback folded into the plant matrix.
    Folded,
    /// `0 < tau < h`: the delayed argument of the first `tau` of each step
    /// lies in the step before (nodes k − 1, k) and that of the rest in the
    /// step itself (nodes k, k + 1); node k + 1 follows from a 2×2 linear
    /// solve. The history keeps the nodes k − 1 and k.
    InsideStep {
        /// The delay tau (s).
        tau: f64,
    },
    /// `tau = m h`: the delayed nodes are `m` whole steps back.
    WholeSteps {
        /// m >= 1.
        m: u64,
    },
}

/// The internal grid: the step and how the delay is resolved on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayGrid {
    /// Internal step h (s).
    pub step: f64,
    /// How the delay lies on the grid.
    pub regime: DelayRegime,
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
                regime: DelayRegime::Folded,
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
                regime: DelayRegime::InsideStep { tau },
            });
        }
        let m = ratio as u64;
        Ok(DelayGrid {
            step: tau / m as f64,
            regime: DelayRegime::WholeSteps { m },
        })
    }

    /// Whether the delay is resolved on the grid (not folded).
    pub fn resolves_delay(&self) -> bool {
        !matches!(self.regime, DelayRegime::Folded)
    }

    /// Whether the delay is shorter than the step.
    pub fn delay_inside_step(&self) -> bool {
        matches!(self.regime, DelayRegime::InsideStep { .. })
    }

    /// How many steps back the history reaches: `m` for whole steps, 1 for
    /// a delay inside the step (nodes k − 1 and k), 0 when folded. The
    /// history holds `delay_steps() + 1` nodes.
    pub fn delay_steps(&self) -> u64 {
        match self.regime {
            DelayRegime::Folded => 0,
            DelayRegime::InsideStep { .. } => 1,
            DelayRegime::WholeSteps { m } => m,
        }
    }

    /// The delay when it lies inside the step, else 0.
    pub fn inner_delay(&self) -> f64 {
        match self.regime {
            DelayRegime::InsideStep { tau } => tau,
            _ => 0.0,
        }
    }
}
