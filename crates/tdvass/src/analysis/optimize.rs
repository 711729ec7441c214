//! The paper's two optimisations with the particle swarm of [`super::pso`]:
//!
//! - **absorber** (section 2.3): `(k_h, c_h)` of PVASS in `(0, k_s) × (0, c_s)`;
//! - **controller** (section 4.2): `(g, tau)` of TDVASS in user bounds.
//!
//! Each candidate is scored by the objective J of Eq. (6) from a
//! time-domain run from rest on the chosen road. Controller candidates that
//! are unstable (rightmost characteristic root in the right half plane, from
//! [`super::spectrum`]) are rejected without being simulated; a run that
//! diverges anyway is rejected too. The report also gives J at the paper's
//! own optimum, so the two can be compared.

use super::pso::{Bounds, PsoResult, PsoSettings, pso_minimize};
use super::spectrum::CharacteristicRootSolver;
use super::stability::delay_independent_g_max;
use crate::error::{Error, Result};
use crate::model::{PAPER_G1, PAPER_G2, PAPER_TAU1, PAPER_TAU2, Params, Variant};
use crate::solver::{SimulationConfig, simulate};

/// Which parameters to optimise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// `(k_h, c_h)` of PVASS.
    Absorber,
    /// `(g, tau)` of TDVASS.
    Controller,
}

/// Default search range of the feedback gain g for [`Target::Controller`]
/// (N/m).
pub const CONTROLLER_GAIN_RANGE: [f64; 2] = [0.0, 20000.0];
/// Default search range of the feedback delay tau for
/// [`Target::Controller`] (s).
pub const CONTROLLER_DELAY_RANGE: [f64; 2] = [0.0, 0.05];

impl Target {
    /// Names of the optimised parameters, in order.
    pub fn parameter_names(self) -> [&'static str; 2] {
        match self {
            Target::Absorber => ["k_h", "c_h"],
            Target::Controller => ["g", "tau"],
        }
    }

    /// The variant whose J is minimised.
    pub fn variant(self) -> Variant {
        match self {
            Target::Absorber => Variant::Pvass,
            Target::Controller => Variant::Tdvass,
        }
    }

    /// Default bounds: absorber `(0, k_s) × (0, c_s)` (kept off the open
    /// ends by one part in 10^6); controller `g ∈ [0, 20000]` N/m,
    /// `tau ∈ [0, 0.05]` s.
    pub fn default_bounds(self, params: &Params) -> Bounds {
        match self {
            Target::Absorber => {
                let margin = 1e-6;
                Bounds {
                    lower: vec![params.k_s * margin, params.c_s * margin],
                    upper: vec![params.k_s * (1.0 - margin), params.c_s * (1.0 - margin)],
                }
            }
            Target::Controller => Bounds {
                lower: vec![CONTROLLER_GAIN_RANGE[0], CONTROLLER_DELAY_RANGE[0]],
                upper: vec![CONTROLLER_GAIN_RANGE[1], CONTROLLER_DELAY_RANGE[1]],
            },
        }
    }

    /// The paper's optimum for this target, labelled.
    pub fn paper_points(self) -> Vec<(&'static str, [f64; 2])> {
        match self {
            Target::Absorber => vec![("paper (k_h, c_h)", [6444.0, 348.0])],
            Target::Controller => vec![
                ("paper (g1, tau1)", [PAPER_G1, PAPER_TAU1]),
                ("paper (g2, tau2)", [PAPER_G2, PAPER_TAU2]),
            ],
        }
    }

    /// `base` with the two optimised parameters replaced by `x`.
    pub fn apply(self, base: &Params, x: &[f64]) -> Params {
        match self {
            Target::Absorber => Params {
                k_h: x[0],
                c_h: x[1],
                ..*base
            },
            Target::Controller => Params {
                g: x[0],
                tau: x[1],
                ..*base
            },
        }
    }
}

/// A full optimisation problem.
#[derive(Debug, Clone)]
pub struct Problem {
    /// What to optimise.
    pub target: Target,
    /// Everything else: parameters, road, weights, internal step.
    pub base: SimulationConfig,
    /// Length of each run from rest (s).
    pub duration: f64,
    /// Search box.
    pub bounds: Bounds,
}

impl Problem {
    /// A problem with the target's default bounds.
    pub fn new(target: Target, base: SimulationConfig, duration: f64) -> Problem {
        let bounds = target.default_bounds(&base.params);
        Problem {
            target,
            base,
            duration,
            bounds,
        }
    }

    /// J at `x`, or `None` when the candidate is unstable, invalid or its
    /// run diverges.
    pub fn objective(&self, x: &[f64]) -> Option<f64> {
        let params = self.target.apply(&self.base.params, x);
        if self.target == Target::Controller && !self.is_stable(&params) {
            return None;
        }
        let config = SimulationConfig {
            params,
            variant: self.target.variant(),
            ..self.base.clone()
        };
        simulate(config, self.duration)
            .ok()
            .map(|run| run.objective)
    }

