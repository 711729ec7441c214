//! The command line's arguments: the clap definitions of every subcommand
//! and the parsing of names (variant, road, target).

use super::deferred::Deferred;
use clap::{Args, CommandFactory, Parser, Subcommand};
use tdvass::TireContact;
use tdvass::analysis::optimize::{
    CONTROLLER_DELAY_RANGE, CONTROLLER_GAIN_RANGE, DEFAULT_TRAVEL_LIMIT, Objective, Target,
};
use tdvass::chassis::ChassisParams;
use tdvass::error::{Error, Result};
use tdvass::metrics::Weights;
use tdvass::model::{Params, State, Variant};
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::{DEFAULT_TOLERANCE, Metrics, SimulationConfig};

/// Accepted `--road` values (case-insensitive), for error messages.
pub(super) const ROAD_NAMES: &str = "harmonic, iso8608 (alias iso), paper or file:PATH (any case)";

/// Time-delay feedback controlled suspension with an annular
/// vibration-absorbing structure (CS, PVASS, TDVASS).
#[derive(Debug, Parser)]
#[command(name = "tdvass", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub(super) command: Command,
}

#[derive(Debug, Subcommand)]
pub(super) enum Command {
    /// Time-domain run from rest; RMS of BA, SDD, TDD and the objective J.
    Simulate(Deferred<SimulateArgs>),
    /// Delay-independent range, crossing frequencies, critical delays and
    /// stable delay intervals for a gain g (section 3), of the linear model
    /// (the bilateral tire; --tire-contact does not apply).
    Stability(Deferred<StabilityArgs>),
    /// Rightmost characteristic roots and stability at one (g, tau), of the
    /// linear model (the bilateral tire; --tire-contact does not apply).
    Stable(Deferred<StableArgs>),
    /// Amplitude-frequency characteristics, Eq. (4) and (5), of the linear
    /// model (the bilateral tire; --tire-contact does not apply).
    Frf(Deferred<FrfArgs>),
    /// Particle swarm optimisation of the absorber or the controller.
    Optimize(Deferred<OptimizeArgs>),
    /// The (g, tau) stability map as CSV, of the linear model (the bilateral
    /// tire; --tire-contact does not apply).
    Map(Deferred<MapArgs>),
    /// The monolithic full car: the chassis on four corners in one delay
    /// equation (the reference of the corner and chassis FMUs' co-simulation).
    Car(Deferred<Box<CarArgs>>),
}

/// Model parameters, named as the FMU parameters (defaults: Table 1, g1, tau1).
#[derive(Debug, Clone, Args)]
pub(super) struct ModelArgs {
    /// Body mass m_s (kg).
    #[arg(long, default_value_t = 345.0)]
    pub(super) m_s: f64,
    /// Absorber mass m_h (kg).
    #[arg(long, default_value_t = 4.05)]
    pub(super) m_h: f64,
    /// Wheel mass m_t (kg).
    #[arg(long, default_value_t = 40.5)]
    pub(super) m_t: f64,
    /// Suspension stiffness k_s (N/m).
    #[arg(long, default_value_t = 16000.0)]
    pub(super) k_s: f64,
    /// Absorber stiffness k_h (N/m).
    #[arg(long, default_value_t = 6444.0)]
    pub(super) k_h: f64,
    /// Tire stiffness k_t (N/m).
    #[arg(long, default_value_t = 190000.0)]
    pub(super) k_t: f64,
    /// Suspension damping c_s (N.s/m).
    #[arg(long, default_value_t = 1500.0)]
    pub(super) c_s: f64,
    /// Absorber damping c_h (N.s/m).
    #[arg(long, default_value_t = 348.0)]
    pub(super) c_h: f64,
    /// Feedback gain g (N/m).
    #[arg(long, default_value_t = 5386.0)]
    pub(super) g: f64,
    /// Feedback delay tau (s).
    #[arg(long, default_value_t = 2e-4)]
    pub(super) tau: f64,
}

