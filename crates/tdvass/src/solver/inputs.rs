//! The inputs of the delay equation (Eq. (2)): the road and the delayed
//! tire displacement, as the stepping layers see them.
//!
//! [`Inputs`] owns
//! - the road, seen as pieces through the one breakpoint rule of
//!   [`super::pieces`] ([`Inputs::piece_from`], [`Inputs::stretch`]);
//! - the delay history: `(x_t, v_t)` at the last `m + 1` grid nodes in a
//!   ring, and the cubic Hermite interpolant of the delayed input over a
//!   step ([`Inputs::delayed_nodes`], [`Inputs::delayed_input`]), with the
//!   constant initial `x_t` before the start;
//! - the harmonic road's phase `A [sin ω t, cos ω t]`, by the policies the
//!   results' bits depend on: at grid node k it is exact at every anchor
//!   node (`k ≡ 0 mod PHASE_ANCHOR`) and rotated over one step from the
//!   node before elsewhere ([`Inputs::node_phase`]); at the start of a
//!   partial step it is that node phase at the grid index's node, the node
//!   phase rotated by `ω tau` at `t_k + tau`, and `sin_cos` elsewhere
//!   ([`Inputs::harmonic_at`]); for the road's value and rate at an
//!   instant, `sin_cos` through a cache of its last four angles
//!   ([`Inputs::road_at`]).
//!
//! It imports the road, the grid, the piece rule, the road generator's
//! rotation and the linear algebra; nothing of the operators, the
//! trajectory or the accumulators.

use super::grid::{DelayGrid, MAX_HISTORY_NODES};
use super::linalg::hermite;
use super::pieces::{self, Stretch};
use super::system::{phase_rotation, rotate};
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::road::piece::harmonic_angle;
use crate::road::{Road, RoadPiece};
use nalgebra::Vector4;

/// The harmonic road's phase `A [sin ω t_k, cos ω t_k]` at grid node k is
/// evaluated exactly at every node `k ≡ 0 (mod PHASE_ANCHOR)` and carried
/// to the following nodes by the rotation over one step (a power of two, so
/// the test is a mask). The rounding drift between anchors stays of the
/// order of PHASE_ANCHOR ulp; the phase is a function of k alone.
pub(super) const PHASE_ANCHOR: u64 = 1024;

/// The inputs (see the module docs). `Clone` copies the history.
#[derive(Debug, Clone)]
pub(super) struct Inputs {
    pub(super) road: Road,
    /// (x_t, v_t) at grid nodes `grid_index − m ..= grid_index`, by
    /// `index % (m + 1)`.
    pub(super) history: Vec<[f64; 2]>,
    /// The grid the history lies on.
    grid: DelayGrid,
    /// t_0 (s): node k lies at `t_0 + k h`.
    start_time: f64,
    /// x_t(t_0) (m): the delayed input before the start.
    initial_tire: f64,
    /// The harmonic road's amplitude (m), angular frequency (rad/s) and
    /// phase (rad); `None` for the other roads.
    harmonic: Option<(f64, f64, f64)>,
    /// [`phase_rotation`] over one step.
    rotation: [[f64; 2]; 2],
    /// The harmonic road's last phases (a cache of `sin_cos`).
    phases: Phases,
    /// Harmonic road phase `(k, A [sin ω t_k, cos ω t_k])` at the last grid
    /// node reached by the whole-step loop: a cache of a function of k
    /// alone (see [`PHASE_ANCHOR`]), so it is not part of the saved state.
    phase: Option<(u64, [f64; 2])>,
}

