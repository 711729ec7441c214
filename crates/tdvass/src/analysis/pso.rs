//! A generic particle swarm optimiser (PSO), section 2.3.2 of the paper,
//! used to choose the absorber parameters `(k_h, c_h)` (section 2.3) and the
//! time-delay feedback parameters `(g, tau)` (section 4.2).
//!
//! # Algorithm
//!
//! A swarm of `m` particles moves in a box `[lower, upper]` of `R^n`. Each
//! particle `i` has a position `X_i`, a velocity `V_i` and remembers its
//! individual best position `P_i`; the swarm shares the global best position
//! `P_g`. At iteration `k` every component `d` is updated with Eq. (7):
//!
//! ```text
//! V_id^{k+1} = w^k V_id^k + c1 r1 (P_id^k - X_id^k) + c2 r2 (P_gd^k - X_id^k)
//! X_id^{k+1} = X_id^k + V_id^{k+1}                                      (7)
//! ```
//!
//! where `w^k` is the inertia weight, `c1` (cognitive) and `c2` (social) are
//! the learning factors and `r1`, `r2` are uniform random numbers in
//! `[0, 1)`, drawn afresh for every particle, component and iteration.
//!
//! Implementation choices the paper leaves open:
//! - the inertia weight decreases linearly from
//!   [`PsoSettings::inertia_start`] at the first update to
//!   [`PsoSettings::inertia_end`] at the last one:
//!   `w^k = w_start - (w_start - w_end) k / (N - 1)`, `k = 0, ..., N - 1`
//!   (`w^0 = w_start` when `N = 1`);
//! - each velocity component is clamped to `|V_id| <= v_max,d` with
//!   `v_max,d = max_velocity_fraction * (upper_d - lower_d)`;
//! - a position leaving the box is clamped back onto the violated bound and
//!   that velocity component is set to zero ("absorbing wall"), so every
//!   evaluated candidate lies in `[lower, upper]`. For an open range such as
//!   the paper's `(0, k_s)` the caller passes slightly shrunk bounds;
//! - the update is synchronous: the whole swarm moves with the bests of the
//!   previous iteration, then all particles are evaluated (in parallel), then
//!   the individual bests and the global best are updated;
//! - an objective returning `None`, NaN or an infinite value marks an
//!   infeasible candidate (e.g. an unstable controller): it counts as
//!   `+infinity` and never becomes a best. While a particle (or the swarm)
//!   has no feasible best yet, the corresponding attraction term of Eq. (7)
//!   is left out (its random number is still drawn).
//!
//! # Determinism
//!
//! All random numbers (initial positions, initial velocities, `r1`, `r2`)
//! are drawn sequentially on the calling thread from a
//! [`ChaCha8Rng`] seeded with [`PsoSettings::seed`], in a fixed order
//! (particle by particle, component by component, `r1` before `r2`). Only
//! the objective evaluations run in parallel (rayon), and their results are
//! collected in particle order. Ties are broken deterministically: a best is
//! replaced only by a strictly smaller value, and the global best is the
//! first particle (lowest index) holding the smallest value. Hence, for a
//! deterministic objective, the same seed gives a bit-identical
//! [`PsoResult`] whatever the number of threads.

use rand::RngExt;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Settings of the particle swarm optimiser.
///
/// The default is the paper's swarm (section 4.2): 100 particles and 200
/// iterations, with the inertia weight decreasing linearly from 0.9 to 0.4,
/// learning factors `c1 = c2 = 1.49445`, velocities clamped to 20 % of each
/// dimension's range, and seed 1.
#[derive(Debug, Clone, PartialEq)]
pub struct PsoSettings {
    /// Number of particles `m` (at least 1).
    pub particles: usize,
    /// Number of iterations `N` (position updates after the initial swarm).
    pub iterations: usize,
    /// Inertia weight `w^k` at the first update (`k = 0`).
    pub inertia_start: f64,
    /// Inertia weight `w^k` at the last update (`k = N - 1`); the schedule is
    /// linear in between.
    pub inertia_end: f64,
    /// Cognitive learning factor `c1` (attraction to the individual best).
    pub cognitive: f64,
    /// Social learning factor `c2` (attraction to the global best).
    pub social: f64,
    /// Velocity clamp as a fraction of each dimension's range
    /// `upper_d - lower_d`; must be positive. Initial velocities are uniform
    /// in `[-v_max,d, v_max,d)`.
    pub max_velocity_fraction: f64,
    /// Seed of the [`ChaCha8Rng`] that draws every random number.
    pub seed: u64,
}

