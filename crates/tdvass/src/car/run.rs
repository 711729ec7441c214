//! The full car's integration: the precise integration of the quarter
//! car's solver (`crate::solver`), step for step, on the whole car.
//!
//! - **The grid** is the quarter car's ([`DelayGrid`]): `t_k = t_0 + k h`,
//!   the delay resolved as whole steps (`tau = m h`), inside the step
//!   (`0 < tau < h`: the step is split at tau, the end node entering its
//!   own interpolant through a linear solve, here for the four wheels at
//!   once), or folded into A.
//! - **The delayed input** of each corner is the cubic Hermite interpolant
//!   of its wheel's `x_t`, `v_t` at the history nodes
//!   (`model::dynamics::hermite`), as in the quarter car; before the start
//!   the history is the state at rest.
//! - **The roads** are exact: a random road's straight pieces (a step is
//!   split where a piece ends inside it: a rear wheel's breakpoints, delayed
//!   by the wheelbase over the speed), the harmonic road through the
//!   exosystem, reset to `sin ω t_k`, `cos ω t_k` at every node.
//! - **The time averages** are the quarter car's corrected trapezoid,
//!   `∫_a^b f = (b − a)/2 (f_a + f_b) − (b − a)²/12 (f'_b − f'_a)`, on
//!   every stretch between nodes, road breakpoints and switches (the
//!   rates one-sided, of the stretch's own inputs), of `SDD²`, `TDD²` of
//!   each corner, the squares of the chassis's three accelerations, and
//!   `a_w²`, `a_w⁴` at the seat. The largest |SDD| is that of each
//!   stretch's cubic Hermite interpolant.
//! - **The unilateral tire** of each corner switches where its contact
//!   margin `W_c/k_t − (x_t − x_g)` crosses zero: the crossing is bracketed
//!   by the margin's cubic Hermite interpolant over the stretch and then
//!   found by Newton's method on the exact partial step; the step goes on
//!   from there in the new mode. With the bilateral tire the crossings
//!   are counted and the time below zero measured on the interpolant.
//!
//! With the default chassis (`I_θ = m a b`, the centre of gravity midway)
//! and the same road on both tracks, the car's four corners are four
//! quarter cars; since the car takes the quarter car's grid and its
//! every approximation, each corner's RMS values equal the quarter car's
//! to rounding (`tests/car.rs`).
//!
//! Layer: the car's run; it imports the car's `layout`, `maps` and
//! `crossings`, the solver's grid and `largest_magnitude`, and the crate's
//! `error`, `model` and `road`.

use super::crossings::{below_zero, first_crossing};
use super::layout::{
    CORNERS, CarSystem, DELAY_ORDER, INPUTS, ROAD_ORDER, STATES, check_divergence, delay_input,
    road_input, slot,
};
use super::maps::{Maps, StretchMap};
use crate::error::{Error, Result};
use crate::model::dynamics::hermite;
use crate::model::{V_T, X_T};
use crate::road::Road;
use crate::solver::{DelayGrid, DelayRegime, largest_magnitude};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use std::collections::VecDeque;

/// The wheels' `[x_t, v_t]` at a node.
type WheelNodes = [[f64; 2]; CORNERS];
/// The unknown wheel states at the step's end node (delay inside the step).
const UNKNOWNS: usize = 2 * CORNERS;
/// The integrals kept: `SDD²` and `TDD²` of each corner, the squares of
/// `z''`, `θ''`, `φ''`, and `a_w²`, `a_w⁴`.
pub(super) const INTEGRALS: usize = 2 * CORNERS + 3 + 2;
/// Index of `∫ SDD²` of corner 0 (then `TDD²` at `CORNERS`, the
/// accelerations at `2 CORNERS`).
const DEFLECTION: usize = 0;
const TIRE: usize = CORNERS;
const ACCELERATION: usize = 2 * CORNERS;
const WEIGHTED_SQUARE: usize = 2 * CORNERS + 3;
const WEIGHTED_FOURTH: usize = 2 * CORNERS + 4;
/// The groups of time averages: each corner's, then the chassis's.
const GROUPS: usize = CORNERS + 1;
/// The chassis's group.
const CHASSIS_GROUP: usize = CORNERS;
/// Every group's bit.
const ALL_GROUPS: u8 = (1 << GROUPS) - 1;
/// Most tire switches inside one step.
const MAX_SWITCHES_PER_STEP: usize = 64;

