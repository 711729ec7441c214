//! The driver: the [`Simulator`] and its step. It holds the grouped parts
//! (configuration, modes, inputs, trajectory, observers), advances them
//! ([`Simulator::advance_to`]: whole steps through `whole_steps`, points inside
//! a step through `stepping`, the tire's switches through `events`), and
//! alone moves the committed point and tells the observers of it (the
//! whole steps do it through the view `whole_steps::WholeSteps` it lends them).
//! The public constructors and readers that need the clients
//! (`accuracy`, `outputs`, `persist`) are declared in the solver's module.
//!
//! Layer: driver (docs/architecture.md); it imports the solver's `config`,
//! `contact`, `deferred`, `grid`, `holding`, `inputs`, `integrals`,
//! `modes`, `observers`, `pieces`, `reports`, `stepping`, `system`,
//! `trajectory`, `whole_steps` and the crate's `error`, `limits`, `metrics`,
//! `model`, `monotone`, `road`.

use super::config::{SimulationConfig, StepChoice};
use super::deferred::{Deferred, Kind};
use super::grid::DelayGrid;
use super::inputs::Inputs;
use super::integrals::{Accumulated, INTEGRALS, Squares};
use super::modes::Modes;
use super::observers::Observers;
use super::pieces;
use super::reports::Outputs;
use super::stepping::stepping;
use super::system::Filter;
use super::trajectory::Trajectory;
use super::whole_steps;
use crate::error::{Error, Result};
use crate::metrics::rms_values;
use crate::metrics::{RmsValues, Weights};
use crate::model::dynamics::Mode;
use crate::model::inputs::{BODY_ATTACHMENT, PRESCRIBED};
use crate::model::{Params, Plant, State, V_T, X_T};
use crate::road::{Road, RoadPiece};

/// Rounding drift covered by the snap tolerance, in additions: a time
/// accumulated as `t += step` over N steps is off by at most `N ε |t| / 2`,
/// so `2^22 ε |t|` covers 2^22 steps with a factor 2 to spare (1.4e-8 s at
/// t = 15 s).
const SNAPPED_ADDITIONS: f64 = 4_194_304.0;
/// The snap tolerance never exceeds this fraction of the internal step
/// (2^-10: 1e-7 s at the default step, far below any time scale of the
/// model or its roads).
const SNAP_STEP_FRACTION: f64 = 1.0 / 1024.0;

/// The simulator: a quarter car on a road, advanced in time by the precise
/// integration method. `Clone` is a complete snapshot of it.
#[derive(Debug, Clone)]
pub struct Simulator {
    /// The configuration, as given (the gain and the weights are tunable).
    pub(super) config: SimulationConfig,
    /// The plant of the configuration (A, b, e of Eq. (2)).
    pub(super) plant: Plant,
    /// The internal grid: the step and how the delay lies on it.
    pub(super) grid: DelayGrid,
    /// How the internal step came from the tolerance.
    pub(super) step_choice: StepChoice,
    /// The operators of the tire's modes and their caches.
    pub(super) modes: Modes,
    /// The road and the delay history.
    pub(super) inputs: Inputs,
    /// The committed point and the current point.
    pub(super) trajectory: Trajectory,
    /// What the run accumulates for its outputs.
    pub(super) observers: Observers,
    /// The outputs at the current time, once computed (cleared by every
    /// change of the state, the time or a parameter).
    pub(super) outputs_cache: Option<Outputs>,
}

impl Simulator {
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

    /// How the internal step came from the tolerance (the model's step,
    /// the probe's estimate; see [`super::accuracy`]).
    pub fn step_choice(&self) -> StepChoice {
        self.step_choice
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.trajectory.current_time
    }

    /// Time of the last committed state (s): the last grid node reached, or
    /// the last change of an external road input.
    pub fn committed_time(&self) -> f64 {
        self.trajectory.committed_time
    }

    /// Current state `X` (solver coordinates); a deferred one
    /// ([`Self::computed_state`]) is computed on a copy.
    pub fn state(&self) -> State {
        match self.computed_state() {
            Some(x) => x,
            None => {
                let mut settled = self.clone();
                settled.settle();
                settled.trajectory.current_state
            }
        }
    }