impl Default for PsoSettings {
    fn default() -> Self {
        Self {
            particles: 100,
            iterations: 200,
            inertia_start: 0.9,
            inertia_end: 0.4,
            cognitive: 1.49445,
            social: 1.49445,
            max_velocity_fraction: 0.2,
            seed: 1,
        }
    }
}

impl PsoSettings {
    /// Checks the settings: at least one particle, finite non-negative
    /// inertia weights and learning factors, and a finite positive velocity
    /// fraction.
    pub fn validate(&self) -> Result<()> {
        if self.particles == 0 {
            return Err(Error::InvalidSetting {
                name: "particles",
                value: 0,
                reason: "the swarm needs at least one particle",
            });
        }
        let non_negative = [
            ("inertia_start", self.inertia_start),
            ("inertia_end", self.inertia_end),
            ("cognitive", self.cognitive),
            ("social", self.social),
        ];
        for (name, value) in non_negative {
            if !value.is_finite() || value < 0.0 {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and non-negative",
                });
            }
        }
        if !self.max_velocity_fraction.is_finite() || self.max_velocity_fraction <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "max_velocity_fraction",
                value: self.max_velocity_fraction,
                reason: "must be finite and positive",
            });
        }
        Ok(())
    }

    /// Inertia weight `w^k` of the update at (0-based) iteration `k`:
    /// linear from `inertia_start` (`k = 0`) to `inertia_end`
    /// (`k = iterations - 1`).
    pub fn inertia(&self, k: usize) -> f64 {
        if self.iterations <= 1 {
            return self.inertia_start;
        }
        let t = k as f64 / (self.iterations - 1) as f64;
        self.inertia_start + (self.inertia_end - self.inertia_start) * t
    }
}

/// The search box `[lower, upper]`, one entry per dimension.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounds {
    /// Lower bound of each dimension.
    pub lower: Vec<f64>,
    /// Upper bound of each dimension (strictly greater than the lower one).
    pub upper: Vec<f64>,
}

impl Bounds {
    /// Builds and validates a box (see [`Bounds::validate`]).
    pub fn new(lower: Vec<f64>, upper: Vec<f64>) -> Result<Self> {
        let bounds = Self { lower, upper };
        bounds.validate()?;
        Ok(bounds)
    }

    /// Number of dimensions.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// Checks that there is at least one dimension, that both vectors have
    /// the same length, that all bounds are finite, that `lower < upper`
    /// componentwise and that each range `upper - lower` is finite.
    pub fn validate(&self) -> Result<()> {
        if self.lower.is_empty() {
            return Err(Error::InvalidSetting {
                name: "bounds.lower.len",
                value: 0,
                reason: "at least one dimension is required",
            });
        }
        if self.upper.len() != self.lower.len() {
            return Err(Error::InvalidSetting {
                name: "bounds.upper.len",
                value: i64::try_from(self.upper.len()).unwrap_or(i64::MAX),
                reason: "must equal the number of lower bounds",
            });
        }
        for (&lo, &hi) in self.lower.iter().zip(&self.upper) {
            if !lo.is_finite() {
                return Err(Error::InvalidParameter {
                    name: "bounds.lower",
                    value: lo,
                    reason: "must be finite",
                });
            }
            if !hi.is_finite() {
                return Err(Error::InvalidParameter {
                    name: "bounds.upper",
                    value: hi,
                    reason: "must be finite",
                });
            }
            if lo >= hi {
                return Err(Error::InvalidParameter {
                    name: "bounds.upper",
                    value: hi,
                    reason: "must be strictly greater than the lower bound of its dimension",
                });
            }
            if !(hi - lo).is_finite() {
                return Err(Error::InvalidParameter {
                    name: "bounds.upper",
                    value: hi,
                    reason: "the range upper - lower overflows",
                });
            }
        }
        Ok(())
    }
}

/// Outcome of [`pso_minimize`].
#[derive(Debug, Clone, PartialEq)]
pub struct PsoResult {
    /// Best feasible position found (inside the bounds).
    pub best_position: Vec<f64>,
    /// Objective value at [`PsoResult::best_position`] (finite).
    pub best_value: f64,
    /// Global best value after each iteration: `history[k]` is the best
    /// value once iteration `k + 1` of `N` is done, so
    /// `history.len() == iterations` and the initial swarm's best is not
    /// included. Non-increasing; an entry is `+infinity` while no feasible
    /// candidate has been found yet.
    pub history: Vec<f64>,
    /// Number of objective evaluations: `particles * (iterations + 1)`.
    pub evaluations: usize,
}