/// What a run accumulates.
#[derive(Debug, Clone, Default)]
pub(super) struct Accumulated {
    /// The integrals ([`INTEGRALS`]).
    pub integrals: [f64; INTEGRALS],
    /// The largest |SDD| of each corner (m).
    pub max_deflection: [f64; CORNERS],
    /// The time each tire had no contact (s).
    pub loss_time: [f64; CORNERS],
    /// Each tire's lift-offs.
    pub lift_offs: [u64; CORNERS],
}

impl Accumulated {
    /// `∫ SDD²` of corner c.
    pub fn deflection(&self, c: usize) -> f64 {
        self.integrals[DEFLECTION + c]
    }
    /// `∫ TDD²` of corner c.
    pub fn tire(&self, c: usize) -> f64 {
        self.integrals[TIRE + c]
    }
    /// `∫` of the square of the chassis's acceleration i (heave, pitch, roll).
    pub fn acceleration(&self, i: usize) -> f64 {
        self.integrals[ACCELERATION + i]
    }
    /// `∫ a_w²` and `∫ a_w⁴`.
    pub fn weighted(&self) -> (f64, f64) {
        (
            self.integrals[WEIGHTED_SQUARE],
            self.integrals[WEIGHTED_FOURTH],
        )
    }
}

/// The car at a committed node, for a time history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarSample {
    /// t (s).
    pub time: f64,
    /// `[z (m), θ (rad), φ (rad)]`.
    pub position: [f64; 3],
    /// SDD of each corner (m).
    pub suspension_deflection: [f64; CORNERS],
    /// The seat's vertical acceleration (m/s²).
    pub seat_acceleration: f64,
}

/// A stretch of a step: `[from, to]` (offsets from the step's node), the
/// states at its ends and its inputs' Taylor coefficients at `from`.
#[derive(Debug, Clone)]
struct Stretch {
    from: f64,
    to: f64,
    x_from: DVector<f64>,
    x_to: DVector<f64>,
    inputs: DVector<f64>,
    /// The groups ([`GROUPS`]) whose time averages end a piece at `to`:
    /// all at the step's end; at a wheel's road breakpoint that corner's
    /// and the chassis's; none at `t_k + tau` alone.
    closes: u8,
}

/// The outputs the integrals need at an instant, with their rates.
#[derive(Debug, Clone, Copy)]
struct Point {
    /// The integrands' outputs y: SDD, TDD of each corner, the three
    /// accelerations, a_w.
    value: [f64; INTEGRALS - 1],
    rate: [f64; INTEGRALS - 1],
    /// Each corner's contact margin and its rate.
    margin: [[f64; 2]; CORNERS],
}

/// A run of the full car.
#[derive(Debug, Clone)]
pub(super) struct Run {
    system: CarSystem,
    grid: DelayGrid,
    start: f64,
    roads: [Road; CORNERS],
    harmonic: bool,
    unilateral: bool,
    maps: Maps,
    mode_matrices: Vec<Option<DMatrix<f64>>>,
    x: DVector<f64>,
    node: u64,
    flight: u8,
    history: VecDeque<WheelNodes>,
    pub accumulated: Accumulated,
}

