//! The fine (precise) integration method for the delay equation of Eq. (2),
//! `dX/dt = A X + b x_t(t − tau) + e x_g(t)`, section 4.1.
//!
//! Over a step of length δ starting at `a`, Eq. (23) gives
//! `X(a+δ) = e^{Aδ} X(a) + ∫_0^δ e^{A(δ−s)} [b u(a+s) + e x_g(a+s)] ds`.
//! The integral is exact here because both inputs have closed forms over
//! the step:
//! - the delayed tire displacement `u = x_t(t − tau)` is the cubic Hermite
//!   interpolant of `x_t` and its derivative `v_t` (a state) at the grid
//!   nodes one delay earlier (the grid step divides tau exactly), so the
//!   method is fourth-order accurate in the step; a delay shorter than the
//!   step bound keeps the step and splits it at tau, the end node of the
//!   step entering its own interpolant through a 2×2 solve
//!   ([`DelayGrid::inner_delay`]);
//! - the road is a sine (an exosystem) or a straight line (see
//!   [`crate::road`]).
//!
//! All the step matrices come from one exponential of an augmented matrix
//! (the plant plus the input generators), computed by the 2^N algorithm in
//! [`expm::precise_exp`].
//!
//! **Caller independence.** States are committed only on an internal grid
//! anchored at the start time (`t_k = t_0 + k h`); road breakpoints inside a
//! step split it internally. A time between grid nodes is reached by a dense
//! output from the last grid node that is not committed. So how a caller
//! splits an interval does not change any result: outputs agree bit for bit.
//! An external road input (`RoadSpec::Input`) is the exception: the state is
//! committed where the input changes.
//!
//! **Hot path.** From a committed grid node, [`Simulator::advance_to`] runs
//! every whole step the call reaches in one loop (see BENCHMARKS.md): the
//! delayed input acts on the two history nodes through `Γ_u H`
//! precomputed, the harmonic road phase is rotated from node to node
//! (exact every `PHASE_ANCHOR` = 1024 nodes), a linear road piece gives
//! `x_g` from the node index until the piece ends, and BA, SDD, TDD go
//! straight into the RMS sums. Each node's state, phase and sums are functions of its
//! index alone, so splits and `to_bytes`/`from_bytes` stay bit-identical
//! (unit tests at the end of this file).

pub mod expm;
mod persist;
mod time_average;

use crate::error::{Error, Result};
use crate::metrics::{RmsValues, RunningRms, Weights};
use crate::model::{Params, Performance, Plant, State, V_T, Variant, X_S, X_T};
use crate::road::{Road, RoadPiece, RoadSpec};
use nalgebra::{Matrix2, Matrix4, Matrix6, SMatrix, Vector2, Vector4};
use std::collections::HashMap;
use time_average::SquareIntegral;

/// Default upper bound of the internal step (s).
pub const DEFAULT_MAX_INTERNAL_STEP: f64 = 1e-4;
/// Most grid nodes of delay history kept (8 M nodes, 64 MiB); a delay
/// needing more is refused.
pub const MAX_HISTORY_NODES: u64 = 1 << 23;
/// Rounding drift covered by the snap tolerance, in additions: a time
/// accumulated as `t += step` over N steps is off by at most `N ε |t| / 2`,
/// so `2^22 ε |t|` covers 2^22 steps with a factor 2 to spare (1.4e-8 s at
/// t = 15 s).
const SNAPPED_ADDITIONS: f64 = 4_194_304.0;
/// The snap tolerance never exceeds this fraction of the internal step
/// (2^-10: 1e-7 s at the default step, far below any time scale of the
/// model or its roads).
const SNAP_STEP_FRACTION: f64 = 1.0 / 1024.0;
/// Delays below this (s) are folded into the plant as
/// `x_t(t − tau) ≈ x_t(t) − tau v_t(t)` (error ≤ tau²/2 |d²x_t/dt²|, below
/// 5e-15 |d²x_t/dt²|) instead of forcing a grid step of tau.
pub const MIN_RESOLVED_DELAY: f64 = 1e-7;
/// Displacement bound (m): beyond it the run is declared divergent.
pub const DIVERGENCE_DISPLACEMENT: f64 = 1e3;
/// Velocity bound (m/s): beyond it the run is declared divergent.
pub const DIVERGENCE_VELOCITY: f64 = 1e6;
/// Cached operators for partial steps (the cache is cleared when full).
const OPERATOR_CACHE_SIZE: usize = 512;
/// Resolution of partial step lengths: 2^-40 of the grid step.
const PARTIAL_STEP_RESOLUTION: f64 = 1099511627776.0;
/// The harmonic road's phase `A [sin ω t_k, cos ω t_k]` at grid node k is
/// evaluated exactly at every node `k ≡ 0 (mod PHASE_ANCHOR)` and carried
/// to the following nodes by the rotation over one step (a power of two, so
/// the test is a mask). The rounding drift between anchors stays of the
/// order of PHASE_ANCHOR ulp; the phase is a function of k alone.
const PHASE_ANCHOR: u64 = 1024;
/// Divergence bounds in state order.
const DIVERGENCE_BOUNDS: [f64; 6] = [
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
];

/// Everything that defines a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Physical and controller parameters.
    pub params: Params,
    /// CS, PVASS or TDVASS.
    pub variant: Variant,
    /// The road.
    pub road: RoadSpec,
    /// Upper bound of the internal step (s).
    pub max_internal_step: f64,
    /// Start time t_0 (s).
    pub start_time: f64,
    /// X(t_0) = [x_s, v_s, x_h, v_h, x_t, v_t]; also the history for t < t_0.
    pub initial_state: State,
    /// Weights of the objective J.
    pub weights: Weights,
}

impl Default for SimulationConfig {
    /// TDVASS, Table 1, (g1, tau1), the harmonic road 0.05 sin 5t, from rest.
    fn default() -> Self {
        SimulationConfig {
            params: Params::default(),
            variant: Variant::Tdvass,
            road: RoadSpec::paper_harmonic(),
            max_internal_step: DEFAULT_MAX_INTERNAL_STEP,
            start_time: 0.0,
            initial_state: State::zeros(),
            weights: Weights::default(),
        }
    }
}

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

/// Dimension of the augmented system: plant (6), cubic delayed input (4),
/// linear road (2), harmonic road (2).
const AUGMENTED: usize = 14;
const DELAY_INPUT: usize = 6;
const LINEAR_ROAD: usize = 10;
const HARMONIC_ROAD: usize = 12;

/// The exact map of one step of length δ:
/// `X(a+δ) = Φ X(a) + Γ_u p + Γ_l q + Γ_h z`, where
/// `p = [u, u', u'', u'''](a)` (delayed tire displacement and derivatives),
/// `q = [x_g, x_g'](a)` (linear road), `z = A_r [sin ω a, cos ω a]` (harmonic).
#[derive(Debug, Clone, PartialEq)]
struct StepOperator {
    transition: Matrix6<f64>,
    delayed_input: SMatrix<f64, 6, 4>,
    linear_road: SMatrix<f64, 6, 2>,
    harmonic_road: SMatrix<f64, 6, 2>,
}

impl StepOperator {
    fn new(a: &Matrix6<f64>, b: &State, e: &State, angular_frequency: f64, length: f64) -> Self {
        let mut m = SMatrix::<f64, AUGMENTED, AUGMENTED>::zeros();
        m.fixed_view_mut::<6, 6>(0, 0).copy_from(a);
        m.fixed_view_mut::<6, 1>(0, DELAY_INPUT).copy_from(b);
        for i in 0..3 {
            m[(DELAY_INPUT + i, DELAY_INPUT + i + 1)] = 1.0;
        }
        m.fixed_view_mut::<6, 1>(0, LINEAR_ROAD).copy_from(e);
        m[(LINEAR_ROAD, LINEAR_ROAD + 1)] = 1.0;
        m.fixed_view_mut::<6, 1>(0, HARMONIC_ROAD).copy_from(e);
        m[(HARMONIC_ROAD, HARMONIC_ROAD + 1)] = angular_frequency;
        m[(HARMONIC_ROAD + 1, HARMONIC_ROAD)] = -angular_frequency;
        let exp = expm::precise_exp(&(m * length));
        StepOperator {
            transition: exp.fixed_view::<6, 6>(0, 0).into_owned(),
            delayed_input: exp.fixed_view::<6, 4>(0, DELAY_INPUT).into_owned(),
            linear_road: exp.fixed_view::<6, 2>(0, LINEAR_ROAD).into_owned(),
            harmonic_road: exp.fixed_view::<6, 2>(0, HARMONIC_ROAD).into_owned(),
        }
    }