impl ModelArgs {
    pub(super) fn params(&self) -> Params {
        // A parameter without a command-line option keeps its default.
        #[allow(clippy::needless_update)]
        Params {
            m_s: self.m_s,
            m_h: self.m_h,
            m_t: self.m_t,
            k_s: self.k_s,
            k_h: self.k_h,
            k_t: self.k_t,
            c_s: self.c_s,
            c_h: self.c_h,
            g: self.g,
            tau: self.tau,
            ..Params::default()
        }
    }
}

/// A `--road` value, read case-insensitively (the path of `file:PATH` is
/// kept as typed).
#[derive(Debug, Clone, PartialEq)]
pub(super) enum RoadName {
    Harmonic,
    Iso8608,
    Paper,
    File(String),
}

impl RoadName {
    pub(super) fn parse(text: &str) -> Result<RoadName> {
        let trimmed = text.trim();
        let lower = trimmed.to_ascii_lowercase();
        Ok(match lower.as_str() {
            "harmonic" => RoadName::Harmonic,
            "iso8608" | "iso" => RoadName::Iso8608,
            "paper" => RoadName::Paper,
            _ if lower.starts_with("file:") => RoadName::File(trimmed["file:".len()..].to_string()),
            _ => {
                return Err(Error::UnknownName {
                    what: "road",
                    given: text.to_string(),
                    expected: ROAD_NAMES,
                });
            }
        })
    }

    /// The name a result records (`harmonic`, `iso8608`, `paper`, `file:PATH`).
    pub(super) fn canonical(&self) -> String {
        match self {
            RoadName::Harmonic => "harmonic".into(),
            RoadName::Iso8608 => "iso8608".into(),
            RoadName::Paper => "paper".into(),
            RoadName::File(path) => format!("file:{path}"),
        }
    }
}

/// Road, solver and objective settings shared by `simulate` and `optimize`.
#[derive(Debug, Clone, Args)]
pub(super) struct RunArgs {
    /// harmonic, iso8608 (alias iso), paper (the paper-compatible random
    /// road) or file:PATH (CSV rows t,x_g; the last value is held after the
    /// last row). Any case.
    #[arg(long, default_value = "harmonic")]
    pub(super) road: String,
    /// Harmonic amplitude (m).
    #[arg(long, default_value_t = 0.05)]
    pub(super) road_amplitude: f64,
    /// Harmonic angular frequency (rad/s).
    #[arg(long, default_value_t = 5.0)]
    pub(super) road_angular_frequency: f64,
    /// ISO 8608 class of the random roads, A..H (any case) or 1..8.
    #[arg(long, default_value = "C")]
    pub(super) road_class: String,
    /// Vehicle speed u (m/s).
    #[arg(long, default_value_t = 20.0)]
    pub(super) vehicle_speed: f64,
    /// Lower cut-off frequency f0 (Hz).
    #[arg(long, default_value_t = 0.1)]
    pub(super) road_cutoff_frequency: f64,
    /// Random road seed.
    #[arg(long, default_value_t = 1)]
    pub(super) road_seed: u64,
    /// Paper-compatible road: noise hold interval D (s).
    #[arg(long, default_value_t = 0.1)]
    pub(super) road_sample_interval: f64,
    /// Relative accuracy of every reported metric (1e-12 to 0.1): it sets
    /// the internal step.
    #[arg(long, default_value_t = DEFAULT_TOLERANCE)]
    pub(super) tolerance: f64,
    /// Optional upper bound of the internal integration step (s; 0 = none,
    /// the tolerance alone sets the step).
    #[arg(long, default_value_t = 0.0)]
    pub(super) max_internal_step: f64,
    /// Weight z1 of RMS(BA) in J.
    #[arg(long, default_value_t = 0.4)]
    pub(super) w_ba: f64,
    /// Weight z2 of RMS(SDD) in J.
    #[arg(long, default_value_t = 0.2)]
    pub(super) w_sdd: f64,
    /// Weight z3 of RMS(TDD) in J (TDD in m).
    #[arg(long, default_value_t = 0.4)]
    pub(super) w_tdd: f64,
    /// Simulated duration of each run (s).
    #[arg(long, default_value_t = 15.0)]
    pub(super) duration: f64,
    /// bilateral (the paper's linear tire, which pulls as well as pushes)
    /// or unilateral (the tire cannot pull: the wheel lifts off where the
    /// tire load falls to 0 and flies until it lands). Any case.
    #[arg(long, default_value = "bilateral")]
    pub(super) tire_contact: String,
}