    pub(super) fn grid_time(&self, k: u64) -> f64 {
        self.inputs.node_time(k)
    }

    /// Whether times `a` and `b` are the same on this grid
    /// ([`pieces::coincide`]).
    pub(super) fn coincide(&self, a: f64, b: f64) -> bool {
        pieces::coincide(a, b, self.grid.step)
    }

    /// The snap tolerance at time `t` (s): `2^22 ε |t|` (the rounding drift
    /// of 2^22 additions `t += step`, with a factor 2 to spare), at most
    /// `h / 1024`, at least `1e-9 h + 8 ε |t|` (the tolerance within which
    /// two times are the same node).
    pub fn snap_tolerance(&self, t: f64) -> f64 {
        let drift = SNAPPED_ADDITIONS * f64::EPSILON * t.abs();
        let floor = 1e-9 * self.grid.step + 8.0 * f64::EPSILON * t.abs();
        drift.min(self.grid.step * SNAP_STEP_FRACTION).max(floor)
    }

    /// The time of the first internal grid node after the committed one
    /// that is at or after `t` (s): where a master can be called back
    /// inside a step (FMI 3.0 intermediate updates) without moving the
    /// grid.
    pub fn node_at_or_after(&self, t: f64) -> f64 {
        let first = self.trajectory.grid_index.saturating_add(1);
        // `as` saturates (and maps NaN to 0); the loops correct the guess.
        let mut k = (((t - self.config.start_time) / self.grid.step).ceil() as u64).max(first);
        while k > first && self.grid_time(k - 1) >= t {
            k -= 1;
        }
        while self.grid_time(k) < t && k < u64::MAX - 1 {
            k += 1;
        }
        self.grid_time(k)
    }