/// Maps an objective value to the fitness used for comparisons: `None`,
/// NaN and infinite values are infeasible (`+infinity`).
fn fitness(value: Option<f64>) -> f64 {
    match value {
        Some(v) if v.is_finite() => v,
        _ => f64::INFINITY,
    }
}

/// Evaluates the whole swarm in parallel; results are in particle order.
fn evaluate<F>(objective: &F, positions: &[Vec<f64>]) -> Vec<f64>
where
    F: Fn(&[f64]) -> Option<f64> + Sync,
{
    positions
        .par_iter()
        .map(|x| fitness(objective(x)))
        .collect()
}

/// Minimises `objective` over `bounds` with the particle swarm optimiser of
/// Eq. (7) (see the [module documentation](self) for the details).
///
/// `objective` returns `None` for an infeasible candidate (e.g. an unstable
/// controller); such candidates, and NaN or infinite values, never become a
/// best. It is called from rayon worker threads, hence `Sync`.
///
/// `progress`, if given, is called on the calling thread after each
/// iteration with the number of completed iterations (`1..=iterations`) and
/// the current global best value (`+infinity` while nothing feasible has
/// been found).
///
/// # Errors
///
/// [`Error::InvalidParameter`] / [`Error::InvalidSetting`] for invalid
/// `bounds` or `settings`, and [`Error::Numerical`] if no evaluated candidate
/// was feasible.
///
/// # Example
///
/// A small swarm on a bowl with its minimum at (1, −2):
///
/// ```
/// use tdvass::analysis::pso::{Bounds, PsoSettings, pso_minimize};
///
/// let bowl = |x: &[f64]| Some((x[0] - 1.0).powi(2) + (x[1] + 2.0).powi(2));
/// let bounds = Bounds::new(vec![-5.0, -5.0], vec![5.0, 5.0])?;
/// let settings = PsoSettings { particles: 20, iterations: 60, seed: 7, ..PsoSettings::default() };
/// let result = pso_minimize(bowl, &bounds, &settings, None)?;
/// assert!((result.best_position[0] - 1.0).abs() < 1e-2);
/// assert!((result.best_position[1] + 2.0).abs() < 1e-2);
/// assert_eq!(result.evaluations, 20 * 61);
/// # Ok::<(), tdvass::Error>(())
/// ```
pub fn pso_minimize<F>(
    objective: F,
    bounds: &Bounds,
    settings: &PsoSettings,
    progress: Option<&dyn Fn(usize, f64)>,
) -> Result<PsoResult>
where
    F: Fn(&[f64]) -> Option<f64> + Sync,
{
    bounds.validate()?;
    settings.validate()?;

    let v_max: Vec<f64> = bounds
        .upper
        .iter()
        .zip(&bounds.lower)
        .map(|(hi, lo)| settings.max_velocity_fraction * (hi - lo))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);

    // Steps 1 and 3: the random swarm, its fitness and its bests.
    let (positions, velocities) = random_swarm(bounds, &v_max, settings.particles, &mut rng);
    let values = evaluate(&objective, &positions);
    let mut evaluations = settings.particles;
    let mut swarm = Swarm::new(positions, velocities, values);

    let mut history = Vec::with_capacity(settings.iterations);
    for k in 0..settings.iterations {
        swarm.fly(bounds, settings, &v_max, settings.inertia(k), &mut rng);
        // Steps 2, 3 and 5: evaluate, then update the bests in particle order.
        let values = evaluate(&objective, &swarm.positions);
        evaluations += settings.particles;
        swarm.update(&values);
        history.push(swarm.global_val);
        if let Some(report) = progress {
            report(k + 1, swarm.global_val);
        }
    }

    // Step 6: output the optimum.
    if swarm.global.is_none() {
        return Err(Error::Numerical {
            what: "particle swarm optimisation",
            reason: format!("no feasible candidate among {evaluations} evaluations"),
        });
    }
    Ok(PsoResult {
        best_position: swarm.global_pos,
        best_value: swarm.global_val,
        history,
        evaluations,
    })
}

