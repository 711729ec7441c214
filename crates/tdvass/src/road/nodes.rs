//! The random roads' node generator: node `n` at `origin + n · interval`,
//! `x_{n+1} = decay x_n + gain ξ_n` from a seeded generator, the window of
//! nodes kept, and the linear piece between two nodes.

use super::piece::RoadPiece;
use super::saved::RoadState;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;

/// Largest index of a random road node (2^53, where node indices stop
/// being exact in f64). The road holds the value of this node after its
/// time, so a piece lookup never needs node `n + 1` beyond it.
pub(super) const MAX_NODE: u64 = 1 << 53;

/// Room for generated road nodes made with the road.
pub(super) const NODE_WINDOW: usize = 64;
/// Nodes reserved beyond those of the span asked for
/// ([`super::Road::reserve_window`]).
pub(super) const NODE_MARGIN: usize = 8;
/// Most nodes [`super::Road::reserve_window`] reserves (8 MB of nodes).
pub(super) const MAX_RESERVED_NODES: usize = 1 << 20;

/// Random road node generator: node `n` is at `origin + n · interval`.
#[derive(Debug, Clone)]
pub(super) struct NodeSequence {
    pub(super) origin: f64,
    pub(super) interval: f64,
    /// `x_{n+1} = decay x_n + gain ξ_n` with ξ_n ~ N(0, 1).
    pub(super) decay: f64,
    pub(super) gain: f64,
    pub(super) seed: u64,
    pub(super) rng: ChaCha8Rng,
    /// Index of `nodes[0]`.
    pub(super) first: u64,
    pub(super) nodes: VecDeque<f64>,
}

impl NodeSequence {
    pub(super) fn new(
        origin: f64,
        interval: f64,
        decay: f64,
        gain: f64,
        seed: u64,
    ) -> NodeSequence {
        NodeSequence {
            origin,
            interval,
            decay,
            gain,
            seed,
            rng: ChaCha8Rng::seed_from_u64(seed),
            first: 0,
            nodes: Self::window(),
        }
    }

    /// The generated nodes at the start: node 0, with room for
    /// [`NODE_WINDOW`] (the solver releases the nodes behind its committed
    /// point as it goes, so a run keeps a few; generating them allocates
    /// nothing).
    pub(super) fn window() -> VecDeque<f64> {
        let mut nodes = VecDeque::with_capacity(NODE_WINDOW);
        nodes.push_back(0.0);
        nodes
    }

    pub(super) fn node_time(&self, n: u64) -> f64 {
        self.origin + n as f64 * self.interval
    }

    pub(super) fn node(&mut self, n: u64) -> f64 {
        debug_assert!(n >= self.first, "road node {n} was released");
        while self.first + self.nodes.len() as u64 <= n {
            let last = *self.nodes.back().unwrap_or(&0.0);
            let xi: f64 = StandardNormal.sample(&mut self.rng);
            self.nodes.push_back(self.decay * last + self.gain * xi);
        }
        self.nodes[(n - self.first.min(n)) as usize]
    }

    /// The node whose interval holds `t`: the largest `n <= MAX_NODE` with
    /// `node_time(n) <= t` (0 before the origin or for NaN). The floor of
    /// `(t − origin) / interval` is corrected against rounding by a bounded
    /// search, also where many nodes share one floating-point time (an
    /// interval below the spacing of floats at t).
    pub(super) fn index_at(&self, t: f64) -> u64 {
        // `as` saturates and maps NaN to 0; the search clamps to MAX_NODE.
        let estimate = ((t - self.origin) / self.interval).floor() as u64;
        crate::monotone::last_index_where(0, MAX_NODE, estimate, |n| self.node_time(n) <= t)
    }

    /// The linear piece whose `[start, end)` holds `t` (the first piece
    /// before the origin; from node [`MAX_NODE`] on, its value held).
    pub(super) fn piece(&mut self, t: f64) -> RoadPiece {
        let n = self.index_at(t).max(self.first);
        let (x0, start) = (self.node(n), self.node_time(n));
        if n >= MAX_NODE {
            return RoadPiece::Linear {
                start,
                end: f64::INFINITY,
                value: x0,
                slope: 0.0,
            };
        }
        let (x1, end) = (self.node(n + 1), self.node_time(n + 1));
        RoadPiece::Linear {
            start,
            end,
            value: x0,
            slope: (x1 - x0) / (end - start),
        }
    }

    /// Takes the generator's position and the nodes of `state`.
    pub(super) fn restore(&mut self, state: &RoadState) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.rng.set_word_pos(state.word_position);
        self.first = state.first_node;
        self.nodes = state.nodes.iter().copied().collect();
    }

    pub(super) fn release_before(&mut self, t: f64) {
        while self.nodes.len() > 2 && self.node_time(self.first + 1) <= t {
            self.nodes.pop_front();
            self.first += 1;
        }
    }
}
