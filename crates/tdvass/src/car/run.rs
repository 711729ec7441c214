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
//! - **The time averages** (`averages`) are the quarter car's corrected
//!   trapezoid, `∫_a^b f = (b − a)/2 (f_a + f_b) − (b − a)²/12 (f'_b − f'_a)`,
//!   on the pieces between nodes and the kinks of the integrands (the rates
//!   one-sided, of the stretch's own inputs): a corner's `SDD²`, `TDD²`
//!   between its own road breakpoints and switches, the squares of the
//!   chassis's three accelerations and `a_w²`, `a_w⁴` at the seat between
//!   every corner's. The largest |SDD| is that of each piece's cubic
//!   Hermite interpolant.
//! - **The unilateral tire** of each corner switches where its contact
//!   margin `W_c/k_t − (x_t − x_g)` crosses zero: the crossing is bracketed
//!   by the margin's cubic Hermite interpolant over the stretch and then
//!   found by Newton's method on the exact partial step; the step goes on
//!   from there in the new mode. With the bilateral tire the crossings
//!   are counted and the time below zero measured on the interpolant.
//!
//! - **Mirror coordinates** (`mirror`): the state is kept as each left
//!   corner's and its right twin's half-sum and half-difference, so that a
//!   car whose right half mirrors its left, on the same road under both
//!   tracks, keeps its left and right equal to the bit (no roll out of
//!   rounding); twins whose contact margins are equal switch together.
//!
//! With the default chassis (`I_θ = m a b`, the centre of gravity midway)
//! and the same road on both tracks, the car's four corners are four
//! quarter cars; since the car takes the quarter car's grid and its
//! every approximation, each corner's RMS values equal the quarter car's
//! to rounding (`tests/car.rs`).
//!
//! Layer: the car's run; it imports the car's `layout`, `mirror`, `maps`,
//! `crossings` and `averages`, the solver's grid, and the crate's
//! `error`, `model` and `road`.

use super::averages::{
    ACCELERATION, ALL_GROUPS, Accumulated, CHASSIS_GROUP, Contact, DEFLECTION, GROUPS, INTEGRALS,
    Point, TIRE, WEIGHTED_SQUARE,
};
use super::crossings::first_crossing;
use super::layout::{
    CORNERS, CarSystem, DELAY_ORDER, INPUTS, ROAD_ORDER, STATES, check_divergence, delay_input,
    road_input, slot,
};
use super::maps::{Maps, StretchMap};
use super::mirror::{Mirrored, corner_coordinates, corner_value, mirror_matrix};
use crate::error::{Error, Result};
use crate::model::dynamics::hermite;
use crate::model::{V_T, X_T};
use crate::road::Road;
use crate::solver::{DelayGrid, DelayRegime};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use std::collections::VecDeque;

/// The wheels' `[x_t, v_t]` at a node.
type WheelNodes = [[f64; 2]; CORNERS];
/// The unknown wheel states at the step's end node (delay inside the step).
const UNKNOWNS: usize = 2 * CORNERS;
/// Most tire switches inside one step.
const MAX_SWITCHES_PER_STEP: usize = 64;

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