impl Run {
    /// A car at rest at `start`, on the corners' `roads`.
    pub fn new(
        system: CarSystem,
        grid: DelayGrid,
        start: f64,
        roads: [Road; CORNERS],
        unilateral: bool,
    ) -> Run {
        let harmonic = roads[0].harmonic().is_some();
        let mut x = DVector::zeros(STATES);
        system.set_oscillator(&mut x, start);
        let depth = grid.delay_steps() as usize + 1;
        let mut history = VecDeque::with_capacity(depth + 1);
        history.push_back([[0.0; 2]; CORNERS]);
        // A wheel at rest above its road's start (a delayed harmonic road)
        // starts without contact: a lift-off at the start, as the quarter
        // car counts it, and in flight with the unilateral tire.
        let mut roads = roads;
        let mut accumulated = Accumulated::default();
        let mut flight = 0;
        for (c, road) in roads.iter_mut().enumerate() {
            if system.limits[c] + road.piece(start).value(start) < 0.0 {
                accumulated.lift_offs[c] += 1;
                if unilateral {
                    flight |= 1 << c;
                }
            }
        }
        Run {
            system,
            grid,
            start,
            roads,
            harmonic,
            unilateral,
            maps: Maps::default(),
            mode_matrices: vec![None; 1 << CORNERS],
            x,
            node: 0,
            flight,
            history,
            accumulated,
        }
    }

    /// The internal step h (s).
    pub fn step(&self) -> f64 {
        self.grid.step
    }

    /// The committed node's time.
    fn node_time(&self, node: u64) -> f64 {
        self.start + node as f64 * self.grid.step
    }

    /// Runs `duration` (s) from the start, calling `sample` at every
    /// `every`-th node (0: never).
    pub fn run(
        &mut self,
        duration: f64,
        every: u64,
        sample: &mut dyn FnMut(CarSample),
    ) -> Result<()> {
        let h = self.grid.step;
        let end = self.start + duration;
        let whole = ((duration / h) * (1.0 + 1e-12)).floor() as u64;
        if every > 0 {
            sample(self.sample());
        }
        while self.node < whole {
            self.advance(h)?;
            if every > 0 && self.node.is_multiple_of(every) {
                sample(self.sample());
            }
        }
        let rest = end - self.node_time(self.node);
        if rest > 1e-9 * h {
            self.advance(rest.min(h))?;
        }
        Ok(())
    }

    /// The committed node as a sample.
    fn sample(&self) -> CarSample {
        let s = &self.system;
        let seat = &s.seat_row * &self.x;
        CarSample {
            time: self.node_time(self.node),
            position: [self.x[0], self.x[1], self.x[2]],
            suspension_deflection: std::array::from_fn(|c| (&s.deflection_rows[c] * &self.x)[0]),
            seat_acceleration: seat[0],
        }
    }

    /// The matrix of `mode`, made once.
    fn mode_matrix(&mut self, mode: u8) -> &DMatrix<f64> {
        let system = &self.system;
        self.mode_matrices[mode as usize].get_or_insert_with(|| system.mode_matrix(mode))
    }

    /// The wheels at node `j` (the state at rest before the start).
    fn wheels(&self, j: i64) -> WheelNodes {
        let oldest = self.node as i64 - (self.history.len() as i64 - 1);
        if j < oldest.max(0) {
            [[0.0; 2]; CORNERS]
        } else {
            self.history[(j - oldest) as usize]
        }
    }