    fn is_stable(&self, params: &Params) -> bool {
        if let Ok(bound) = delay_independent_g_max(params)
            && params.g.abs() < bound
        {
            return true;
        }
        CharacteristicRootSolver::new(params, Variant::Tdvass)
            .and_then(|solver| solver.spectral_abscissa(params.tau))
            .map(|abscissa| abscissa < 0.0)
            .unwrap_or(false)
    }
}

/// J at one labelled point.
#[derive(Debug, Clone, PartialEq)]
pub struct ScoredPoint {
    /// What the point is.
    pub label: String,
    /// Parameter values, in [`Target::parameter_names`] order.
    pub position: [f64; 2],
    /// J there (`None`: unstable, invalid or divergent).
    pub objective: Option<f64>,
}

/// Result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Report {
    /// The target optimised.
    pub target: Target,
    /// The swarm's result (best position, J, history of the best J).
    pub swarm: PsoResult,
    /// J at the paper's optimum (or optima), for comparison.
    pub paper: Vec<ScoredPoint>,
}

/// Runs the swarm on `problem` and scores the paper's point(s).
///
/// A small controller search (8 particles, 4 iterations, 2 s runs) on the
/// harmonic road; J at the paper's (g1, tau1) comes with it:
///
/// ```
/// use tdvass::analysis::optimize::{Problem, Target, optimize};
/// use tdvass::analysis::pso::PsoSettings;
/// use tdvass::solver::SimulationConfig;
///
/// let problem = Problem::new(Target::Controller, SimulationConfig::default(), 2.0); // 2 s runs
/// let settings = PsoSettings { particles: 8, iterations: 4, ..PsoSettings::default() };
/// let report = optimize(&problem, &settings, None)?;
/// let paper_j = report.paper[0].objective.expect("(g1, tau1) is stable");
/// assert!(report.swarm.best_value <= paper_j + 0.05);
/// let [g, tau] = [report.swarm.best_position[0], report.swarm.best_position[1]];
/// assert!((0.0..=20000.0).contains(&g) && (0.0..=0.05).contains(&tau)); // N/m, s
/// # Ok::<(), tdvass::Error>(())
/// ```
pub fn optimize(
    problem: &Problem,
    settings: &PsoSettings,
    progress: Option<&dyn Fn(usize, f64)>,
) -> Result<Report> {
    if !(problem.duration.is_finite() && problem.duration > 0.0) {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: problem.duration,
            reason: "must be finite and > 0",
        });
    }
    SimulationConfig {
        variant: problem.target.variant(),
        ..problem.base.clone()
    }
    .road
    .validate()?;
    let swarm = pso_minimize(
        |x| problem.objective(x),
        &problem.bounds,
        settings,
        progress,
    )?;
    let paper = problem
        .target
        .paper_points()
        .into_iter()
        .map(|(label, position)| ScoredPoint {
            label: label.to_string(),
            position,
            objective: problem.objective(&position),
        })
        .collect();
    Ok(Report {
        target: problem.target,
        swarm,
        paper,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::road::RoadSpec;

    fn small_settings() -> PsoSettings {
        PsoSettings {
            particles: 8,
            iterations: 6,
            seed: 3,
            ..PsoSettings::default()
        }
    }

    #[test]
    fn absorber_optimum_is_no_worse_than_the_papers_point() {
        let base = SimulationConfig {
            road: RoadSpec::paper_harmonic(),
            ..SimulationConfig::default()
        };
        let problem = Problem::new(Target::Absorber, base, 5.0);
        let report = optimize(&problem, &small_settings(), None).unwrap();
        let paper = report.paper[0].objective.unwrap();
        assert!(
            report.swarm.best_value <= paper,
            "{} > {paper}",
            report.swarm.best_value
        );
        assert!(report.swarm.best_position[0] > 0.0);
        assert_eq!(report.swarm.history.len(), 6);
    }

    #[test]
    fn unstable_controllers_are_rejected_without_simulation() {
        let problem = Problem {
            bounds: Bounds {
                lower: vec![30000.0, 0.14],
                upper: vec![50000.0, 0.16],
            },
            ..Problem::new(Target::Controller, SimulationConfig::default(), 2.0)
        };
        // A3* = (40000, 0.15) is unstable; A1* = (40000, 0.03) is stable.
        assert_eq!(problem.objective(&[40000.0, 0.15]), None);
        assert!(problem.objective(&[40000.0, 0.03]).is_some());
        assert!(problem.objective(&[5386.0, 2e-4]).is_some());
    }

    #[test]
    fn controller_search_beats_or_matches_the_papers_point() {
        let base = SimulationConfig::default();
        let problem = Problem::new(Target::Controller, base, 5.0);
        let report = optimize(&problem, &small_settings(), None).unwrap();
        let g1 = report.paper[0].objective.unwrap();
        assert!(
            report.swarm.best_value <= g1 * (1.0 + 1e-12),
            "{} vs {g1}",
            report.swarm.best_value
        );
    }
}