    #[inline]
    fn apply(&self, x: &State, delayed: Option<&Vector4<f64>>, road: &RoadPiece, at: f64) -> State {
        let mut next = self.transition * x;
        if let Some(p) = delayed {
            next += self.delayed_input * p;
        }
        match *road {
            RoadPiece::Linear { .. } => {
                next += self.linear_road * Vector2::new(road.value(at), road.slope(at));
            }
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                let (sin, cos) = (angular_frequency * at).sin_cos();
                next += self.harmonic_road * Vector2::new(amplitude * sin, amplitude * cos);
            }
        }
        next
    }
}

/// Cubic Hermite interpolant of `x_t` over one grid interval of length h:
/// `[u, u', u'', u''']` at offset σ.
#[inline]
fn hermite(nodes: [f64; 4], h: f64, offset: f64) -> Vector4<f64> {
    let [x0, v0, x1, v1] = nodes;
    let slope = (x1 - x0) / h;
    let c2 = (3.0 * slope - 2.0 * v0 - v1) / h;
    let c3 = (v0 + v1 - 2.0 * slope) / (h * h);
    let s = offset;
    Vector4::new(
        x0 + s * (v0 + s * (c2 + s * c3)),
        v0 + s * (2.0 * c2 + 3.0 * c3 * s),
        2.0 * c2 + 6.0 * c3 * s,
        6.0 * c3,
    )
}

/// The 4×4 matrix of [`hermite`]: `[u, u', u'', u''']` at offset σ is
/// `hermite_matrix(h, σ) [x_0, v_0, x_1, v_1]`.
fn hermite_matrix(h: f64, offset: f64) -> Matrix4<f64> {
    Matrix4::from_fn(|i, j| {
        let mut nodes = [0.0; 4];
        nodes[j] = 1.0;
        hermite(nodes, h, offset)[i]
    })
}

/// `C`: the 2×6 map from X to a history node `(x_t, v_t)`.
fn tire_pick() -> SMatrix<f64, 2, 6> {
    let mut pick = SMatrix::<f64, 2, 6>::zeros();
    pick[(0, X_T)] = 1.0;
    pick[(1, V_T)] = 1.0;
    pick
}

/// Columns of a 6-row matrix, stored as plain arrays for the hot loop.
type Columns<const N: usize> = [[f64; 6]; N];

fn columns<const C: usize>(m: &SMatrix<f64, 6, C>) -> Columns<C> {
    std::array::from_fn(|j| std::array::from_fn(|i| m[(i, j)]))
}

/// `Σ_j cols[j] v[j]` for six columns, summed pairwise so that the
/// dependency chain is short.
#[inline(always)]
fn combine6(c: &Columns<6>, v: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| {
        ((c[0][i] * v[0] + c[1][i] * v[1]) + (c[2][i] * v[2] + c[3][i] * v[3]))
            + (c[4][i] * v[4] + c[5][i] * v[5])
    })
}

/// `Σ_j cols[j] v[j]` for four columns, summed pairwise.
#[inline(always)]
fn combine4(c: &Columns<4>, v: &[f64; 4]) -> [f64; 6] {
    std::array::from_fn(|i| (c[0][i] * v[0] + c[1][i] * v[1]) + (c[2][i] * v[2] + c[3][i] * v[3]))
}

/// `cols[0] v[0] + cols[1] v[1]`.
#[inline(always)]
fn combine2(c: &Columns<2>, v: &[f64; 2]) -> [f64; 6] {
    std::array::from_fn(|i| c[0][i] * v[0] + c[1][i] * v[1])
}

#[inline(always)]
fn add6(a: [f64; 6], b: [f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| a[i] + b[i])
}

/// The exact map of one whole grid step from a grid node, in the form the
/// hot loop uses. At offset 0 over a whole step the Hermite vector is linear
/// in the two history nodes, `p = H [x_0, v_0, x_1, v_1]`, so the delayed
/// input acts through `Γ_u H` directly on the nodes (no division per step).
#[derive(Debug, Clone, PartialEq)]
struct GridStep {
    /// Columns of Φ.
    transition: Columns<6>,
    /// Columns of `Γ_u H`, acting on `[x_t, v_t](k − m)`, `[x_t, v_t](k − m + 1)`.
    nodes: Columns<4>,
    /// Columns of `Γ_h`, acting on `A [sin ω t_k, cos ω t_k]`.
    harmonic: Columns<2>,
    /// Columns of `Γ_l`, acting on `[x_g, x_g'](t_k)`.
    linear: Columns<2>,
    /// The road phase rotation over one step, `z' = r_1 z + r_2 swap(z)` with
    /// `r_1 = [cos ω h, cos ω h]`, `r_2 = [sin ω h, −sin ω h]`.
    rotation: [[f64; 2]; 2],
    /// Columns of the 2×6 map from X to `[BA, SDD]` (row V_S of A, and
    /// `x_s − x_t`).
    outputs: [[f64; 2]; 6],
}

impl GridStep {
    fn new(op: &StepOperator, a: &Matrix6<f64>, angular_frequency: f64, h: f64) -> GridStep {
        // [u, u', u'', u'''] at the start of the Hermite interpolant of
        // (x0, v0) and (x1, v1) over [0, h].
        let (h2, h3) = (h * h, h * h * h);
        #[rustfmt::skip]
        let hermite = nalgebra::Matrix4::new(
            1.0, 0.0, 0.0, 0.0,
            0.0, 1.0, 0.0, 0.0,
            -6.0 / h2, -4.0 / h, 6.0 / h2, -2.0 / h,
            12.0 / h3, 6.0 / h2, -12.0 / h3, 6.0 / h2,
        );
        Self::from_matrices(
            &op.transition,
            &(op.delayed_input * hermite),
            op,
            a,
            angular_frequency,
            h,
        )
    }

    /// The whole step when the delay `tau` is shorter than the step h
    /// ([`DelayGrid::inner_delay`]). Over `[t_k, t_k + tau)` the delayed
    /// argument lies in step k − 1 (Hermite offsets from `h − tau`), over
    /// `[t_k + tau, t_{k+1})` in step k itself (offsets from 0), so
    /// `X_{k+1} = Φ X_k + D_1 n_{k−1,k} + D_2 n_{k,k+1} + road` with
    /// `D_1 = Φ(h − tau) Γ_u(tau) H(h − tau)` and `D_2 = Γ_u(h − tau) H(0)`.
    /// Node k + 1 appears on both sides through its `(x_t, v_t) = C X_{k+1}`;
    /// with `S = (I − D_2'' C)^{-1}` (`D_2''` the columns acting on node
    /// k + 1, `D_2'` those on node k) the explicit step is
    /// `X_{k+1} = S (Φ + D_2' C) X_k + S D_1 n_{k−1,k} + S road`.
    /// `None` when `I − D_2'' C` is singular.
    fn inner_delay(
        whole: &StepOperator,
        parts: [&StepOperator; 2],
        a: &Matrix6<f64>,
        angular_frequency: f64,
        h: f64,
        tau: f64,
    ) -> Option<GridStep> {
        let [first, rest] = parts;
        let earlier = rest.transition * first.delayed_input * hermite_matrix(h, h - tau);
        let current = rest.delayed_input * hermite_matrix(h, 0.0);
        let pick = tire_pick();
        let implicit = Matrix6::identity() - current.fixed_view::<6, 2>(0, 2) * pick;
        let solve = implicit.try_inverse()?;
        let scaled = StepOperator {
            transition: solve * (whole.transition + current.fixed_view::<6, 2>(0, 0) * pick),
            delayed_input: solve * earlier,
            linear_road: solve * whole.linear_road,
            harmonic_road: solve * whole.harmonic_road,
        };
        Some(Self::from_matrices(
            &scaled.transition,
            &scaled.delayed_input,
            &scaled,
            a,
            angular_frequency,
            h,
        ))
    }

    /// `nodes`: the 6×4 map from the two history nodes to the state; the
    /// road columns come from `road`.
    fn from_matrices(
        transition: &Matrix6<f64>,
        nodes: &SMatrix<f64, 6, 4>,
        road: &StepOperator,
        a: &Matrix6<f64>,
        angular_frequency: f64,
        h: f64,
    ) -> GridStep {
        let (sin, cos) = (angular_frequency * h).sin_cos();
        GridStep {
            transition: columns(transition),
            nodes: columns(nodes),
            harmonic: columns(&road.harmonic_road),
            linear: columns(&road.linear_road),
            rotation: [[cos, cos], [sin, -sin]],
            outputs: std::array::from_fn(|j| {
                let sdd = match j {
                    X_S => 1.0,
                    X_T => -1.0,
                    _ => 0.0,
                };
                [a[(crate::model::V_S, j)], sdd]
            }),
        }
    }