impl RunArgs {
    pub(super) fn road_name(&self) -> Result<RoadName> {
        RoadName::parse(&self.road)
    }

    pub(super) fn road_class(&self) -> Result<RoadClass> {
        match self.road_class.trim().parse::<i64>() {
            Ok(code) => RoadClass::from_code(code),
            Err(_) => self.road_class.parse::<RoadClass>(),
        }
    }

    pub(super) fn tire_contact(&self) -> Result<TireContact> {
        self.tire_contact.trim().parse()
    }

    pub(super) fn road_spec(&self) -> Result<RoadSpec> {
        let road = self.road_name()?;
        let random = RandomRoad {
            class: self.road_class()?,
            speed: self.vehicle_speed,
            cutoff_frequency: self.road_cutoff_frequency,
            seed: self.road_seed,
        };
        let spec = match road {
            RoadName::Harmonic => RoadSpec::Harmonic {
                amplitude: self.road_amplitude,
                angular_frequency: self.road_angular_frequency,
            },
            RoadName::Iso8608 => RoadSpec::Iso8608(random),
            RoadName::Paper => RoadSpec::PaperCompatible {
                road: random,
                sample_interval: self.road_sample_interval,
            },
            RoadName::File(path) => RoadSpec::from_csv_file(&path)?,
        };
        spec.validate()?;
        Ok(spec)
    }

    pub(super) fn config(&self, params: Params, variant: Variant) -> Result<SimulationConfig> {
        // Checked here, once, so that an optimisation refuses them by name
        // rather than finding every candidate infeasible.
        tdvass::solver::accuracy::check_tolerance(self.tolerance)?;
        tdvass::solver::accuracy::check_max_internal_step(self.max_internal_step)?;
        Ok(SimulationConfig {
            params,
            variant,
            road: self.road_spec()?,
            road_shift: tdvass::road::RoadShift::NONE,
            tolerance: self.tolerance,
            max_internal_step: self.max_internal_step,
            communication_step: 0.0,
            tire_contact: self.tire_contact()?,
            body: tdvass::model::Body::Mass,
            start_time: 0.0,
            initial_state: State::zeros(),
            weights: Weights {
                body_acceleration: self.w_ba,
                suspension_deflection: self.w_sdd,
                tire_deflection: self.w_tdd,
            },
            metrics: Metrics::Paper,
        })
    }

    /// A sentence saying which road a result used.
    pub(super) fn road_note(&self) -> String {
        let class = self
            .road_class()
            .map_or_else(|_| self.road_class.clone(), |c| format!("{c:?}"));
        match self.road_name() {
            Ok(RoadName::Paper) => "paper-compatible band-limited road (about 10x weaker than true ISO 8608; reproduces the paper's Table 3)".into(),
            Ok(RoadName::Iso8608) => format!("ISO 8608 class {class} road at {} m/s", self.vehicle_speed),
            Ok(RoadName::Harmonic) => format!("harmonic road {} sin({} t)", self.road_amplitude, self.road_angular_frequency),
            Ok(RoadName::File(path)) => format!("road from file:{path}"),
            Err(_) => format!("road {}", self.road),
        }
    }