    /// One step from the committed node, integrated up to `end` (h: the
    /// next node is committed; less: the run's last stretch).
    fn advance(&mut self, end: f64) -> Result<()> {
        let mut from = 0.0;
        let mut x_from = self.x.clone();
        for _ in 0..=MAX_SWITCHES_PER_STEP {
            let stretches = self.resolve(from, &x_from)?;
            let mut switched = None;
            // Where each group's time averages started their current
            // piece: a stretch end closes the groups whose integrands may
            // have a kink there (`Stretch::closes`), as the quarter car
            // closes its runs.
            let mut open: [Option<(f64, Point)>; GROUPS] = [None; GROUPS];
            for stretch in stretches.iter().filter(|s| s.from < end) {
                let to = stretch.to.min(end);
                if open.iter().any(Option::is_none) {
                    let start = self.point(stretch.from, &stretch.x_from, stretch, self.flight);
                    for slot in open.iter_mut().filter(|o| o.is_none()) {
                        *slot = Some((stretch.from, start));
                    }
                }
                if let Some((at, x_at, corner)) = self.switch_in(stretch, to)? {
                    let stop = self.point(at, &x_at, stretch, self.flight);
                    for (group, start) in open.iter().enumerate() {
                        let (from, start) = start.expect("every group is open");
                        self.accumulate(group, at - from, &start, &stop);
                    }
                    self.flip(corner);
                    switched = Some((at, x_at));
                    break;
                }
                let closes = if to < stretch.to {
                    ALL_GROUPS
                } else {
                    stretch.closes
                };
                if closes == 0 {
                    continue;
                }
                let x_to = if to < stretch.to {
                    StretchMap::new(&self.system, self.flight, to - stretch.from)
                        .apply(&stretch.x_from, &stretch.inputs)
                } else {
                    stretch.x_to.clone()
                };
                let stop = self.point(to, &x_to, stretch, self.flight);
                for (group, start) in open.iter_mut().enumerate() {
                    if closes & (1 << group) != 0 {
                        let (from, point) = start.take().expect("every group is open");
                        self.accumulate(group, to - from, &point, &stop);
                    }
                }
            }
            match switched {
                Some((at, x_at)) if at < end * (1.0 - 1e-12) => {
                    from = at;
                    x_from = x_at;
                }
                Some((_, x_at)) => return self.commit(end, x_at),
                None => {
                    let x_end = stretches.last().map_or(x_from, |s| s.x_to.clone());
                    return self.commit(end, x_end);
                }
            }
        }
        Err(Error::InvalidTime {
            name: "time",
            value: self.node_time(self.node),
            reason: "more tire switches inside one internal step than the car locates (64)",
        })
    }

    /// Commits the node at the step's end (a whole step) after checking
    /// the state.
    fn commit(&mut self, end: f64, mut x: DVector<f64>) -> Result<()> {
        let h = self.grid.step;
        let time = self.node_time(self.node) + end;
        check_divergence(&x, time)?;
        if end < h * (1.0 - 1e-12) {
            return Ok(());
        }
        self.node += 1;
        self.system
            .set_oscillator(&mut x, self.node_time(self.node));
        let wheels = std::array::from_fn(|c| [x[slot(c, X_T)], x[slot(c, V_T)]]);
        self.x = x;
        self.history.push_back(wheels);
        let depth = self.grid.delay_steps() as usize + 1;
        while self.history.len() > depth {
            self.history.pop_front();
        }
        Ok(())
    }

    /// The tire of `corner` switches mode.
    fn flip(&mut self, corner: usize) {
        if self.flight & (1 << corner) == 0 {
            self.accumulated.lift_offs[corner] += 1;
        }
        self.flight ^= 1 << corner;
    }