    /// Road phase at the node after one with phase `z`.
    #[inline(always)]
    fn rotate(&self, z: [f64; 2]) -> [f64; 2] {
        let [c, s] = self.rotation;
        [c[0] * z[0] + s[0] * z[1], c[1] * z[1] + s[1] * z[0]]
    }

    /// `[BA, SDD]` at state x, summed pairwise like [`combine6`] (in the
    /// hot loop the products share their broadcasts of x with `Φ x`).
    #[inline(always)]
    fn ba_sdd(&self, x: &[f64; 6]) -> [f64; 2] {
        let c = &self.outputs;
        std::array::from_fn(|i| {
            ((c[0][i] * x[0] + c[1][i] * x[1]) + (c[2][i] * x[2] + c[3][i] * x[3]))
                + (c[4][i] * x[4] + c[5][i] * x[5])
        })
    }

    /// Adds node X's BA, SDD and TDD (road displacement `road`) to `rms`.
    #[inline(always)]
    fn count(&self, rms: &mut RunningRms, x: &[f64; 6], road: f64) {
        let [ba, sdd] = self.ba_sdd(x);
        rms.add_values(ba, sdd, x[X_T] - road);
    }
}

/// The largest absolute row sum of `m`.
fn infinity_norm(m: &Matrix6<f64>) -> f64 {
    m.row_iter()
        .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Whether every state component is within its divergence bound (false
/// for NaN), with one branch for the whole state.
#[inline(always)]
fn within_bounds(x: &[f64; 6]) -> bool {
    let b = DIVERGENCE_BOUNDS;
    (x[0].abs() <= b[0])
        & (x[1].abs() <= b[1])
        & (x[2].abs() <= b[2])
        & (x[3].abs() <= b[3])
        & (x[4].abs() <= b[4])
        & (x[5].abs() <= b[5])
}

/// The road as the whole-step loop carries it from grid node to grid node.
trait NodeRoad: Copy {
    /// The road's part of the step that leaves the current node.
    fn input(&self, op: &GridStep) -> [f64; 6];
    /// `x_g` at the current node (m).
    fn displacement(&self) -> f64;
    /// Moves to the next node.
    fn advance(&mut self, op: &GridStep);
}

/// The harmonic road's phase `A [sin ω t_k, cos ω t_k]` at node k, rotated
/// exactly from node to node (see [`PHASE_ANCHOR`]).
#[derive(Clone, Copy)]
struct HarmonicPhase([f64; 2]);

impl NodeRoad for HarmonicPhase {
    #[inline(always)]
    fn input(&self, op: &GridStep) -> [f64; 6] {
        combine2(&op.harmonic, &self.0)
    }
    #[inline(always)]
    fn displacement(&self) -> f64 {
        self.0[0]
    }
    #[inline(always)]
    fn advance(&mut self, op: &GridStep) {
        self.0 = op.rotate(self.0);
    }
}

/// One linear road piece `x_g = value + slope (t − start)` at grid node
/// `t_k = t_0 + k h`, evaluated as [`RoadPiece::value`] does.
#[derive(Clone, Copy)]
struct LinearPiece {
    start_time: f64,
    step: f64,
    k: u64,
    start: f64,
    value: f64,
    slope: f64,
}

impl LinearPiece {
    #[inline(always)]
    fn value_now(&self) -> f64 {
        let t = self.start_time + self.k as f64 * self.step;
        self.value + self.slope * (t - self.start)
    }
}

impl NodeRoad for LinearPiece {
    #[inline(always)]
    fn input(&self, op: &GridStep) -> [f64; 6] {
        combine2(&op.linear, &[self.value_now(), self.slope])
    }
    #[inline(always)]
    fn displacement(&self) -> f64 {
        self.value_now()
    }
    #[inline(always)]
    fn advance(&mut self, _: &GridStep) {
        self.k += 1;
    }
}

/// What the whole-step loop carries from node to node.
#[derive(Clone, Copy)]
struct HotState<R> {
    x: [f64; 6],
    road: R,
    k: u64,
    /// Ring slot of node k + 1 (it holds node k − m until overwritten).
    slot: usize,
    rms: RunningRms,
}

/// One run of the whole-step loop, within which neither a phase anchor
/// (harmonic road), a road breakpoint (linear roads) nor the start of the
/// history is crossed.
struct Segment<'a> {
    op: &'a GridStep,
    history: &'a mut [[f64; 2]],
    /// The node the segment stops at.
    end: u64,
    /// The nodes `[x, 0, x, 0]` of the constant history before the start.
    before_start: [f64; 4],
}

/// The hot loop: `X_{k+1} = Φ X_k + Γ_uH n_k + road_k`, the road moved on,
/// the new node stored in the history. The BA, SDD, TDD of every node
/// after the first are added to the RMS sums, except the last one's, which
/// the caller adds (on the harmonic road its phase is exact at an anchor).
/// Stops at `end` or before a state out of bounds, which it returns.
/// `DELAY`: the delay is resolved on the grid; `BEFORE`: all the delayed
/// nodes lie before the start.
#[inline(always)]
fn segment<R: NodeRoad, const DELAY: bool, const BEFORE: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
) -> Option<[f64; 6]> {
    let op = seg.op;
    let history = seg.history;
    let len = history.len();
    assert!(hot.slot < len);
    let HotState {
        mut x,
        mut road,
        mut k,
        mut slot,
        mut rms,
    } = *hot;
    let mut diverged = None;
    // Node k, where the segment starts, was counted in the RMS sums already;
    // each later node is counted in the step that leaves it.
    let mut count = false;
    while k < seg.end {
        let next_slot = if slot + 1 == len { 0 } else { slot + 1 };
        let mut input = road.input(op);
        if DELAY {
            let nodes = if BEFORE {
                seg.before_start
            } else {
                debug_assert!(slot < len && next_slot < len);
                // SAFETY: both slots are < len (the ring's length): slot
                // starts below len and next_slot wraps to 0 at len.
                let ([x0, v0], [x1, v1]) = unsafe {
                    (
                        *history.get_unchecked(slot),
                        *history.get_unchecked(next_slot),
                    )
                };
                [x0, v0, x1, v1]
            };
            input = add6(combine4(&op.nodes, &nodes), input);
        }
        let x_next = add6(combine6(&op.transition, &x), input);
        if count {
            op.count(&mut rms, &x, road.displacement());
        }
        count = true;
        if !within_bounds(&x_next) {
            diverged = Some(x_next);
            break;
        }
        road.advance(op);
        // SAFETY: slot < len, as above.
        unsafe { *history.get_unchecked_mut(slot) = [x_next[X_T], x_next[V_T]] };
        x = x_next;
        slot = next_slot;
        k += 1;
    }
    *hot = HotState {
        x,
        road,
        k,
        slot,
        rms,
    };
    diverged
}

/// [`segment`] compiled for AVX2 (the same operations in the same order,
/// without FMA, so the results are bit-identical).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn segment_avx2<R: NodeRoad, const DELAY: bool, const BEFORE: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
) -> Option<[f64; 6]> {
    segment::<R, DELAY, BEFORE>(seg, hot)
}

/// Runs [`segment`] with the widest vector unit available.
fn run_segment<R: NodeRoad, const DELAY: bool>(
    seg: Segment,
    hot: &mut HotState<R>,
    before: bool,
) -> Option<[f64; 6]> {
    #[cfg(target_arch = "x86_64")]
    if wide_vectors() {
        // SAFETY: the CPU supports AVX2 (checked at run time).
        return unsafe {
            match (DELAY, before) {
                (true, true) => segment_avx2::<R, true, true>(seg, hot),
                (true, false) => segment_avx2::<R, true, false>(seg, hot),
                _ => segment_avx2::<R, false, false>(seg, hot),
            }
        };
    }
    match (DELAY, before) {
        (true, true) => segment::<R, true, true>(seg, hot),
        (true, false) => segment::<R, true, false>(seg, hot),
        _ => segment::<R, false, false>(seg, hot),
    }
}