    /// Every road, solver and objective setting of a run, by the FMU
    /// parameter names (the road by its canonical name, the class as a
    /// letter).
    pub(super) fn record(&self, value: &mut serde_json::Value) -> Result<()> {
        value["road"] = self.road_name()?.canonical().into();
        value["road_amplitude"] = self.road_amplitude.into();
        value["road_angular_frequency"] = self.road_angular_frequency.into();
        value["road_class"] = format!("{:?}", self.road_class()?).into();
        value["vehicle_speed"] = self.vehicle_speed.into();
        value["road_cutoff_frequency"] = self.road_cutoff_frequency.into();
        value["road_seed"] = self.road_seed.into();
        value["road_sample_interval"] = self.road_sample_interval.into();
        value["tolerance"] = self.tolerance.into();
        value["max_internal_step"] = self.max_internal_step.into();
        value["w_ba"] = self.w_ba.into();
        value["w_sdd"] = self.w_sdd.into();
        value["w_tdd"] = self.w_tdd.into();
        value["duration"] = self.duration.into();
        value["tire_contact"] = self.tire_contact()?.name().into();
        Ok(())
    }

    /// Warns (on standard error) when a run of `duration` seconds goes past
    /// the last sample of a road file, whose value is then held.
    pub(super) fn warn_past_road_end(&self, spec: &RoadSpec) {
        if let Some((last_time, last_value)) = spec.last_sample()
            && self.duration > last_time
        {
            eprintln!(
                "warning: the road file ends at t = {last_time} s; from there to {} s \
                 its last value x_g = {last_value} m is held",
                self.duration
            );
        }
    }
}

#[derive(Debug, Args)]
pub(super) struct SimulateArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    #[command(flatten)]
    pub(super) run: RunArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    pub(super) variant: String,
    /// Write the time histories to this CSV file.
    #[arg(long)]
    pub(super) output: Option<String>,
    /// Time between CSV rows (s).
    #[arg(long, default_value_t = 1e-3)]
    pub(super) output_interval: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub(super) json: bool,
}

/// The chassis's parameters, named as the chassis FMU's.
#[derive(Debug, Clone, Args)]
pub(super) struct ChassisArgs {
    /// Body mass m (kg; 4 x 345, the paper's car).
    #[arg(long, default_value_t = 1380.0)]
    pub(super) mass: f64,
    /// Centre of gravity to the front axle a (m).
    #[arg(long, default_value_t = 1.3)]
    pub(super) a: f64,
    /// Centre of gravity to the rear axle b (m).
    #[arg(long, default_value_t = 1.3)]
    pub(super) b: f64,
    /// Front track (m).
    #[arg(long, default_value_t = 1.5)]
    pub(super) track_front: f64,
    /// Rear track (m).
    #[arg(long, default_value_t = 1.5)]
    pub(super) track_rear: f64,
    /// Pitch inertia I_theta (kg.m2; default m a b, which decouples front
    /// and rear).
    #[arg(long)]
    pub(super) pitch_inertia: Option<f64>,
    /// Roll inertia I_phi (kg.m2).
    #[arg(long, default_value_t = 400.0)]
    pub(super) roll_inertia: f64,
    /// Seat point ahead of the centre of gravity (m).
    #[arg(long, default_value_t = 0.3)]
    pub(super) seat_x: f64,
    /// Seat point left of the centre of gravity (m).
    #[arg(long, default_value_t = 0.35)]
    pub(super) seat_y: f64,
}

impl ChassisArgs {
    pub(super) fn params(&self) -> ChassisParams {
        ChassisParams {
            mass: self.mass,
            a: self.a,
            b: self.b,
            track_front: self.track_front,
            track_rear: self.track_rear,
            pitch_inertia: self.pitch_inertia.unwrap_or(self.mass * self.a * self.b),
            roll_inertia: self.roll_inertia,
            seat_x: self.seat_x,
            seat_y: self.seat_y,
        }
    }
}