/// A run of the full car.
#[derive(Debug, Clone)]
pub(super) struct Run {
    system: CarSystem,
    mirrored: Mirrored,
    grid: DelayGrid,
    start: f64,
    roads: [Road; CORNERS],
    harmonic: bool,
    unilateral: bool,
    maps: Maps,
    /// Each mode's matrix, in mirror coordinates.
    mode_matrices: Vec<Option<DMatrix<f64>>>,
    /// The committed node's state, in mirror coordinates.
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
            mirrored: Mirrored::new(&system),
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
        let s = &self.mirrored;
        let seat = &s.seat_row * &self.x;
        CarSample {
            time: self.node_time(self.node),
            position: [self.x[0], self.x[1], self.x[2]],
            suspension_deflection: std::array::from_fn(|c| (&s.deflection_rows[c] * &self.x)[0]),
            seat_acceleration: seat[0],
        }
    }

    /// The matrix of `mode` in mirror coordinates, made once.
    fn mode_matrix(&mut self, mode: u8) -> &DMatrix<f64> {
        let (system, states) = (&self.system, &self.mirrored.states);
        self.mode_matrices[mode as usize]
            .get_or_insert_with(|| mirror_matrix(&system.mode_matrix(mode), states, states))
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
        // Where each group's time averages started their current piece: a
        // stretch end closes the groups whose integrands may have a kink
        // there (`Stretch::closes`), a tire's switch the switching
        // corners' and the chassis's, as the quarter car closes its runs.
        let mut open: [Option<(f64, Point)>; GROUPS] = [None; GROUPS];
        for _ in 0..=MAX_SWITCHES_PER_STEP {
            let stretches = self.resolve(from, &x_from)?;
            let mut switched = None;
            for stretch in stretches.iter().filter(|s| s.from < end) {
                let to = stretch.to.min(end);
                if open.iter().any(Option::is_none) {
                    let start = self.point(stretch.from, &stretch.x_from, stretch, self.flight);
                    for slot in open.iter_mut().filter(|o| o.is_none()) {
                        *slot = Some((stretch.from, start));
                    }
                }
                if let Some((at, x_at, corners)) = self.switch_in(stretch, to)? {
                    let stop = self.point(at, &x_at, stretch, self.flight);
                    let closing = corners | 1 << CHASSIS_GROUP;
                    for (group, start) in open.iter_mut().enumerate() {
                        if closing & (1 << group) != 0 {
                            let (from, start) = start.take().expect("every group is open");
                            self.accumulated.add(
                                group,
                                at - from,
                                &start,
                                &stop,
                                self.contact(group),
                            );
                        }
                    }
                    self.flip(corners);
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
                        self.accumulated
                            .add(group, to - from, &point, &stop, self.contact(group));
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
        check_divergence(&corner_coordinates(&x), time)?;
        if end < h * (1.0 - 1e-12) {
            return Ok(());
        }
        self.node += 1;
        self.system
            .set_oscillator(&mut x, self.node_time(self.node));
        let wheels = std::array::from_fn(|c| [corner_value(&x, c, X_T), corner_value(&x, c, V_T)]);
        self.x = x;
        self.history.push_back(wheels);
        let depth = self.grid.delay_steps() as usize + 1;
        while self.history.len() > depth {
            self.history.pop_front();
        }
        Ok(())
    }

    /// How group `group`'s tire meets the road now (none for the chassis).
    fn contact(&self, group: usize) -> Contact {
        if group >= CORNERS {
            Contact::None
        } else if !self.unilateral {
            Contact::Bilateral
        } else if self.flight & (1 << group) != 0 {
            Contact::Flight
        } else {
            Contact::Ground
        }
    }

    /// The tires of `corners` (bit c: corner c) switch mode.
    fn flip(&mut self, corners: u8) {
        for c in (0..CORNERS).filter(|c| corners & (1 << c) != 0) {
            if self.flight & (1 << c) == 0 {
                self.accumulated.lift_offs[c] += 1;
            }
        }
        self.flight ^= corners;
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
        // The end-node wheels in their own coordinates, for the inputs.
        let wheels = self.mirrored.unknowns.restored(&y);
        for (a, b, x0, m, known, unknown, x_to, m_to) in affine {
            stretches.push(Stretch {
                from: a,
                to: b,
                x_from: x0 + m * &y,
                x_to: x_to + m_to * &y,
                inputs: known + unknown * &wheels,
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
        // Each input's value at s, in its value's place.
        let mut now = DVector::<f64>::zeros(INPUTS);
        for c in 0..CORNERS {
            let road = road_input(c);
            now[road] = w[road] + w[road + 1] * s;
            let d = delay_input(c);
            now[d] = w[d] + s * (w[d + 1] + s * (w[d + 2] / 2.0 + s * w[d + 3] / 6.0));
        }
        self.mirrored.inputs.halve(now.as_mut_slice());
        let rate = self.mode_matrix(mode) * x + &self.mirrored.input_columns * now;
        let t_node = self.node_time(self.node);
        let t = t_node + at;
        // The stretch's own road piece: one-sided at a breakpoint.
        let middle = t_node + 0.5 * (stretch.from + stretch.to);
        let pieces: [_; CORNERS] = std::array::from_fn(|c| self.roads[c].piece(middle));
        let (system, rows) = (&self.system, &self.mirrored);
        let mut value = [0.0; INTEGRALS - 1];
        let mut rates = [0.0; INTEGRALS - 1];
        let mut margin = [[0.0; 2]; CORNERS];
        for c in 0..CORNERS {
            value[DEFLECTION + c] = (&rows.deflection_rows[c] * x)[0];
            rates[DEFLECTION + c] = (&rows.deflection_rows[c] * &rate)[0];
            let piece = pieces[c];
            let tire = corner_value(x, c, X_T) - piece.value(t);
            let tire_rate = corner_value(x, c, V_T) - piece.slope(t);
            value[TIRE + c] = tire;
            rates[TIRE + c] = tire_rate;
            margin[c] = [system.limits[c] - tire, -tire_rate];
        }
        for i in 0..3 {
            value[ACCELERATION + i] = (&rows.acceleration_rows[i] * x)[0];
            rates[ACCELERATION + i] = (&rows.acceleration_rows[i] * &rate)[0];
        }
        value[WEIGHTED_SQUARE] = (&rows.weighted_row * x)[0];
        rates[WEIGHTED_SQUARE] = (&rows.weighted_row * &rate)[0];
        Point {
            value,
            rate: rates,
            margin,
        }
    }

    /// The first switch of a unilateral tire in `stretch` up to `to`: its
    /// offset, the state there and the corners that switch (bit c: corner
    /// c): the first to cross and every corner in the same mode whose
    /// contact margin is the same to the bit at both ends of the stretch,
    /// on the same road (a twin, when the car mirrors itself).
    fn switch_in(&mut self, stretch: &Stretch, to: f64) -> Result<Option<(f64, DVector<f64>, u8)>> {
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
            let tire = corner_value(&stretch.x_from, c, X_T);
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
        let t_middle = self.node_time(self.node) + 0.5 * (stretch.from + stretch.to);
        let own_piece = self.roads[corner].piece(t_middle);
        let mut corners = 0u8;
        for c in 0..CORNERS {
            let same_mode = (self.flight >> c & 1) == (self.flight >> corner & 1);
            if c == corner
                || (same_mode
                    && a.margin[c] == a.margin[corner]
                    && b.margin[c] == b.margin[corner]
                    && self.roads[c].piece(t_middle) == own_piece)
            {
                corners |= 1 << c;
            }
        }
        // Newton's method on the exact partial step.
        let t_node = self.node_time(self.node);
        for _ in 0..4 {
            let x = StretchMap::new(&self.system, self.flight, s)
                .apply(&stretch.x_from, &stretch.inputs);
            let t = t_node + stretch.from + s;
            let piece = self.roads[corner].piece(t_node + 0.5 * (stretch.from + stretch.to));
            let margin =
                self.system.limits[corner] - (corner_value(&x, corner, X_T) - piece.value(t));
            let rate = -(corner_value(&x, corner, V_T) - piece.slope(t));
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
        Ok(Some((stretch.from + s, x, corners)))
    }
}