impl Inputs {
    /// The road of `spec` from `start_time` on and a history at rest at
    /// `(x_t, v_t) = initial_tire` on `grid`.
    pub(super) fn new(
        road: Road,
        grid: DelayGrid,
        start_time: f64,
        initial_tire: [f64; 2],
    ) -> Inputs {
        let harmonic = match road.harmonic() {
            Some(RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
                phase,
            }) => Some((amplitude, angular_frequency, phase)),
            _ => None,
        };
        Inputs {
            road,
            history: vec![initial_tire; grid.delay_steps() as usize + 1],
            grid,
            start_time,
            initial_tire: initial_tire[0],
            harmonic,
            rotation: phase_rotation(harmonic.map_or(0.0, |(_, w, _)| w), grid.step),
            phases: Phases::default(),
            phase: None,
        }
    }

    /// The time of grid node k (s): `t_0 + k h`.
    #[inline]
    pub(super) fn node_time(&self, k: u64) -> f64 {
        self.start_time + k as f64 * self.grid.step
    }

    /// Moves t_0 (the simulator's own start time must move with it): for
    /// tests of states that no simulator reaches.
    #[cfg(test)]
    pub(super) fn move_start_for_tests(&mut self, start_time: f64) {
        self.start_time = start_time;
    }

    /// The angular frequency ω of the harmonic road (0 for the others).
    pub(super) fn angular_frequency(&self) -> f64 {
        self.harmonic.map_or(0.0, |(_, w, _)| w)
    }

    /// The road piece in force from `t` on ([`pieces::piece_from`]).
    #[inline(always)]
    pub(super) fn piece_from(&mut self, t: f64) -> RoadPiece {
        pieces::piece_from(&mut self.road, t, self.grid.step)
    }

    /// The stretch of integration from `start` towards `to`
    /// ([`pieces::stretch`]), ending at `switch` too when given.
    #[inline]
    pub(super) fn stretch(&mut self, start: f64, to: f64, switch: Option<f64>) -> Stretch {
        pieces::stretch(&mut self.road, start, to, switch, self.grid.step)
    }

    /// The road piece over the whole step `[t, to]` if no breakpoint
    /// splits it (the same choice as the stretches); `at_t`:
    /// `road.piece(t)` if already known.
    #[inline(always)]
    pub(super) fn piece_over(
        &mut self,
        t: f64,
        to: f64,
        at_t: Option<RoadPiece>,
    ) -> Option<RoadPiece> {
        let step = self.grid.step;
        let piece = match at_t {
            Some(piece) => pieces::piece_after(&mut self.road, piece, t, step),
            None => pieces::piece_from(&mut self.road, t, step),
        };
        (!pieces::ends_before(&piece, to, step)).then_some(piece)
    }

    /// Writes the delay history ring.
    pub(super) fn write_history(&self, w: &mut ByteWriter) {
        let flat: Vec<f64> = self.history.iter().flatten().copied().collect();
        w.f64s(&flat);
    }

    /// Reads what [`Inputs::write_history`] wrote into a ring of the same
    /// length.
    pub(super) fn read_history(&mut self, r: &mut ByteReader) -> Result<()> {
        let flat = r.f64s(2 * MAX_HISTORY_NODES + 2)?;
        if flat.len() != 2 * self.history.len() {
            return Err(Error::InvalidState(format!(
                "history of {} values where {} were expected",
                flat.len(),
                2 * self.history.len()
            )));
        }
        for (slot, pair) in self.history.iter_mut().zip(flat.chunks(2)) {
            *slot = [pair[0], pair[1]];
        }
        Ok(())
    }

    /// `(x_t, v_t)` at grid node k, from the history ring (k at most `m`
    /// nodes back from the last node recorded).
    #[inline]
    pub(super) fn node_tire(&self, k: u64) -> [f64; 2] {
        self.history[(k % self.history.len() as u64) as usize]
    }

    /// Records node k's `(x_t, v_t)` in the history ring.
    #[inline]
    pub(super) fn record_node(&mut self, k: u64, tire: [f64; 2]) {
        let len = self.history.len() as u64;
        self.history[(k % len) as usize] = tire;
    }

    /// The Hermite nodes `[x_t, v_t, x_t, v_t]` of the delayed input over
    /// grid step k: the history nodes k − m and k − m + 1, or the constant
    /// initial `x_t` before the start.
    #[inline]
    pub(super) fn delayed_nodes(&self, k: u64) -> [f64; 4] {
        let m = self.grid.delay_steps();
        if k < m {
            self.before_start()
        } else {
            let len = self.history.len();
            let first = ((k - m) % len as u64) as usize;
            let second = if first + 1 == len { 0 } else { first + 1 };
            let [x0, v0] = self.history[first];
            let [x1, v1] = self.history[second];
            [x0, v0, x1, v1]
        }
    }

    /// The constant history before the start, as Hermite nodes.
    #[inline]
    pub(super) fn before_start(&self) -> [f64; 4] {
        let x = self.initial_tire;
        [x, 0.0, x, 0.0]
    }

    /// Delayed-input vector `[u, u', u'', u''']` at offset σ into grid
    /// step k.
    #[inline]
    pub(super) fn delayed_input(&self, k: u64, offset: f64) -> Vector4<f64> {
        hermite(self.delayed_nodes(k), self.grid.step, offset)
    }

    /// `A [sin ω t_k, cos ω t_k]` of the harmonic road, evaluated directly.
    #[inline]
    pub(super) fn exact_phase(&self, k: u64) -> [f64; 2] {
        let Some((amplitude, angular_frequency, phase)) = self.harmonic else {
            return [0.0; 2];
        };
        let angle = harmonic_angle(angular_frequency, phase, self.node_time(k));
        let (sin, cos) = crate::math::sin_cos(angle);
        [amplitude * sin, amplitude * cos]
    }

    /// The harmonic road phase at grid node k as the whole-step loop
    /// carries it: exact at the last anchor node, then rotated.
    #[inline]
    pub(super) fn harmonic_phase(&self, k: u64) -> [f64; 2] {
        if let Some((index, z)) = self.phase
            && index == k
        {
            return z;
        }
        let anchor = k - k % PHASE_ANCHOR;
        let mut z = self.exact_phase(anchor);
        for _ in anchor..k {
            z = rotate(&self.rotation, z);
        }
        z
    }

    /// [`Self::harmonic_phase`] at node k, kept for the whole-step loop
    /// (the same value).
    #[inline]
    pub(super) fn node_phase(&mut self, k: u64) -> [f64; 2] {
        let z = self.harmonic_phase(k);
        self.phase = Some((k, z));
        z
    }

    /// Keeps the phase `z` of node k, as the whole-step loop carried it.
    #[inline]
    pub(super) fn keep_node_phase(&mut self, k: u64, z: [f64; 2]) {
        self.phase = Some((k, z));
    }

    /// The kept phase of node k, if the last one kept is k's.
    #[inline]
    pub(super) fn kept_node_phase(&self, k: u64) -> Option<[f64; 2]> {
        self.phase.and_then(|(index, z)| (index == k).then_some(z))
    }

    /// The harmonic road's `A [sin ω t, cos ω t]` at the start `t` of a
    /// partial step in grid step k (`road`: the piece that drives it). At
    /// node k it is the phase the whole-step loop carries
    /// ([`Self::harmonic_phase`]), and at `tau` after it (the delay inside
    /// the step) that phase rotated by `ω tau`: the pieces of a step start
    /// there, and each point inside it asks again. Elsewhere `sin_cos` (its
    /// last four values kept). Each is a function of `t` and k alone.
    pub(super) fn harmonic_at(&mut self, road: &RoadPiece, t: f64, k: u64) -> [f64; 2] {
        let RoadPiece::Harmonic {
            amplitude,
            angular_frequency,
            phase,
        } = *road
        else {
            return [0.0; 2];
        };
        let node = self.node_time(k);
        if t == node {
            return self.node_phase(k);
        }
        if self.grid.delay_inside_step() && t == node + self.grid.inner_delay() {
            let [z0, z1] = self.node_phase(k);
            let (s, c) = self
                .phases
                .sin_cos(angular_frequency * self.grid.inner_delay());
            return [c * z0 + s * z1, c * z1 - s * z0];
        }
        let (sin, cos) = self
            .phases
            .sin_cos(harmonic_angle(angular_frequency, phase, t));
        [amplitude * sin, amplitude * cos]
    }

    /// `[x_g, dx_g/dt]` of `piece` at `t`: [`RoadPiece::value`] and
    /// [`RoadPiece::slope`] to the bit, the harmonic road's `sin` and `cos`
    /// from the kept `sin_cos` (one evaluation serves both, and the other
    /// users of the same instant).
    #[inline]
    pub(super) fn road_at(&mut self, piece: &RoadPiece, t: f64) -> [f64; 2] {
        match *piece {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
                phase,
            } => {
                let angle = harmonic_angle(angular_frequency, phase, t);
                let (sin, cos) = self.phases.sin_cos(angle);
                [amplitude * sin, amplitude * angular_frequency * cos]
            }
            RoadPiece::Linear { .. } => [piece.value(t), piece.slope(t)],
        }
    }
}

/// The last four `(sin, cos)` of [`crate::math::sin_cos`] by their
/// angle's bits: the points inside a step ask for the same few angles
/// again (`ω tau`, the committed time's).
#[derive(Debug, Clone, Copy)]
pub(super) struct Phases([(u64, (f64, f64)); 4]);

impl Default for Phases {
    fn default() -> Self {
        Phases([(f64::NAN.to_bits(), (f64::NAN, f64::NAN)); 4])
    }
}

impl Phases {
    /// `sin_cos(angle)`, the same to the bit.
    #[inline]
    pub(super) fn sin_cos(&mut self, angle: f64) -> (f64, f64) {
        let bits = angle.to_bits();
        if let Some((_, value)) = self.0.iter().find(|(b, _)| *b == bits) {
            return *value;
        }
        let value = crate::math::sin_cos(angle);
        self.0 = [self.0[1], self.0[2], self.0[3], (bits, value)];
        value
    }
}