    /// The stretches from `from` to the step's end, in the current mode,
    /// with their states resolved (module documentation).
    fn resolve(&mut self, from: f64, x_from: &DVector<f64>) -> Result<Vec<Stretch>> {
        let h = self.grid.step;
        let t_node = self.node_time(self.node);
        let tolerance = 1e-9 * h;
        let mut cuts = vec![from, h];
        let mut road_cuts = Vec::new();
        if !self.harmonic {
            for (corner, road) in self.roads.iter_mut().enumerate() {
                let mut at = from;
                loop {
                    let end = road.piece(t_node + at + tolerance).end() - t_node;
                    if end >= h - tolerance {
                        break;
                    }
                    road_cuts.push((end, corner));
                    at = end;
                }
            }
        }
        cuts.extend(road_cuts.iter().map(|(cut, _)| *cut));
        if let DelayRegime::InsideStep { tau } = self.grid.regime
            && tau > from + tolerance
        {
            cuts.push(tau);
        }
        let closes = |b: f64| -> u8 {
            if b >= h - tolerance {
                return ALL_GROUPS;
            }
            road_cuts
                .iter()
                .filter(|(cut, _)| (cut - b).abs() <= tolerance)
                .fold(0, |mask, (_, corner)| {
                    mask | 1 << corner | 1 << CHASSIS_GROUP
                })
        };
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|b, a| *b - *a <= tolerance);
        let mode = self.flight;
        let mut stretches = Vec::with_capacity(cuts.len());
        // States affine in the unknown end-node wheels (delay inside the
        // step): x = x0 + M y, inputs = n0 + N y.
        let mut x0 = x_from.clone();
        let mut m = DMatrix::<f64>::zeros(STATES, UNKNOWNS);
        let mut affine = Vec::with_capacity(cuts.len());
        for pair in cuts.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (known, unknown) = self.inputs(a, b);
            let map = self.maps.get(&self.system, mode, b - a, h);
            let x_to = map.apply(&x0, &known);
            let m_to = map.apply_columns(&m, &unknown);
            affine.push((
                a,
                b,
                x0.clone(),
                m.clone(),
                known,
                unknown,
                x_to.clone(),
                m_to.clone(),
            ));
            x0 = x_to;
            m = m_to;
        }
        let y = if m.iter().any(|v| *v != 0.0) {
            let mut system = SMatrix::<f64, UNKNOWNS, UNKNOWNS>::identity();
            let mut rhs = SVector::<f64, UNKNOWNS>::zeros();
            for c in 0..CORNERS {
                for (k, local) in [X_T, V_T].into_iter().enumerate() {
                    let row = 2 * c + k;
                    rhs[row] = x0[slot(c, local)];
                    for j in 0..UNKNOWNS {
                        system[(row, j)] -= m[(slot(c, local), j)];
                    }
                }
            }
            let solved = system.lu().solve(&rhs).ok_or(Error::InvalidParameter {
                name: "tau",
                value: self.grid.inner_delay(),
                reason: "the step's end node has no solution with the delay inside the step",
            })?;
            DVector::from_column_slice(solved.as_slice())
        } else {
            DVector::zeros(UNKNOWNS)
        };
        for (a, b, x0, m, known, unknown, x_to, m_to) in affine {
            stretches.push(Stretch {
                from: a,
                to: b,
                x_from: x0 + m * &y,
                x_to: x_to + m_to * &y,
                inputs: known + unknown * &y,
                closes: closes(b),
            });
        }
        Ok(stretches)
    }

    /// The inputs' Taylor coefficients at `a` over `[a, b]`: the known part
    /// and, with the delay inside the step, the part per unknown end-node
    /// wheel state.
    fn inputs(&mut self, a: f64, b: f64) -> (DVector<f64>, DMatrix<f64>) {
        let h = self.grid.step;
        let t_node = self.node_time(self.node);
        let mut known = DVector::zeros(INPUTS);
        let mut unknown = DMatrix::zeros(INPUTS, UNKNOWNS);
        for c in 0..CORNERS {
            let road = road_input(c);
            if self.flight & (1 << c) != 0 {
                known[road] = -self.system.limits[c];
            } else if !self.harmonic {
                let t = t_node + a;
                let piece = self.roads[c].piece(t_node + 0.5 * (a + b));
                known[road] = piece.value(t);
                known[road + 1] = piece.slope(t);
            }
            debug_assert_eq!(ROAD_ORDER, 2);
        }
        let k = self.node as i64;
        let delayed = |nodes: [f64; 4], offset: f64| hermite(nodes, h, offset);
        for c in 0..CORNERS {
            let at = delay_input(c);
            let coefficients = match self.grid.regime {
                DelayRegime::Folded => [0.0; DELAY_ORDER],
                DelayRegime::WholeSteps { m } => {
                    let (left, right) = (self.wheels(k - m as i64), self.wheels(k - m as i64 + 1));
                    delayed([left[c][0], left[c][1], right[c][0], right[c][1]], a)
                }
                DelayRegime::InsideStep { tau } if b <= tau + 1e-9 * h => {
                    let (left, right) = (self.wheels(k - 1), self.wheels(k));
                    delayed(
                        [left[c][0], left[c][1], right[c][0], right[c][1]],
                        h - tau + a,
                    )
                }
                DelayRegime::InsideStep { tau } => {
                    let left = self.wheels(k);
                    let offset = a - tau;
                    let per_position = delayed([0.0, 0.0, 1.0, 0.0], offset);
                    let per_velocity = delayed([0.0, 0.0, 0.0, 1.0], offset);
                    for p in 0..DELAY_ORDER {
                        unknown[(at + p, 2 * c)] = per_position[p];
                        unknown[(at + p, 2 * c + 1)] = per_velocity[p];
                    }
                    delayed([left[c][0], left[c][1], 0.0, 0.0], offset)
                }
            };
            for (p, value) in coefficients.iter().enumerate() {
                known[at + p] = *value;
            }
        }
        (known, unknown)
    }

    /// The outputs and their rates at offset `at` of the step, state `x`,
    /// inside `stretch` (whose inputs and `mode` give the rates).
    fn point(&mut self, at: f64, x: &DVector<f64>, stretch: &Stretch, mode: u8) -> Point {
        let s = at - stretch.from;
        let w = &stretch.inputs;
        let mut rate = self.mode_matrix(mode) * x;
        for c in 0..CORNERS {
            let road = road_input(c);
            let r = w[road] + w[road + 1] * s;
            let d = delay_input(c);
            let u = w[d] + s * (w[d + 1] + s * (w[d + 2] / 2.0 + s * w[d + 3] / 6.0));
            rate += &self.system.road_columns[c] * r + &self.system.delay_columns[c] * u;
        }
        let t_node = self.node_time(self.node);
        let t = t_node + at;
        // The stretch's own road piece: one-sided at a breakpoint.
        let middle = t_node + 0.5 * (stretch.from + stretch.to);
        let pieces: [_; CORNERS] = std::array::from_fn(|c| self.roads[c].piece(middle));
        let system = &self.system;
        let mut value = [0.0; INTEGRALS - 1];
        let mut rates = [0.0; INTEGRALS - 1];
        let mut margin = [[0.0; 2]; CORNERS];
        for c in 0..CORNERS {
            value[DEFLECTION + c] = (&system.deflection_rows[c] * x)[0];
            rates[DEFLECTION + c] = (&system.deflection_rows[c] * &rate)[0];
            let piece = pieces[c];
            let tire = x[slot(c, X_T)] - piece.value(t);
            let tire_rate = x[slot(c, V_T)] - piece.slope(t);
            value[TIRE + c] = tire;
            rates[TIRE + c] = tire_rate;
            margin[c] = [system.limits[c] - tire, -tire_rate];
        }
        for i in 0..3 {
            value[ACCELERATION + i] = (&system.acceleration_rows[i] * x)[0];
            rates[ACCELERATION + i] = (&system.acceleration_rows[i] * &rate)[0];
        }
        value[WEIGHTED_SQUARE] = (&system.weighted_row * x)[0];
        rates[WEIGHTED_SQUARE] = (&system.weighted_row * &rate)[0];
        Point {
            value,
            rate: rates,
            margin,
        }
    }

    /// Adds a piece of `length` between the points `a` and `b` to the
    /// time averages of `group` (a corner's SDD², TDD², largest |SDD| and
    /// contact; the chassis's accelerations and a_w).
    fn accumulate(&mut self, group: usize, length: f64, a: &Point, b: &Point) {
        let acc = &mut self.accumulated;
        let trapezoid = |f: [f64; 2], g: [f64; 2]| {
            length / 2.0 * (f[0] + g[0]) - length * length / 12.0 * (g[1] - f[1])
        };
        let square = |p: &Point, i: usize| [p.value[i] * p.value[i], 2.0 * p.value[i] * p.rate[i]];
        if group == CHASSIS_GROUP {
            for i in ACCELERATION..WEIGHTED_SQUARE + 1 {
                acc.integrals[i] += trapezoid(square(a, i), square(b, i));
            }
            let fourth = |p: &Point| {
                let y = p.value[WEIGHTED_SQUARE];
                [y * y * y * y, 4.0 * y * y * y * p.rate[WEIGHTED_SQUARE]]
            };
            acc.integrals[WEIGHTED_FOURTH] += trapezoid(fourth(a), fourth(b));
            return;
        }
        let c = group;
        for i in [DEFLECTION + c, TIRE + c] {
            acc.integrals[i] += trapezoid(square(a, i), square(b, i));
        }
        let i = DEFLECTION + c;
        let largest = largest_magnitude(length, [a.value[i], a.rate[i]], [b.value[i], b.rate[i]]);
        acc.max_deflection[c] = acc.max_deflection[c].max(largest);
        if self.unilateral {
            if self.flight & (1 << c) != 0 {
                acc.loss_time[c] += length;
            }
        } else {
            let (below, downs) = below_zero(length, a.margin[c], b.margin[c]);
            acc.loss_time[c] += below;
            acc.lift_offs[c] += downs;
        }
    }

    /// The first switch of a unilateral tire in `stretch` up to `to`: its
    /// offset, the state there and the corner.
    fn switch_in(
        &mut self,
        stretch: &Stretch,
        to: f64,
    ) -> Result<Option<(f64, DVector<f64>, usize)>> {
        if !self.unilateral {
            return Ok(None);
        }
        let length = to - stretch.from;
        let x_to = if to < stretch.to {
            StretchMap::new(&self.system, self.flight, length)
                .apply(&stretch.x_from, &stretch.inputs)
        } else {
            stretch.x_to.clone()
        };
        let a = self.point(stretch.from, &stretch.x_from, stretch, self.flight);
        let b = self.point(to, &x_to, stretch, self.flight);
        let mut first: Option<(f64, usize)> = None;
        for c in 0..CORNERS {
            let falling = self.flight & (1 << c) == 0;
            // Within rounding of 0 a margin is on the side it moves to (a
            // corner that crosses with another, as the two of an axle do on
            // the same road, switches with it).
            let tire = stretch.x_from[slot(c, X_T)];
            let rounding = 64.0
                * f64::EPSILON
                * (self.system.limits[c]
                    + tire.abs()
                    + (self.system.limits[c] - tire - a.margin[c][0]).abs());
            let mut start = a.margin[c];
            let toward = if falling {
                start[1] < 0.0
            } else {
                start[1] > 0.0
            };
            if start[0].abs() <= rounding && toward {
                start[0] = 0.0;
            }
            if let Some(s) = first_crossing(length, start, b.margin[c], falling)
                && first.is_none_or(|(f, _)| s < f)
            {
                first = Some((s, c));
            }
        }
        let Some((mut s, corner)) = first else {
            return Ok(None);
        };
        // Newton's method on the exact partial step.
        let t_node = self.node_time(self.node);
        for _ in 0..4 {
            let x = StretchMap::new(&self.system, self.flight, s)
                .apply(&stretch.x_from, &stretch.inputs);
            let t = t_node + stretch.from + s;
            let piece = self.roads[corner].piece(t_node + 0.5 * (stretch.from + stretch.to));
            let margin = self.system.limits[corner] - (x[slot(corner, X_T)] - piece.value(t));
            let rate = -(x[slot(corner, V_T)] - piece.slope(t));
            if rate == 0.0 || !rate.is_finite() {
                break;
            }
            let next = (s - margin / rate).clamp(0.0, length);
            let moved = (next - s).abs();
            s = next;
            if moved <= 1e-15 * self.grid.step {
                break;
            }
        }
        let x =
            StretchMap::new(&self.system, self.flight, s).apply(&stretch.x_from, &stretch.inputs);
        Ok(Some((stretch.from + s, x, corner)))
    }
}