#[derive(Debug, Args)]
pub(super) struct CarArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    #[command(flatten)]
    pub(super) run: RunArgs,
    #[command(flatten)]
    pub(super) chassis: ChassisArgs,
    /// cs, pvass or tdvass on every corner (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    pub(super) variant: String,
    /// Seed of the right track's random road (default: --road-seed + 1).
    #[arg(long)]
    pub(super) right_seed: Option<u64>,
    /// The right track's phase on the harmonic road (rad).
    #[arg(long, default_value_t = 0.0)]
    pub(super) right_phase: f64,
    /// A corner's own road, `CORNER=file:PATH` (CORNER: fl, fr, rl, rr;
    /// repeatable), seen as it is, with no wheelbase delay. Once one is
    /// given, every wheel rolls on its own road in place of --road's
    /// tracks, and a corner not named on a flat one (x_g = 0).
    #[arg(long, value_name = "CORNER=file:PATH")]
    pub(super) corner_road: Vec<String>,
    /// Write heave, pitch, roll, the seat acceleration and the four
    /// suspension deflections to this CSV file.
    #[arg(long)]
    pub(super) output: Option<String>,
    /// Time between CSV rows (s), rounded to a whole number of internal steps.
    #[arg(long, default_value_t = 1e-3)]
    pub(super) output_interval: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub(super) json: bool,
}

#[derive(Debug, Args)]
pub(super) struct StabilityArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Largest delay considered (s).
    #[arg(long, default_value_t = 0.5)]
    pub(super) tau_max: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub(super) json: bool,
}

#[derive(Debug, Args)]
pub(super) struct StableArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    pub(super) variant: String,
    /// How many rightmost roots to list.
    #[arg(long, default_value_t = 6)]
    pub(super) roots: usize,
    /// Print one JSON object.
    #[arg(long)]
    pub(super) json: bool,
}

#[derive(Debug, Args)]
pub(super) struct FrfArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    pub(super) variant: String,
    /// Lowest frequency (Hz).
    #[arg(long, default_value_t = 0.1)]
    pub(super) f_min: f64,
    /// Highest frequency (Hz).
    #[arg(long, default_value_t = 30.0)]
    pub(super) f_max: f64,
    /// Number of log-spaced points.
    #[arg(long, default_value_t = 500)]
    pub(super) points: usize,
    /// Write the curve here instead of standard output (CSV).
    #[arg(long)]
    pub(super) output: Option<String>,
    /// Print one JSON object (the peaks) instead of the CSV.
    #[arg(long)]
    pub(super) json: bool,
}

#[derive(Debug, Args)]
pub(super) struct OptimizeArgs {
    /// absorber (k_h, c_h of PVASS in (0, k_s) x (0, c_s)) or controller
    /// (g, tau of TDVASS in [--g-min, --g-max] x [--tau-min, --tau-max]).
    /// Any case.
    pub(super) target: String,
    #[command(flatten)]
    pub(super) model: ModelArgs,
    #[command(flatten)]
    pub(super) run: RunArgs,
    /// Swarm size.
    #[arg(long, default_value_t = 100)]
    pub(super) particles: usize,
    /// Iterations.
    #[arg(long, default_value_t = 200)]
    pub(super) iterations: usize,
    /// Seed of the swarm.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    /// Controller only: lower bound of the gain g (N/m).
    #[arg(long, default_value_t = CONTROLLER_GAIN_RANGE[0])]
    pub(super) g_min: f64,
    /// Controller only: upper bound of the gain g (N/m).
    #[arg(long, default_value_t = CONTROLLER_GAIN_RANGE[1])]
    pub(super) g_max: f64,
    /// Controller only: lower bound of the delay tau (s, >= 0).
    #[arg(long, default_value_t = CONTROLLER_DELAY_RANGE[0])]
    pub(super) tau_min: f64,
    /// Controller only: upper bound of the delay tau (s).
    #[arg(long, default_value_t = CONTROLLER_DELAY_RANGE[1])]
    pub(super) tau_max: f64,
    /// paper (J of Eq. (6)) or comfort (ISO 2631-1 a_w subject to RMS
    /// dynamic tire load ratio <= 1/3, max |SDD| <= --travel-limit and
    /// static deflection <= --static-deflection-limit). Any case.
    #[arg(long, default_value = "paper")]
    pub(super) objective: String,
    /// Comfort objective: the largest admissible |SDD| (m).
    #[arg(long, default_value_t = DEFAULT_TRAVEL_LIMIT)]
    pub(super) travel_limit: f64,
    /// Comfort objective: the largest admissible static deflection of the
    /// springs between body and wheel (m) [default: the Table 1 design's,
    /// 0.7427 m]
    #[arg(long)]
    pub(super) static_deflection_limit: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub(super) json: bool,
}