/// Whether the AVX2 loop is used: the CPU has it and `TDVASS_NO_AVX2` is
/// not set (to compare the two loops).
#[cfg(target_arch = "x86_64")]
fn wide_vectors() -> bool {
    use std::sync::OnceLock;
    static WIDE: OnceLock<bool> = OnceLock::new();
    *WIDE.get_or_init(|| {
        std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("TDVASS_NO_AVX2").is_none()
    })
}

/// Every output of the model at one instant (the FMU's outputs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outputs {
    /// Time (s).
    pub time: f64,
    /// Reported state `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: x_h, v_h mirror the wheel).
    pub state: State,
    /// BA, SDD, TDD.
    pub performance: Performance,
    /// The road displacement x_g actually applied (m).
    pub road_displacement: f64,
    /// Control force `u = g x_t(t − tau)` (N).
    pub control_force: f64,
    /// Running RMS values from the start to now, as time averages
    /// `sqrt((1/(t − t_0)) ∫_{t_0}^{t} y² ds)` (0 at the start).
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
}

/// First time derivatives of the outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OutputDerivatives {
    /// dX/dt (reported state).
    pub state: State,
    /// d/dt of BA, SDD, TDD.
    pub performance: Performance,
    /// dx_g/dt.
    pub road_displacement: f64,
    /// du/dt.
    pub control_force: f64,
    /// d/dt of the running RMS values: `(y² − RMS²) / (2 RMS (t − t_0))`
    /// (0 at the start and where an RMS value is 0).
    pub rms: RmsValues,
    /// dJ/dt.
    pub objective: f64,
}

/// Summary of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// RMS values over the run.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
}

/// The simulator: a quarter car on a road, advanced in time by the precise
/// integration method. `Clone` is a complete snapshot of it.
#[derive(Debug, Clone)]
pub struct Simulator {
    config: SimulationConfig,
    plant: Plant,
    /// Plant matrix used by the solver (the plant's A, plus the folded
    /// feedback when the delay is not resolved on the grid).
    solver_matrix: Matrix6<f64>,
    /// `‖solver_matrix‖_∞` (largest absolute row sum, 1/s): chooses the
    /// order of the Taylor series near a node.
    solver_matrix_norm: f64,
    grid: DelayGrid,
    full_step: StepOperator,
    /// `full_step` in the form of the whole-step loop.
    grid_step: GridStep,
    partial_steps: HashMap<u64, StepOperator>,
    road: Road,
    /// Index k of the grid node at or before the committed time.
    grid_index: u64,
    committed_time: f64,
    committed_state: State,
    current_time: f64,
    current_state: State,
    /// (x_t, v_t) at grid nodes `grid_index − m ..= grid_index`, by `index % (m + 1)`.
    history: Vec<[f64; 2]>,
    /// `Σ y²` of BA, SDD, TDD over the grid nodes of the open run (after
    /// the anchor of `integral`, up to `grid_index`).
    rms: RunningRms,
    /// The time integral of `y²` (see [`time_average`]).
    integral: SquareIntegral,
    /// The outputs at the current time, once computed (cleared by every
    /// change of the state, the time or a parameter).
    outputs_cache: Option<Outputs>,
    /// Harmonic road phase `(k, A [sin ω t_k, cos ω t_k])` at the last grid
    /// node reached by the whole-step loop: a cache of a function of k alone
    /// (see [`PHASE_ANCHOR`]), so it is not part of the saved state.
    phase: Option<(u64, [f64; 2])>,
}

impl Simulator {
    /// Largest |start time| in internal steps (2^42). Node times
    /// `t_0 + k h` then resolve every step to 2^-10 h near the start; from
    /// 2^53 steps on, `t_0 + h` can round to `t_0` and a step would no
    /// longer advance time.
    pub const MAX_START_TIME_IN_STEPS: f64 = 4_398_046_511_104.0;