/// Step 1: `particles` random positions, uniform in the bounds, and
/// velocities, uniform in `±v_max`, drawn sequentially (for each particle
/// and dimension: the position's number, then the velocity's).
fn random_swarm(
    bounds: &Bounds,
    v_max: &[f64],
    particles: usize,
    rng: &mut ChaCha8Rng,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let dim = bounds.dim();
    let mut positions: Vec<Vec<f64>> = Vec::with_capacity(particles);
    let mut velocities: Vec<Vec<f64>> = Vec::with_capacity(particles);
    for _ in 0..particles {
        let mut x = Vec::with_capacity(dim);
        let mut v = Vec::with_capacity(dim);
        for ((&lower, &upper), &v_max) in bounds.lower.iter().zip(&bounds.upper).zip(v_max) {
            let u: f64 = rng.random();
            // `lower + u * range` can round up to `upper` but never beyond it
            // in a way `clamp` would not fix.
            x.push((lower + u * (upper - lower)).clamp(lower, upper));
            let u: f64 = rng.random();
            v.push((2.0 * u - 1.0) * v_max);
        }
        positions.push(x);
        velocities.push(v);
    }
    (positions, velocities)
}

/// The swarm between iterations: the particles, their own bests and the
/// swarm's best.
struct Swarm {
    positions: Vec<Vec<f64>>,
    velocities: Vec<Vec<f64>>,
    personal_pos: Vec<Vec<f64>>,
    personal_val: Vec<f64>,
    /// Index into `personal_*` of the swarm's best (`None` while no value
    /// is finite).
    global: Option<usize>,
    global_val: f64,
    global_pos: Vec<f64>,
}

impl Swarm {
    /// Step 3 on the first evaluation: every particle's best is where it
    /// starts.
    fn new(positions: Vec<Vec<f64>>, velocities: Vec<Vec<f64>>, values: Vec<f64>) -> Swarm {
        let mut swarm = Swarm {
            personal_pos: positions.clone(),
            positions,
            velocities,
            personal_val: values,
            global: None,
            global_val: f64::INFINITY,
            global_pos: Vec::new(),
        };
        swarm.choose_global();
        swarm
    }

    /// The swarm's best among the particles' bests, in particle order
    /// (the first of equal values stays).
    fn choose_global(&mut self) {
        let mut improved = false;
        for (i, &val) in self.personal_val.iter().enumerate() {
            if val < self.global_val {
                self.global_val = val;
                self.global = Some(i);
                improved = true;
            }
        }
        if improved && let Some(i) = self.global {
            self.global_pos.clone_from(&self.personal_pos[i]);
        }
    }

    /// Step 4: Eq. (7) with inertia `w`, the random numbers drawn
    /// sequentially (r1, r2 for each particle and dimension); a particle
    /// that would leave the bounds stops on them.
    fn fly(
        &mut self,
        bounds: &Bounds,
        settings: &PsoSettings,
        v_max: &[f64],
        w: f64,
        rng: &mut ChaCha8Rng,
    ) {
        let swarm_best = self.global.is_some();
        for i in 0..self.positions.len() {
            let x = &mut self.positions[i];
            let v = &mut self.velocities[i];
            let own_best = self.personal_val[i].is_finite();
            for d in 0..x.len() {
                let r1: f64 = rng.random();
                let r2: f64 = rng.random();
                let mut vd = w * v[d];
                if own_best {
                    vd += settings.cognitive * r1 * (self.personal_pos[i][d] - x[d]);
                }
                if swarm_best {
                    vd += settings.social * r2 * (self.global_pos[d] - x[d]);
                }
                vd = vd.clamp(-v_max[d], v_max[d]);
                let xd = x[d] + vd;
                if xd < bounds.lower[d] {
                    x[d] = bounds.lower[d];
                    v[d] = 0.0;
                } else if xd > bounds.upper[d] {
                    x[d] = bounds.upper[d];
                    v[d] = 0.0;
                } else {
                    x[d] = xd;
                    v[d] = vd;
                }
            }
        }
    }

    /// Steps 3 and 5: each particle's best, then the swarm's.
    fn update(&mut self, values: &[f64]) {
        for (i, &val) in values.iter().enumerate() {
            if val < self.personal_val[i] {
                self.personal_val[i] = val;
                self.personal_pos[i].clone_from(&self.positions[i]);
            }
        }
        self.choose_global();
    }
}

#[cfg(test)]
mod tests;