#[derive(Debug, Args)]
pub(super) struct MapArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Smallest gain (N/m).
    #[arg(long, default_value_t = -200000.0)]
    pub(super) g_min: f64,
    /// Largest gain (N/m).
    #[arg(long, default_value_t = 200000.0)]
    pub(super) g_max: f64,
    /// Gain samples.
    #[arg(long, default_value_t = 400)]
    pub(super) g_points: usize,
    /// Largest delay (s).
    #[arg(long, default_value_t = 0.5)]
    pub(super) tau_max: f64,
    /// Delay samples.
    #[arg(long, default_value_t = 400)]
    pub(super) tau_points: usize,
    /// CSV file to write (standard output when absent).
    #[arg(long)]
    pub(super) output: Option<String>,
    /// Print a JSON summary.
    #[arg(long)]
    pub(super) json: bool,
}

pub(super) fn parse_variant(name: &str) -> Result<Variant> {
    name.parse()
}

/// The objective of `optimize`, with its limits (each finite and > 0).
pub(super) fn parse_objective(a: &OptimizeArgs) -> Result<Objective> {
    match a.objective.trim().to_ascii_lowercase().as_str() {
        "paper" => Ok(Objective::Paper),
        "comfort" => {
            let Objective::Comfort {
                static_deflection_limit: table1,
                ..
            } = Objective::comfort()
            else {
                unreachable!("the comfort objective")
            };
            let limits = [
                ("travel_limit", a.travel_limit),
                (
                    "static_deflection_limit",
                    a.static_deflection_limit.unwrap_or(table1),
                ),
            ];
            for (name, value) in limits {
                if !(value.is_finite() && value > 0.0) {
                    return Err(Error::InvalidParameter {
                        name,
                        value,
                        reason: "must be finite and > 0",
                    });
                }
            }
            Ok(Objective::Comfort {
                travel_limit: limits[0].1,
                static_deflection_limit: limits[1].1,
            })
        }
        _ => Err(Error::UnknownName {
            what: "objective",
            given: a.objective.clone(),
            expected: "paper or comfort (any case)",
        }),
    }
}

pub(super) fn parse_target(name: &str) -> Result<Target> {
    match name.trim().to_ascii_lowercase().as_str() {
        "absorber" => Ok(Target::Absorber),
        "controller" => Ok(Target::Controller),
        _ => Err(Error::UnknownName {
            what: "optimisation target",
            given: name.to_string(),
            expected: "absorber or controller (any case)",
        }),
    }
}

pub(super) fn io_error(action: &'static str, path: &str, error: &std::io::Error) -> Error {
    Error::Io {
        action,
        path: path.to_string(),
        reason: error.to_string(),
    }
}

pub(super) fn write_text(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| io_error("writing", path, &e))
}

/// The command line: the derived parser, each subcommand's arguments
/// declared when it is parsed ([`Deferred`]).
pub(super) fn command() -> clap::Command {
    Cli::command()
}

#[cfg(test)]
mod tests {
    /// clap's own consistency checks of the parser run only in debug
    /// builds (the suite tests a release build), where a flag that takes
    /// no value but accepts negative numbers panics at every command: the
    /// rule is checked here in any build, and clap's checks where they run.
    #[test]
    fn the_parser_passes_clap_s_checks() {
        let mut command = super::command();
        // Declares every subcommand's deferred arguments.
        command.build();
        let mut negative = 0;
        for sub in command.get_subcommands() {
            for arg in sub.get_arguments() {
                negative += usize::from(arg.is_allow_negative_numbers_set());
                assert!(
                    !arg.is_allow_negative_numbers_set() || arg.get_action().takes_values(),
                    "{} --{}: negative numbers for a flag that takes no value",
                    sub.get_name(),
                    arg.get_id()
                );
            }
        }
        assert!(negative > 50, "{negative} flags take negative numbers");
        command.debug_assert();
    }
}