    /// Validates the configuration and places the system at its initial
    /// state. Besides each value, it checks that the internal step `h`
    /// resolves times near the start: `|start_time| <= 2^42 h`
    /// ([`Self::MAX_START_TIME_IN_STEPS`]).
    pub fn new(config: SimulationConfig) -> Result<Simulator> {
        let plant = Plant::new(config.params, config.variant)?;
        if !config.start_time.is_finite() {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: config.start_time,
                reason: "must be finite",
            });
        }
        for (i, value) in config.initial_state.iter().enumerate() {
            if !value.is_finite() {
                return Err(Error::InvalidParameter {
                    name: crate::model::STATE_NAMES[i],
                    value: *value,
                    reason: "the initial state must be finite",
                });
            }
        }
        let w = config.weights;
        for (name, value) in [
            ("w_ba", w.body_acceleration),
            ("w_sdd", w.suspension_deflection),
            ("w_tdd", w.tire_deflection),
        ] {
            if !value.is_finite() {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "a weight must be finite",
                });
            }
        }
        let tau = if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        };
        let grid = DelayGrid::new(tau, config.max_internal_step)?;
        if config.start_time.abs() > grid.step * Self::MAX_START_TIME_IN_STEPS {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: config.start_time,
                reason: "|start_time| must be at most 2^42 internal steps (max_internal_step, or less to divide tau) so that node times resolve the step",
            });
        }
        let road = Road::new(&config.road, config.start_time)?;
        let mut initial = config.initial_state;
        if config.variant == Variant::Cs {
            initial[crate::model::X_H] = 0.0;
            initial[crate::model::V_H] = 0.0;
        }
        let (solver_matrix, full_step, grid_step) = Self::operators(&plant, &config, &grid)?;
        let history = vec![[initial[X_T], initial[V_T]]; grid.delay_steps as usize + 1];
        let start_time = config.start_time;
        let mut sim = Simulator {
            plant,
            solver_matrix_norm: infinity_norm(&solver_matrix),
            solver_matrix,
            grid,
            full_step,
            grid_step,
            partial_steps: HashMap::new(),
            road,
            grid_index: 0,
            committed_time: config.start_time,
            committed_state: initial,
            current_time: config.start_time,
            current_state: initial,
            history,
            rms: RunningRms::default(),
            integral: SquareIntegral::new(start_time, Default::default()),
            outputs_cache: None,
            phase: None,
            config,
        };
        let piece = sim.piece_from(start_time);
        sim.integral.anchor =
            sim.squares_at(0, start_time, &initial, (start_time, initial), &piece);
        Ok(sim)
    }

    fn operators(
        plant: &Plant,
        config: &SimulationConfig,
        grid: &DelayGrid,
    ) -> Result<(Matrix6<f64>, StepOperator, GridStep)> {
        let mut a = plant.a;
        let mut b = plant.b;
        if !grid.resolves_delay() {
            // u = g (x_t − tau v_t): fold the feedback into the plant.
            let tau = if config.variant.has_control() {
                config.params.tau
            } else {
                0.0
            };
            for row in 0..6 {
                a[(row, X_T)] += b[row];
                a[(row, V_T)] -= tau * b[row];
            }
            b = State::zeros();
        }
        let omega = match config.road {
            RoadSpec::Harmonic {
                angular_frequency, ..
            } => angular_frequency,
            _ => 0.0,
        };
        let (h, tau) = (grid.step, grid.inner_delay);
        let step = StepOperator::new(&a, &b, &plant.e, omega, h);
        let grid_step = if grid.delay_inside_step() {
            let first = StepOperator::new(&a, &b, &plant.e, omega, tau);
            let rest = StepOperator::new(&a, &b, &plant.e, omega, h - tau);
            GridStep::inner_delay(&step, [&first, &rest], &a, omega, h, tau).ok_or(
                Error::InvalidParameter {
                    name: "g",
                    value: config.params.g,
                    reason: "the step with the delay inside it is singular at this gain",
                },
            )?
        } else {
            GridStep::new(&step, &a, omega, h)
        };
        Ok((a, step, grid_step))
    }

    /// The configuration.
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    /// The plant (A, b, e of Eq. (2)).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The internal grid (step and delay in steps).
    pub fn grid(&self) -> DelayGrid {
        self.grid
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.current_time
    }

    /// Time of the last committed state (s): the last grid node reached, or
    /// the last change of an external road input.
    pub fn committed_time(&self) -> f64 {
        self.committed_time
    }

    /// Current state `X` (solver coordinates).
    pub fn state(&self) -> State {
        self.current_state
    }

    fn grid_time(&self, k: u64) -> f64 {
        self.config.start_time + k as f64 * self.grid.step
    }

    fn coincide(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * self.grid.step + 8.0 * f64::EPSILON * a.abs().max(b.abs())
    }

    /// The snap tolerance at time `t` (s): `2^22 ε |t|` (see
    /// [`SNAPPED_ADDITIONS`]), at most `h / 1024`, at least the
    /// [`Self::coincide`] tolerance.
    pub fn snap_tolerance(&self, t: f64) -> f64 {
        let drift = SNAPPED_ADDITIONS * f64::EPSILON * t.abs();
        let floor = 1e-9 * self.grid.step + 8.0 * f64::EPSILON * t.abs();
        drift.min(self.grid.step * SNAP_STEP_FRACTION).max(floor)
    }

    /// Whether a requested time `a` and a grid time `b` differ only by
    /// floating-point accumulation: then `b` is reached (committed) and
    /// the outputs are evaluated at `a` itself from there.
    fn snaps(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= self.snap_tolerance(a.abs().max(b.abs()))
    }

    /// Delayed-input vector `[u, u', u'', u''']` at offset σ into grid step k.
    #[inline]
    fn delayed_input(&self, k: u64, offset: f64) -> Vector4<f64> {
        let m = self.grid.delay_steps;
        let nodes = if k < m {
            let x = self.config.initial_state[X_T];
            [x, 0.0, x, 0.0]
        } else {
            let len = self.history.len() as u64;
            let [x0, v0] = self.history[((k - m) % len) as usize];
            let [x1, v1] = self.history[((k - m + 1) % len) as usize];
            [x0, v0, x1, v1]
        };
        hermite(nodes, self.grid.step, offset)
    }

    fn partial_operator(&mut self, length: f64) -> &StepOperator {
        let key = (length / self.grid.step * PARTIAL_STEP_RESOLUTION).round() as u64;
        if self.partial_steps.len() >= OPERATOR_CACHE_SIZE && !self.partial_steps.contains_key(&key)
        {
            self.partial_steps.clear();
        }
        let (a, b, e) = (self.solver_matrix, self.solver_input_column(), self.plant.e);
        let omega = match self.config.road {
            RoadSpec::Harmonic {
                angular_frequency, ..
            } => angular_frequency,
            _ => 0.0,
        };
        let quantized = key as f64 / PARTIAL_STEP_RESOLUTION * self.grid.step;
        self.partial_steps
            .entry(key)
            .or_insert_with(|| StepOperator::new(&a, &b, &e, omega, quantized))
    }

    fn solver_input_column(&self) -> State {
        if self.grid.resolves_delay() {
            self.plant.b
        } else {
            State::zeros()
        }
    }

    /// Integrates from (a, x) to b, all inside grid step k, splitting at road
    /// breakpoints.
    fn integrate_within_step(&mut self, k: u64, from: f64, x: State, to: f64) -> State {
        if self.grid.delay_inside_step() {
            let next = self.grid_time(k + 1);
            let (node, end) = self.inner_delay_next_node(k, from, x);
            if to == next {
                return node;
            }
            let (state, sensitivity) = self.integrate_inner_delay(k, from, x, to);
            return state + sensitivity * Vector2::from(end);
        }
        let step_start = self.grid_time(k);
        let mut start = from;
        let mut state = x;
        loop {
            let mut piece = self.road.piece(start);
            if piece.end() <= start || self.coincide(piece.end(), start) {
                piece = self.road.piece(piece.end().max(start));
            }
            let end = if piece.end() < to && !self.coincide(piece.end(), to) {
                piece.end()
            } else {
                to
            };
            let delayed = self
                .grid
                .resolves_delay()
                .then(|| self.delayed_input(k, start - step_start));
            let length = end - start;
            state = if self.coincide(length, self.grid.step) {
                self.full_step
                    .apply(&state, delayed.as_ref(), &piece, start)
            } else {
                self.partial_operator(length)
                    .apply(&state, delayed.as_ref(), &piece, start)
            };
            if end == to {
                return state;
            }
            start = end;
        }
    }

    /// Delay inside the step ([`DelayGrid::inner_delay`]): the state at grid
    /// node k + 1 reached from (from, x) in step k, and that node's
    /// `(x_t, v_t)`, which the delayed input of `[t_k + tau, t_{k+1})`
    /// interpolates (a 2×2 solve; NaN if it is singular, which the
    /// divergence check reports).
    fn inner_delay_next_node(&mut self, k: u64, from: f64, x: State) -> (State, [f64; 2]) {
        let next = self.grid_time(k + 1);
        let (state, sensitivity) = self.integrate_inner_delay(k, from, x, next);
        let pick = tire_pick();
        let end = (Matrix2::identity() - pick * sensitivity)
            .lu()
            .solve(&(pick * state))
            .unwrap_or(Vector2::repeat(f64::NAN));
        (state + sensitivity * end, [end[0], end[1]])
    }

    /// Delay inside the step: integrates from (from, x) to `to` inside grid
    /// step k, splitting at road breakpoints and at `t_k + tau`, with node
    /// k + 1 taken as zero in the delayed input. Returns that state and its
    /// 6×2 sensitivity to node k + 1's `(x_t, v_t)` (the result is affine
    /// in them).
    fn integrate_inner_delay(
        &mut self,
        k: u64,
        from: f64,
        x: State,
        to: f64,
    ) -> (State, SMatrix<f64, 6, 2>) {
        let (h, tau) = (self.grid.step, self.grid.inner_delay);
        let step_start = self.grid_time(k);
        let switch = step_start + tau;
        let [node_x, node_v] = self.history[(k % self.history.len() as u64) as usize];
        let mut start = from;
        let mut state = x;
        let mut sensitivity = SMatrix::<f64, 6, 2>::zeros();
        loop {
            let mut piece = self.road.piece(start);
            if piece.end() <= start || self.coincide(piece.end(), start) {
                piece = self.road.piece(piece.end().max(start));
            }
            let mut end = if piece.end() < to && !self.coincide(piece.end(), to) {
                piece.end()
            } else {
                to
            };
            let earlier = start < switch && !self.coincide(start, switch);
            if earlier && end > switch && !self.coincide(end, switch) {
                end = switch;
            }
            let op = self.partial_operator(end - start).clone();
            if earlier {
                let delayed = self.delayed_input(k, h - tau + (start - step_start));
                state = op.apply(&state, Some(&delayed), &piece, start);
                sensitivity = op.transition * sensitivity;
            } else {
                let interpolant = hermite_matrix(h, (start - switch).max(0.0));
                let delayed = interpolant * Vector4::new(node_x, node_v, 0.0, 0.0);
                state = op.apply(&state, Some(&delayed), &piece, start);
                sensitivity = op.transition * sensitivity
                    + op.delayed_input * interpolant.fixed_view::<4, 2>(0, 2);
            }
            if end == to {
                return (state, sensitivity);
            }
            start = end;
        }
    }

    fn check_divergence(&self, time: f64, x: &State) -> Result<()> {
        for (i, value) in x.iter().enumerate() {
            let bound = if i % 2 == 0 {
                DIVERGENCE_DISPLACEMENT
            } else {
                DIVERGENCE_VELOCITY
            };
            if value.is_nan() || value.abs() > bound {
                return Err(Error::Diverged {
                    time,
                    variable: crate::model::STATE_NAMES[i],
                    value: *value,
                    bound,
                });
            }
        }
        Ok(())
    }

    /// Advances to `t_end` (any length; any number of calls). On divergence
    /// the simulator stays at the last good grid node and returns
    /// [`Error::Diverged`].
    ///
    /// A `t_end` within the snap tolerance of a grid node
    /// ([`Self::snap_tolerance`]) commits that node, as if it had been
    /// asked for exactly; the state at `t_end` itself then comes from the
    /// node by a short Taylor series. So a caller that accumulates its
    /// communication times (`t += step`) commits the same nodes, does the
    /// same work and gets the same RMS integrals as one that computes them
    /// exactly; its outputs differ only by the drift times their rates.
    pub fn advance_to(&mut self, t_end: f64) -> Result<()> {
        self.outputs_cache = None;
        if !t_end.is_finite()
            || (t_end < self.current_time && !self.snaps(t_end, self.current_time))
        {
            return Err(Error::InvalidTime {
                name: "t_end",
                value: t_end,
                reason: "must be finite and not before the current time",
            });
        }
        loop {
            let k = self.grid_index;
            let next_node = self.grid_time(k + 1);
            if next_node < t_end || self.snaps(t_end, next_node) {
                if self.committed_time == self.grid_time(k) {
                    // On a grid node: whole steps up to the last node the
                    // interval reaches, in one tight loop.
                    let last = self.last_node_until(t_end);
                    self.whole_steps(last)?;
                } else {
                    // From a point inside the step (where an external road
                    // input changed) to its end node.
                    let from = (self.committed_time, self.committed_state);
                    let x = self.integrate_within_step(k, from.0, from.1, next_node);
                    self.check_divergence(next_node, &x)?;
                    let anchor = self.integral.anchor;
                    let (step_integral, at_end, last_piece) =
                        self.integral_within_step(k, from, anchor, next_node, &x);
                    self.commit_node(k + 1, next_node, x, step_integral, (at_end, last_piece));
                }
                if self.snaps(t_end, self.committed_time) {
                    return self.finish_near_committed(t_end);
                }
            } else {
                if self.snaps(t_end, self.committed_time) {
                    return self.finish_near_committed(t_end);
                }
                let x =
                    self.integrate_within_step(k, self.committed_time, self.committed_state, t_end);
                self.check_divergence(t_end, &x)?;
                self.current_state = x;
                self.current_time = t_end;
                return Ok(());
            }
        }
    }

    /// Ends an advance at `t_end`, which snaps to the committed point: the
    /// state there by [`Self::state_near_committed`].
    fn finish_near_committed(&mut self, t_end: f64) -> Result<()> {
        let x = self.state_near_committed(t_end - self.committed_time);
        self.check_divergence(t_end, &x)?;
        self.current_state = x;
        self.current_time = t_end;
        Ok(())
    }

    /// The largest grid index `j >= grid_index` whose node lies before
    /// `t_end` or snaps to it (at most `u64::MAX - 1`, so `j + 1`
    /// exists). Node times never decrease with the index, so `j` is found
    /// from the estimate `(t_end − t_0) / h` by
    /// [`crate::monotone::last_index_where`] in a bounded number of
    /// evaluations, even where many indices share one floating-point time.
    fn last_node_until(&self, t_end: f64) -> u64 {
        let reached = |j: u64| {
            let t = self.grid_time(j);
            t < t_end || self.snaps(t_end, t)
        };
        let k = self.grid_index;
        // `as` saturates (and maps NaN to 0); the search clamps the guess.
        let estimate = ((t_end - self.config.start_time) / self.grid.step).floor() as u64;
        crate::monotone::last_index_where(k, u64::MAX - 1, estimate, reached)
    }

    /// `A [sin ω t_k, cos ω t_k]` of the harmonic road, evaluated directly.
    fn exact_phase(&self, k: u64) -> [f64; 2] {
        match self.config.road {
            RoadSpec::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                let (sin, cos) = (angular_frequency * self.grid_time(k)).sin_cos();
                [amplitude * sin, amplitude * cos]
            }
            _ => [0.0; 2],
        }
    }

    /// The harmonic road phase at grid node k as the whole-step loop
    /// carries it: exact at the last anchor node, then rotated.
    fn harmonic_phase(&self, k: u64) -> [f64; 2] {
        if let Some((index, z)) = self.phase
            && index == k
        {
            return z;
        }
        let anchor = k - k % PHASE_ANCHOR;
        let mut z = self.exact_phase(anchor);
        for _ in anchor..k {
            z = self.grid_step.rotate(z);
        }
        z
    }

    /// Commits the grid nodes `grid_index + 1 ..= last`, each by one whole
    /// step from the node before (the committed state is on node
    /// `grid_index`). Each node's state is a function of its index alone.
    fn whole_steps(&mut self, last: u64) -> Result<()> {
        let harmonic = matches!(self.config.road, RoadSpec::Harmonic { .. });
        match (self.grid.resolves_delay(), harmonic) {
            (true, true) => self.harmonic_whole_steps::<true>(last),
            (false, true) => self.harmonic_whole_steps::<false>(last),
            (true, false) => self.whole_steps_with::<true>(last),
            (false, false) => self.whole_steps_with::<false>(last),
        }
    }

    /// [`Self::whole_steps`] on the harmonic road: segments that end at the
    /// phase anchors (and at node m, where the history starts), each run by
    /// [`segment`].
    fn harmonic_whole_steps<const DELAY: bool>(&mut self, last: u64) -> Result<()> {
        let m = self.grid.delay_steps;
        let first = self.grid_index;
        let len = self.history.len();
        let x0 = self.config.initial_state[X_T];
        let mut hot = HotState {
            x: self.committed_state.into(),
            road: HarmonicPhase(self.harmonic_phase(first)),
            k: first,
            slot: ((first + 1) % len as u64) as usize,
            rms: self.rms,
        };
        let mut diverged = None;
        while hot.k < last {
            let start = hot.k;
            let mut end = last.min((hot.k / PHASE_ANCHOR + 1) * PHASE_ANCHOR);
            let before_history = DELAY && hot.k < m;
            if before_history {
                end = end.min(m);
            }
            let segment = Segment {
                op: &self.grid_step,
                history: &mut self.history,
                end,
                before_start: [x0, 0.0, x0, 0.0],
            };
            diverged = run_segment::<_, DELAY>(segment, &mut hot, before_history);
            if hot.k.is_multiple_of(PHASE_ANCHOR) {
                hot.road = HarmonicPhase(self.exact_phase(hot.k));
            }
            if diverged.is_some() {
                break;
            }
            if hot.k > start {
                self.grid_step.count(&mut hot.rms, &hot.x, hot.road.0[0]);
            }
        }
        self.rms = hot.rms;
        self.phase = Some((hot.k, hot.road.0));
        self.set_committed_node(first, hot.k, hot.x);
        match diverged {
            Some(x) => self.check_divergence(self.grid_time(hot.k + 1), &State::from(x)),
            None => Ok(()),
        }
    }

    /// Records node k (reached by the whole-step loop from node `first`) as
    /// the committed and current state.
    fn set_committed_node(&mut self, first: u64, k: u64, x: [f64; 6]) {
        if k > first {
            let time = self.grid_time(k);
            self.grid_index = k;
            self.committed_time = time;
            self.committed_state = State::from(x);
            self.current_time = time;
            self.current_state = self.committed_state;
            self.road.release_before(time);
        }
    }

    /// [`Self::whole_steps`] on piecewise-linear roads: a step that a road
    /// breakpoint splits goes through [`Self::integrate_within_step`].
    fn whole_steps_with<const DELAY: bool>(&mut self, last: u64) -> Result<()> {
        #[cfg(target_arch = "x86_64")]
        if wide_vectors() {
            // SAFETY: the CPU supports AVX2 (checked at run time).
            return unsafe { self.whole_steps_with_avx2::<DELAY>(last) };
        }
        self.whole_steps_with_body::<DELAY>(last)
    }

    /// [`Self::whole_steps_with`] compiled for AVX2 (bit-identical).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn whole_steps_with_avx2<const DELAY: bool>(&mut self, last: u64) -> Result<()> {
        self.whole_steps_with_body::<DELAY>(last)
    }

    #[inline(always)]
    fn whole_steps_with_body<const DELAY: bool>(&mut self, last: u64) -> Result<()> {
        let m = self.grid.delay_steps;
        let len = self.history.len();
        let first = self.grid_index;
        let mut k = first;
        let mut x: [f64; 6] = self.committed_state.into();
        let before_start = {
            let x0 = self.config.initial_state[X_T];
            [x0, 0.0, x0, 0.0]
        };
        // Ring slot of node k + 1, which holds node k − m until overwritten.
        let mut slot = ((k + 1) % len as u64) as usize;
        let mut rms = self.rms;
        // A local copy: the compiler then knows that the history writes do
        // not change it.
        let op = self.grid_step.clone();
        // The piece at the node just reached, looked up for its road
        // displacement and used again for the step that leaves it.
        let mut piece_at_node = None;
        let result = loop {
            if k >= last {
                break Ok(());
            }
            let (t, to) = (self.grid_time(k), self.grid_time(k + 1));
            let covering = self.piece_over(t, to, piece_at_node.take());
            if let Some(
                piece @ RoadPiece::Linear {
                    start,
                    end,
                    value,
                    slope,
                },
            ) = covering
            {
                // The steps whose end nodes lie inside this piece, and the
                // one after them that reaches its end, in the hot loop (no
                // road lookup, no breakpoint test per step).
                let mut inside = self.last_node_inside(k, last, end);
                let before = DELAY && k < m;
                if before {
                    inside = inside.min(m);
                }
                let stop = inside.max(k + 1);
                let mut hot = HotState {
                    x,
                    road: LinearPiece {
                        start_time: self.config.start_time,
                        step: self.grid.step,
                        k,
                        start,
                        value,
                        slope,
                    },
                    k,
                    slot,
                    rms,
                };
                let segment = Segment {
                    op: &op,
                    history: &mut self.history,
                    end: stop,
                    before_start,
                };
                let diverged = run_segment::<_, DELAY>(segment, &mut hot, before);
                (x, k, slot, rms) = (hot.x, hot.k, hot.slot, hot.rms);
                if let Some(x_next) = diverged {
                    break self.check_divergence(self.grid_time(k + 1), &State::from(x_next));
                }
                let now = self.grid_time(k);
                // `road.piece(now)` is this piece exactly when the node lies
                // inside it.
                let piece_now = if k == inside {
                    piece
                } else {
                    self.road.piece(now)
                };
                op.count(&mut rms, &x, piece_now.value(now));
                if k != inside && self.coincide(end, now) {
                    // The node is a road breakpoint: x_g has a kink there,
                    // so the RMS run of nodes closes at it.
                    let after = self.piece_from(now);
                    self.close_run_at_node(k, now, &State::from(x), &mut rms, &piece, &after);
                }
                self.road.release_before(self.grid_time(k - 1));
                piece_at_node = Some(piece_now);
                continue;
            }
            // A step that a road breakpoint splits: the RMS run closes at
            // its start, and the step is integrated piece by piece.
            let next_slot = if slot + 1 == len { 0 } else { slot + 1 };
            let node = State::from(x);
            let piece_at_start = self.piece_from(t);
            self.close_run_at_node(k, t, &node, &mut rms, &piece_at_start, &piece_at_start);
            let anchor = self.integral.anchor;
            let (x_end, step_integral, at_end, last_piece) =
                self.integrate_split_step(k, t, node, anchor, to);
            let x_next: [f64; 6] = x_end.into();
            if (k + 1).is_multiple_of(PHASE_ANCHOR) {
                self.road.release_before(t);
            }
            let piece_next = self.road.piece(to);
            piece_at_node = Some(piece_next);
            if !within_bounds(&x_next)
                && let Err(e) = self.check_divergence(to, &State::from(x_next))
            {
                break Err(e);
            }
            self.history[slot] = [x_next[X_T], x_next[V_T]];
            self.restart_run_after_step(k + 1, to, &x_end, step_integral, (at_end, last_piece));
            x = x_next;
            slot = next_slot;
            k += 1;
        };
        self.rms = rms;
        self.set_committed_node(first, k, x);
        result
    }

    /// The largest node index `n` in `[k, last]` such that the nodes
    /// `k + 1 ..= n` lie strictly inside a road piece that ends at `end`
    /// (before it and not coinciding with it).
    fn last_node_inside(&self, k: u64, last: u64, end: f64) -> u64 {
        let inside = |j: u64| {
            let t = self.grid_time(j);
            t < end && !self.coincide(end, t)
        };
        let estimate = ((end - self.config.start_time) / self.grid.step).floor();
        let guess = if estimate > k as f64 {
            estimate as u64
        } else {
            k
        };
        crate::monotone::last_index_where(k, last, guess, inside)
    }

    /// The road piece used over the whole step `[t, to]` if no breakpoint
    /// splits it (the same choice as [`Self::integrate_within_step`]).
    /// `at_t`: `self.road.piece(t)` if already known.
    #[inline(always)]
    fn piece_over(&mut self, t: f64, to: f64, at_t: Option<RoadPiece>) -> Option<RoadPiece> {
        let mut piece = match at_t {
            Some(piece) => piece,
            None => self.road.piece(t),
        };
        if piece.end() <= t || self.coincide(piece.end(), t) {
            piece = self.road.piece(piece.end().max(t));
        }
        if piece.end() < to && !self.coincide(piece.end(), to) {
            None
        } else {
            Some(piece)
        }
    }

    /// Commits grid node k (time, state x) reached from a point inside
    /// step k − 1; `step_integral`: `∫ y²` from the committed point to it.
    fn commit_node(
        &mut self,
        k: u64,
        time: f64,
        x: State,
        step_integral: [f64; 3],
        arrival: (time_average::Squares, RoadPiece),
    ) {
        let len = self.history.len() as u64;
        self.history[(k % len) as usize] = [x[X_T], x[V_T]];
        self.grid_index = k;
        self.committed_time = time;
        self.committed_state = x;
        self.current_time = time;
        self.current_state = x;
        self.restart_run_after_step(k, time, &x, step_integral, arrival);
        self.road.release_before(time);
    }

    /// Sets the external road input from the current time on (only with
    /// `RoadSpec::Input`): `x_g(t) = value + slope (t − now)`. A current
    /// time that snaps to the committed point (a time drift) sets it from
    /// that point instead.
    pub fn set_road_input(&mut self, value: f64, slope: f64) -> Result<()> {
        self.outputs_cache = None;
        if !self.road.is_input() {
            return Err(Error::InvalidSetting {
                name: "road",
                value: 0,
                reason: "the input x_g is only used when road = 0",
            });
        }
        // Checked before the RMS run is closed, so that a refused value
        // changes nothing.
        Road::check_input(value, slope)?;
        let start = self.close_run_for_input();
        self.road.set_input(start, value, slope)?;
        self.reanchor_after_input();
        Ok(())
    }

    /// Changes the feedback gain g (tunable); the history is kept.
    pub fn set_gain(&mut self, g: f64) -> Result<()> {
        self.outputs_cache = None;
        let params = Params {
            g,
            ..self.config.params
        };
        let plant = Plant::new(params, self.config.variant)?;
        self.config.params = params;
        let (matrix, step, grid_step) = Self::operators(&plant, &self.config, &self.grid)?;
        self.plant = plant;
        self.solver_matrix = matrix;
        self.solver_matrix_norm = infinity_norm(&matrix);
        self.full_step = step;
        self.grid_step = grid_step;
        self.partial_steps.clear();
        Ok(())
    }

    /// Changes the weights of J (tunable).
    pub fn set_weights(&mut self, weights: Weights) {
        self.outputs_cache = None;
        self.config.weights = weights;
    }

    fn road_piece_now(&mut self) -> RoadPiece {
        let t = self.current_time;
        let piece = self.road.piece(t);
        if self.coincide(piece.end(), t) {
            self.road.piece(piece.end())
        } else {
            piece
        }
    }

    /// `[u, u']`: the delayed tire displacement and its rate now.
    fn delayed_tire_now(&mut self) -> (f64, f64) {
        let (k, t, x) = (self.grid_index, self.current_time, self.current_state);
        let from = (self.committed_time, self.committed_state);
        let p = self.delayed_vector_at(k, t, from, &x);
        (p[0], p[1])
    }

    /// All outputs at the current time.
    pub fn outputs(&mut self) -> Outputs {
        if let Some(outputs) = self.outputs_cache {
            return outputs;
        }
        let t = self.current_time;
        let x = self.current_state;
        let road = self.road_piece_now().value(t);
        let (delayed, _) = self.delayed_tire_now();
        let rms = self.rms_now();
        let outputs = Outputs {
            time: t,
            state: self.plant.reported_state(&x),
            performance: Performance::at(&self.plant, &x, road),
            road_displacement: road,
            control_force: self.config.params.effective_gain(self.config.variant) * delayed,
            rms,
            objective: rms.objective(&self.config.weights),
        };
        self.outputs_cache = Some(outputs);
        outputs
    }

    /// Exact first time derivatives of the instantaneous outputs.
    pub fn output_derivatives(&mut self) -> OutputDerivatives {
        let t = self.current_time;
        let x = self.current_state;
        let piece = self.road_piece_now();
        let (road, road_rate) = (piece.value(t), piece.slope(t));
        let (delayed, delayed_rate) = self.delayed_tire_now();
        let b = self.solver_input_column();
        let dx = self.solver_matrix * x + b * delayed + self.plant.e * road;
        let d2x = self.solver_matrix * dx + b * delayed_rate + self.plant.e * road_rate;
        let gain = self.config.params.effective_gain(self.config.variant);
        let now = Performance::at(&self.plant, &x, road);
        let rms = self.outputs().rms;
        let duration = t - self.config.start_time;
        let rate = |y: f64, value: f64| {
            if duration > 0.0 && value > 0.0 {
                (y * y - value * value) / (2.0 * value * duration)
            } else {
                0.0
            }
        };
        let rms_rate = RmsValues {
            body_acceleration: rate(now.body_acceleration, rms.body_acceleration),
            suspension_deflection: rate(now.suspension_deflection, rms.suspension_deflection),
            tire_deflection: rate(now.tire_deflection, rms.tire_deflection),
        };
        OutputDerivatives {
            rms: rms_rate,
            objective: rms_rate.objective(&self.config.weights),
            state: self.plant.reported_state(&dx),
            performance: Performance {
                body_acceleration: d2x[crate::model::V_S],
                suspension_deflection: dx[crate::model::X_S] - dx[X_T],
                tire_deflection: dx[X_T] - road_rate,
            },
            road_displacement: road_rate,
            control_force: gain * delayed_rate,
        }
    }

    /// RMS values so far (time averages from the start to now).
    pub fn rms(&mut self) -> RmsValues {
        self.rms_now()
    }

    /// Runs from the current time for `duration` seconds and summarises.
    pub fn run_for(&mut self, duration: f64) -> Result<RunSummary> {
        self.advance_to(self.current_time + duration)?;
        let rms = self.rms_now();
        Ok(RunSummary {
            rms,
            objective: rms.objective(&self.config.weights),
        })
    }
}