    /// Whether a requested time `a` and a grid time `b` differ only by
    /// floating-point accumulation: then `b` is reached (committed) and
    /// the outputs are evaluated at `a` itself from there.
    pub(super) fn snaps(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= self.snap_tolerance(a.abs().max(b.abs()))
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
    ///
    /// The state at a `t_end` that is not a grid node (near one, or inside
    /// a step) may be left to be found when first asked for
    /// ([`Self::computed_state`]): bounds show that it passes the
    /// divergence check, and it is the same value to the bit.
    pub fn advance_to(&mut self, t_end: f64) -> Result<()> {
        self.outputs_cache = None;
        if !t_end.is_finite()
            || (t_end < self.trajectory.current_time
                && !self.snaps(t_end, self.trajectory.current_time))
        {
            return Err(Error::InvalidTime {
                name: "t_end",
                value: t_end,
                reason: "must be finite and not before the current time",
            });
        }
        // An element may switch (the unilateral tire).
        let switching = self.modes.grid_step.switching.any();
        // Switches made in the current step.
        let mut switches = 0;
        loop {
            let k = self.trajectory.grid_index;
            let next_node = self.grid_time(k + 1);
            if next_node < t_end || self.snaps(t_end, next_node) {
                let on_node = self.trajectory.committed_time == self.grid_time(k);
                if on_node && self.trajectory.mode == Mode::CONTACT && switches == 0 {
                    // On a grid node, every switching element in its first
                    // law: whole steps up to the last node the interval
                    // reaches, in one tight loop, up to a step in which an
                    // element may switch (the wheel lift off).
                    let last = self.last_node_until(t_end);
                    if self.whole_steps_view().whole_steps(last)? {
                        self.step_to_node_switching(&mut switches)?;
                    }
                } else if switching {
                    self.step_to_node_switching(&mut switches)?;
                } else {
                    self.step_to_node()?;
                }
                if self.trajectory.grid_index > k {
                    switches = 0;
                }
                if self.snaps(t_end, self.trajectory.committed_time) {
                    return self.finish_near_committed(t_end);
                }
            } else {
                if self.snaps(t_end, self.trajectory.committed_time) {
                    return self.finish_near_committed(t_end);
                }
                if switching && self.switch_by(k, t_end, &mut switches)? {
                    continue;
                }
                if self.defer(t_end, Kind::InsideStep) {
                    return Ok(());
                }
                let x = stepping!(self).integrate_within_step(
                    k,
                    self.trajectory.committed_time,
                    self.trajectory.committed_state,
                    t_end,
                );
                crate::limits::check_divergence(t_end, &x)?;
                self.trajectory.set_current(t_end, x);
                return Ok(());
            }
        }
    }

    /// From the committed point inside the current step (where an
    /// external road input changed or the tire contact switched), or from
    /// its start node, to its end node, which is committed.
    pub(super) fn step_to_node(&mut self) -> Result<()> {
        let k = self.trajectory.grid_index;
        let next_node = self.grid_time(k + 1);
        if self.observers.rms.samples > 0 {
            // From a node that ends a run of the whole-step loop (a
            // unilateral tire's step that may lift off, or a step that a
            // road breakpoint splits): the run closes there first.
            let (t, x, w) = (
                self.trajectory.committed_time,
                self.trajectory.committed_state,
                self.trajectory.committed_filter,
            );
            let piece = self.inputs.piece_from(t);
            let (mut rms, mut weighted) = (self.observers.rms, self.observers.weighted);
            self.observers.close_run_at_node(
                &mut stepping!(self),
                k,
                (t, &x, &w),
                &mut rms,
                &mut weighted,
                &piece,
                &piece,
            );
            (self.observers.rms, self.observers.weighted) = (rms, weighted);
        }
        let from = (
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let x = stepping!(self).integrate_within_step(k, from.0, from.1, next_node);
        crate::limits::check_divergence(next_node, &x)?;
        let w_from = self.trajectory.committed_filter;
        let w = stepping!(self).filter_within_step(k, from, &w_from, next_node);
        let anchor = self.observers.integral.anchor;
        let mut holding = self.observers.holding;
        let (step_integral, at_end, last_piece) = stepping!(self).integral_within_step(
            k,
            from,
            &w_from,
            anchor,
            next_node,
            (&x, &w),
            &mut holding,
        );
        self.observers.holding = holding;
        self.commit_node(
            k + 1,
            (next_node, x, w),
            step_integral,
            (at_end, last_piece),
        );
        Ok(())
    }

    /// Ends an advance at `t_end`, which snaps to the committed point: the
    /// state there by [`Stepping::state_near`](super::stepping::Stepping::state_near), deferred where that
    /// is shown to be safe ([`super::deferred`]).
    pub(super) fn finish_near_committed(&mut self, t_end: f64) -> Result<()> {
        let delta = t_end - self.trajectory.committed_time;
        if delta != 0.0 && self.defer(t_end, Kind::NearNode) {
            return Ok(());
        }
        let x = stepping!(self).state_near(self.trajectory.committed_point(), delta);
        crate::limits::check_divergence(t_end, &x)?;
        self.trajectory.set_current(t_end, x);
        Ok(())
    }

    /// The largest grid index `j >= grid_index` whose node lies before
    /// `t_end` or snaps to it (at most `u64::MAX - 1`, so `j + 1`
    /// exists). Node times never decrease with the index, so `j` is found
    /// from the estimate `(t_end − t_0) / h` by
    /// [`crate::monotone::last_index_where`] in a bounded number of
    /// evaluations, even where many indices share one floating-point time.
    /// The usual call of a master that steps one internal step at a time,
    /// to the next node (or a time that snaps to it), is tested first.
    pub(super) fn last_node_until(&self, t_end: f64) -> u64 {
        let reached = |j: u64| {
            let t = self.grid_time(j);
            t < t_end || self.snaps(t_end, t)
        };
        let k = self.trajectory.grid_index;
        if k < u64::MAX - 2 && reached(k + 1) && !reached(k + 2) {
            return k + 1;
        }
        // `as` saturates (and maps NaN to 0); the search clamps the guess.
        let estimate = ((t_end - self.config.start_time) / self.grid.step).floor() as u64;
        crate::monotone::last_index_where(k, u64::MAX - 1, estimate, reached)
    }

    /// Commits grid node k (time, state x, filter state w) reached from a
    /// point inside step k − 1; `step_integral`: `∫ f` from the committed
    /// point to it.
    pub(super) fn commit_node(
        &mut self,
        k: u64,
        (time, x, w): (f64, State, Filter),
        step_integral: [f64; INTEGRALS],
        arrival: (Squares, RoadPiece),
    ) {
        self.inputs.record_node(k, [x[X_T], x[V_T]]);
        self.trajectory.commit_node(k, time, x, w);
        if self.config.metrics.road_holding() {
            self.observers.holding.add_node(&x.into());
        }
        self.observers.restart_run_after_step(
            &mut stepping!(self),
            k,
            (time, &x, &w),
            step_integral,
            arrival,
        );
        self.inputs.road.release_before(time);
    }

    /// Sets the external road input from the current time on (only with
    /// `RoadSpec::Input`): `x_g(t) = value + slope (t − now)`. A current
    /// time that snaps to the committed point (a time drift) sets it from
    /// that point instead.
    pub fn set_road_input(&mut self, value: f64, slope: f64) -> Result<()> {
        self.settle();
        self.outputs_cache = None;
        if !self.inputs.road.is_input() {
            return Err(Error::InvalidSetting {
                name: "road",
                value: 0,
                reason: "the input x_g is only used when road = 0",
            });
        }
        // Checked before the RMS run is closed, so that a refused value
        // changes nothing.
        Road::check_input(value, slope)?;
        self.modes.next_node = None;
        let start = self.close_run_for_input();
        self.inputs.road.set_input(start, value, slope)?;
        self.observers
            .reanchor(&mut stepping!(self), &self.trajectory.committed());
        Ok(())
    }

    /// The body's attachment point now, `(x_s (m), v_s (m/s))`: a
    /// corner's as set and moved at its velocity since
    /// ([`Self::set_body_input`]), the sprung mass's otherwise.
    pub fn body_attachment(&mut self) -> (f64, f64) {
        let [displacement, velocity] = self.prescribed(BODY_ATTACHMENT);
        (displacement, velocity)
    }

    /// The coordinates `[position, velocity]` that the input `input` (an
    /// index into [`PRESCRIBED`]) sets, now.
    pub fn prescribed(&mut self, input: usize) -> [f64; 2] {
        self.settle();
        let x = self.trajectory.current_state;
        PRESCRIBED[input].coordinates.map(|c| x[c])
    }

    /// Sets the body's attachment point from the current time on (only
    /// with [`crate::model::Body::Attached`], a corner): `x_s = displacement`
    /// (m) and `v_s = velocity` (m/s) ([`Self::set_prescribed`]).
    pub fn set_body_input(&mut self, displacement: f64, velocity: f64) -> Result<()> {
        self.set_prescribed(BODY_ATTACHMENT, [displacement, velocity])
    }

    /// Sets the coordinates that the input `input` (an index into
    /// [`PRESCRIBED`]) prescribes from the current time on, `values` =
    /// `[position (m), velocity (m/s)]`, moving at that velocity until
    /// the next change (the plant's law, [`Plant::with_body`]). The
    /// current point is committed first (the RMS run closes there, as at a
    /// change of the road input); the history of the delayed `x_t` stays.
    /// An input the configuration does not have, or a value that is not
    /// finite or beyond the divergence bounds, is refused by name and
    /// changes nothing.
    pub fn set_prescribed(&mut self, input: usize, values: [f64; 2]) -> Result<()> {
        crate::limits::check_prescribed(self.config.body, input, values)?;
        self.settle();
        let [position, velocity] = PRESCRIBED[input].coordinates;
        let x = self.trajectory.current_state;
        if x[position].to_bits() == values[0].to_bits()
            && x[velocity].to_bits() == values[1].to_bits()
        {
            // The coordinates are where they were set to be: nothing to
            // commit.
            return Ok(());
        }
        self.outputs_cache = None;
        self.modes.next_node = None;
        self.close_run_for_input();
        for point in [
            &mut self.trajectory.committed_state,
            &mut self.trajectory.current_state,
        ] {
            point[position] = values[0];
            point[velocity] = values[1];
        }
        if self.config.metrics.road_holding() {
            // The largest |SDD| sees the new coordinates at once.
            self.observers
                .holding
                .add_node(&self.trajectory.committed_state.into());
        }
        self.observers
            .reanchor(&mut stepping!(self), &self.trajectory.committed());
        Ok(())
    }

    /// Changes the feedback gain g (tunable; within the rate limit of
    /// [`crate::limits::check_rates`]); the history is kept.
    pub fn set_gain(&mut self, g: f64) -> Result<()> {
        if g.to_bits() == self.config.params.g.to_bits() {
            // The same gain: the operators stand (a master that sets every
            // tunable parameter at every step rebuilds nothing).
            return Ok(());
        }
        self.settle();
        self.outputs_cache = None;
        let params = Params {
            g,
            ..self.config.params
        };
        let plant = Plant::new(params, self.config.variant)?.with_body(self.config.body);
        crate::limits::check_rates(&params, Some(self.config.variant))?;
        self.config.params = params;
        self.modes = Modes::new(
            &plant,
            &self.config,
            &self.grid,
            self.inputs.angular_frequency(),
        )?;
        self.plant = plant;
        // The contact operators were rebuilt: the flight ones follow, and
        // a flight in progress goes on with them.
        self.enter_recorded_mode();
        Ok(())
    }

    /// Builds now every table that stepping would build at its first use
    /// (the partial steps' maps of every mode a run can reach, the W_k
    /// filter's, the operators of the modes not in force) and makes room for the road's nodes (also after
    /// a restored state, whose nodes come without room), so that stepping
    /// from here on allocates nothing; a front-end with real-time callers
    /// calls it once the run is set up. The tables are caches of functions of the operators:
    /// results are the same with or without it. A gain change
    /// ([`Self::set_gain`]) drops them (call it again after one).
    pub fn reserve(&mut self) {
        let in_force = self.trajectory.mode;
        self.modes.reserve(&self.plant, &self.grid, in_force);
        // The road keeps its nodes from the step before the committed
        // point to the end of the next step.
        self.inputs.road.reserve_window(4.0 * self.grid.step);
    }

    /// Changes the weights of J (tunable).
    pub fn set_weights(&mut self, weights: Weights) {
        self.outputs_cache = None;
        self.config.weights = weights;
    }

    /// The current state if it has been computed; `None` while it is
    /// deferred: [`Self::advance_to`] may leave the state at a point near
    /// a node or inside a step to be found when first asked for
    /// ([`Self::state`], the outputs), after showing that it passes the
    /// divergence check.
    pub fn computed_state(&self) -> Option<State> {
        self.trajectory
            .deferred
            .is_none()
            .then_some(self.trajectory.current_state)
    }

    /// Computes a deferred current state (the same value as when it is
    /// computed at once).
    pub(super) fn settle(&mut self) {
        if let Some(deferred) = self.trajectory.deferred.take() {
            let (k, tc, xc, t) = (
                self.trajectory.grid_index,
                self.trajectory.committed_time,
                self.trajectory.committed_state,
                self.trajectory.current_time,
            );
            self.trajectory.current_state = match deferred.kind {
                Kind::NearNode => {
                    stepping!(self).state_near(self.trajectory.committed_point(), t - tc)
                }
                Kind::InsideStep => stepping!(self).integrate_within_step(k, tc, xc, t),
            };
        }
    }

    /// Bounds of how far the deferred state lies from the committed one
    /// (`None` when it is computed).
    pub(super) fn deferred_drift(&self) -> Option<[f64; 6]> {
        self.trajectory.deferred.map(|d| d.drift)
    }

    /// Makes `t` the current time with its state deferred, where the
    /// bounds of `kind` show that the state passes the divergence check;
    /// `false` (the current point unchanged) otherwise.
    #[inline]
    pub(super) fn defer(&mut self, t: f64, kind: Kind) -> bool {
        let drift = match kind {
            Kind::NearNode => stepping!(self).drift_bounds(
                self.trajectory.committed_point(),
                t - self.trajectory.committed_time,
            ),
            Kind::InsideStep => stepping!(self).inside_bounds(self.trajectory.committed_point(), t),
        };
        let x = self.trajectory.committed_state;
        let Some(drift) = drift.filter(|drift| {
            (0..6).all(|i| x[i].abs() + drift[i] <= 0.5 * crate::limits::divergence_bound(i))
        }) else {
            return false;
        };
        self.trajectory.current_time = t;
        self.trajectory.current_state = x;
        self.trajectory.deferred = Some(Deferred { kind, drift });
        true
    }

    /// Everything accumulated from `t_0` to the current time
    /// ([`Observers::accumulated`]).
    pub(super) fn accumulated_now(&mut self) -> Accumulated {
        self.settle();
        let (t, x) = (self.trajectory.current_time, self.trajectory.current_state);
        let drift = self.snaps(t, self.trajectory.committed_time);
        self.observers.accumulated(
            &mut stepping!(self),
            &self.trajectory.committed(),
            (t, x),
            drift,
        )
    }

    /// `∫_{t_0}^{t} y² dt` of BA, SDD and TDD at the current time t
    /// ([`Observers::rms_integral`]).
    pub(super) fn rms_integral_now(&mut self) -> [f64; 3] {
        let (t, tc) = (self.trajectory.current_time, self.trajectory.committed_time);
        let inside = t != tc && !self.snaps(t, tc);
        if inside {
            self.settle();
        }
        let x = self.trajectory.current_state;
        self.observers.rms_integral(
            &mut stepping!(self),
            &self.trajectory.committed(),
            (t, x),
            inside,
        )
    }

    /// The running RMS values at the current time.
    pub(super) fn rms_now(&mut self) -> RmsValues {
        let integral = self.rms_integral_now();
        rms_values(
            &integral,
            self.trajectory.current_time - self.config.start_time,
        )
    }

    /// Before the external road input changes at the current time: closes
    /// the run there. Returns the time from which the new input applies:
    /// the committed point when the current time snaps to it (a time drift
    /// is not a different time), else the current time, which then becomes
    /// the committed point (its filter state and road-holding accumulators
    /// with it).
    pub(super) fn close_run_for_input(&mut self) -> f64 {
        let (tc, t) = (self.trajectory.committed_time, self.trajectory.current_time);
        if self.snaps(t, tc) {
            self.observers
                .close_run_at_committed(&mut stepping!(self), &self.trajectory.committed());
        } else {
            self.close_run_here();
        }
        self.trajectory.committed_time
    }

    /// Commits the current time, however close to the committed point it
    /// is (a switch of the tire's contact, a change of the road input):
    /// it becomes the committed point, with its filter state and
    /// road-holding accumulators, and the run closes there.
    pub(super) fn close_run_here(&mut self) {
        self.settle();
        if self.trajectory.current_time == self.trajectory.committed_time {
            self.observers
                .close_run_at_committed(&mut stepping!(self), &self.trajectory.committed());
            return;
        }
        let now = self.accumulated_now();
        self.observers.integral.closed = now.integral;
        self.observers.holding = now.holding;
        if self.config.metrics.road_holding() {
            self.observers
                .holding
                .add_node(&self.trajectory.current_state.into());
        }
        self.trajectory.commit_current(now.filter);
        self.observers
            .start_run(self.trajectory.grid_index, self.trajectory.committed_time);
    }

    /// The view of this simulator that runs its whole steps
    /// ([`whole_steps::WholeSteps`]).
    #[inline]
    pub(super) fn whole_steps_view(&mut self) -> whole_steps::WholeSteps<'_> {
        whole_steps::WholeSteps {
            config: &self.config,
            plant: &self.plant,
            grid: self.grid,
            modes: &mut self.modes,
            inputs: &mut self.inputs,
            trajectory: &mut self.trajectory,
            observers: &mut self.observers,
        }
    }
}