/// Simulates `config` from its start for `duration` seconds.
pub fn simulate(config: SimulationConfig, duration: f64) -> Result<RunSummary> {
    Simulator::new(config)?.run_for(duration)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::road::RandomRoad;

    fn bits(sim: &mut Simulator) -> Vec<u64> {
        let o = sim.outputs();
        let mut v: Vec<f64> = o.state.iter().copied().collect();
        v.extend([
            o.performance.body_acceleration,
            o.performance.suspension_deflection,
            o.performance.tire_deflection,
            o.road_displacement,
            o.control_force,
            o.rms.body_acceleration,
            o.rms.suspension_deflection,
            o.rms.tire_deflection,
            o.objective,
            o.time,
        ]);
        v.extend(sim.committed_state.iter().copied());
        v.extend(sim.rms.sums_of_squares);
        v.push(sim.rms.samples as f64);
        v.into_iter().map(f64::to_bits).collect()
    }

    fn configs() -> Vec<SimulationConfig> {
        let base = SimulationConfig::default();
        vec![
            base.clone(),
            SimulationConfig {
                variant: Variant::Pvass,
                ..base.clone()
            },
            SimulationConfig {
                params: Params::with_controller(40000.0, 0.03),
                initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
                ..base.clone()
            },
            SimulationConfig {
                params: Params::with_controller(2528.0, 1.28e-4),
                road: RoadSpec::Iso8608(RandomRoad::default()),
                ..base.clone()
            },
            SimulationConfig {
                road: RoadSpec::PaperCompatible {
                    road: RandomRoad::default(),
                    sample_interval: 0.1,
                },
                ..base.clone()
            },
            // Delays inside one step, on the harmonic and a linear road.
            SimulationConfig {
                params: Params::with_controller(40000.0, 3.7e-5),
                initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
                ..base.clone()
            },
            SimulationConfig {
                params: Params::with_controller(6000.0, 2e-6),
                road: RoadSpec::Iso8608(RandomRoad::default()),
                ..base
            },
        ]
    }

    #[test]
    fn any_split_gives_bit_identical_results() {
        // Splits that cut the whole-step loop at phase anchors, before the
        // history starts, in the middle of anchor segments, and step by step.
        for cfg in configs() {
            let stops: Vec<f64> = (1..=40).map(|i| i as f64 * 0.0517).collect();
            let mut reference = Vec::new();
            let mut sim = Simulator::new(cfg.clone()).unwrap();
            for &t in &stops {
                sim.advance_to(t).unwrap();
                reference.push(bits(&mut sim));
            }
            let mut one_by_one = Simulator::new(cfg.clone()).unwrap();
            let h = one_by_one.grid().step;
            let mut i = 0;
            for (stop, expected) in stops.iter().zip(&reference) {
                loop {
                    let t = (i + 1) as f64 * h * 0.73;
                    if t >= *stop {
                        break;
                    }
                    one_by_one.advance_to(t).unwrap();
                    i += 1;
                }
                one_by_one.advance_to(*stop).unwrap();
                assert_eq!(&bits(&mut one_by_one), expected, "{:?}", cfg.road);
            }
            let mut cut = Simulator::new(cfg.clone()).unwrap();
            for t in [h * 1023.0, h * 1024.0, h * 1025.5, h * 3000.0] {
                cut.advance_to(t).unwrap();
            }
            cut.advance_to(stops[39]).unwrap();
            assert_eq!(&bits(&mut cut), reference.last().unwrap());
        }
    }

    #[test]
    fn restored_simulator_continues_bit_identically_inside_a_segment() {
        for cfg in configs() {
            let mut sim = Simulator::new(cfg).unwrap();
            let h = sim.grid().step;
            // Node 1500 lies inside the second phase-anchor segment.
            sim.advance_to(1500.3 * h).unwrap();
            let mut restored = Simulator::from_bytes(&sim.to_bytes()).unwrap();
            for t in [2047.0 * h, 2048.0 * h, 5000.5 * h, 0.9] {
                sim.advance_to(t).unwrap();
                restored.advance_to(t).unwrap();
                assert_eq!(bits(&mut sim), bits(&mut restored));
            }
        }
    }

    #[test]
    fn whole_steps_match_the_general_step_closely() {
        // The whole-step loop (node form of the delayed input, rotated road
        // phase) against one general step per node (Hermite form, sin/cos).
        let cfg = SimulationConfig {
            params: Params::with_controller(40000.0, 0.03),
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.0, 0.0),
            ..SimulationConfig::default()
        };
        let mut fast = Simulator::new(cfg.clone()).unwrap();
        let mut general = Simulator::new(cfg).unwrap();
        for k in 0..3000u64 {
            let to = general.grid_time(k + 1);
            let from = (general.committed_time, general.committed_state);
            let x = general.integrate_within_step(k, from.0, from.1, to);
            let anchor = general.integral.anchor;
            let (step_integral, at_end, piece) =
                general.integral_within_step(k, from, anchor, to, &x);
            general.commit_node(k + 1, to, x, step_integral, (at_end, piece));
        }
        fast.advance_to(general.committed_time).unwrap();
        let scale = general.committed_state.amax();
        assert!((fast.committed_state - general.committed_state).amax() < 1e-12 * scale);
        let (a, b) = (fast.rms(), general.rms());
        assert!((a.body_acceleration - b.body_acceleration).abs() < 1e-12 * b.body_acceleration);
        assert!((a.tire_deflection - b.tire_deflection).abs() < 1e-12 * b.tire_deflection);
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_loop_is_bit_identical_to_the_baseline_loop() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        /// Runs 1000 steps from `sim`'s node with the baseline and the AVX2
        /// loop; returns the bits of state, RMS sums and history of each.
        fn both<R: NodeRoad>(sim: &Simulator, road: R) -> Vec<Vec<u64>> {
            let start = HotState {
                x: sim.committed_state.into(),
                road,
                k: sim.grid_index,
                slot: ((sim.grid_index + 1) % sim.history.len() as u64) as usize,
                rms: sim.rms,
            };
            let mut results = Vec::new();
            for wide in [false, true] {
                let mut history = sim.history.clone();
                let mut hot = HotState { ..start };
                let seg = Segment {
                    op: &sim.grid_step,
                    history: &mut history,
                    end: sim.grid_index + 1000,
                    before_start: [0.0; 4],
                };
                if wide {
                    // SAFETY: AVX2 was detected by the caller.
                    unsafe { segment_avx2::<_, true, false>(seg, &mut hot) };
                } else {
                    segment::<_, true, false>(seg, &mut hot);
                }
                let mut v: Vec<u64> = hot.x.iter().map(|v| v.to_bits()).collect();
                v.extend(hot.rms.sums_of_squares.map(f64::to_bits));
                v.push(hot.road.displacement().to_bits());
                v.extend(history.iter().flatten().map(|v| v.to_bits()));
                results.push(v);
            }
            results
        }
        let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
        sim.advance_to(0.01).unwrap();
        let phase = HarmonicPhase(sim.harmonic_phase(sim.grid_index));
        let [baseline, wide] = &both(&sim, phase)[..] else {
            unreachable!()
        };
        assert_eq!(baseline, wide);
        // A linear piece (a ramp of the road) from the same state.
        let ramp = LinearPiece {
            start_time: 0.0,
            step: sim.grid.step,
            k: sim.grid_index,
            start: 0.005,
            value: 0.01,
            slope: -0.3,
        };
        let [baseline, wide] = &both(&sim, ramp)[..] else {
            unreachable!()
        };
        assert_eq!(baseline, wide);
    }
}
