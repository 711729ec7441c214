//! Warnings about flags that do not apply to the run they were given for.

use super::args::*;
use clap::ArgMatches;
use clap::parser::ValueSource;
use std::collections::BTreeSet;
use tdvass::analysis::optimize::Target;
use tdvass::model::Variant;

/// The flags given on the command line (argument ids such as `road_seed`).
#[derive(Debug, Default)]
pub(super) struct GivenFlags(BTreeSet<String>);

impl GivenFlags {
    pub(super) fn from_matches(matches: &ArgMatches) -> GivenFlags {
        GivenFlags(
            matches
                .ids()
                .filter(|id| matches.value_source(id.as_str()) == Some(ValueSource::CommandLine))
                .map(|id| id.as_str().to_string())
                .collect(),
        )
    }

    /// A warning naming those of `ids` that were given, saying `why` they do
    /// nothing; `None` when none of them was given.
    pub(super) fn unused(&self, ids: &[&str], why: &str) -> Option<String> {
        let flags: Vec<String> = ids
            .iter()
            .filter(|id| self.0.contains(**id))
            .map(|id| format!("--{}", id.replace('_', "-")))
            .collect();
        match flags.len() {
            0 => None,
            1 => Some(format!("warning: {} has no effect: {why}", flags[0])),
            _ => Some(format!(
                "warning: {} have no effect: {why}",
                flags.join(", ")
            )),
        }
    }
}

pub(super) const HARMONIC_ROAD_FLAGS: [&str; 2] = ["road_amplitude", "road_angular_frequency"];
pub(super) const RANDOM_ROAD_FLAGS: [&str; 4] = [
    "road_class",
    "vehicle_speed",
    "road_cutoff_frequency",
    "road_seed",
];
pub(super) const PAPER_ROAD_FLAGS: [&str; 1] = ["road_sample_interval"];

pub(super) fn variant_warnings(variant: &str, given: &GivenFlags, warnings: &mut Vec<String>) {
    match parse_variant(variant) {
        Ok(Variant::Cs) => warnings.extend(given.unused(
            &["g", "tau", "m_h", "k_h", "c_h"],
            "CS has neither the absorber (m_h, k_h, c_h) nor the feedback (g, tau)",
        )),
        Ok(Variant::Pvass) => warnings.extend(given.unused(
            &["g", "tau"],
            "the feedback u = g x_t(t - tau) acts in TDVASS only",
        )),
        Ok(Variant::Tdvass) | Err(_) => {}
    }
}

pub(super) fn road_warnings(run: &RunArgs, given: &GivenFlags, warnings: &mut Vec<String>) {
    let random_and_paper: Vec<&str> = RANDOM_ROAD_FLAGS
        .iter()
        .chain(&PAPER_ROAD_FLAGS)
        .copied()
        .collect();
    match run.road_name() {
        Ok(RoadName::Harmonic) => warnings.extend(given.unused(
            &random_and_paper,
            "they set the random roads (--road iso8608 or paper)",
        )),
        Ok(RoadName::Iso8608) => {
            warnings.extend(given.unused(&HARMONIC_ROAD_FLAGS, "harmonic road only"));
            warnings.extend(given.unused(
                &PAPER_ROAD_FLAGS,
                "paper-compatible road (--road paper) only",
            ));
        }
        Ok(RoadName::Paper) => {
            warnings.extend(given.unused(&HARMONIC_ROAD_FLAGS, "harmonic road only"));
        }
        Ok(RoadName::File(_)) => {
            let all: Vec<&str> = HARMONIC_ROAD_FLAGS
                .iter()
                .chain(&random_and_paper)
                .copied()
                .collect();
            warnings.extend(given.unused(&all, "the road comes from the file"));
        }
        Err(_) => {}
    }
}

/// Warnings about flags that the command line accepted but that do not
/// apply to this run.
pub(super) fn warnings(command: &Command, given: &GivenFlags) -> Vec<String> {
    let mut warnings = Vec::new();
    match command {
        Command::Simulate(a) => {
            variant_warnings(&a.variant, given, &mut warnings);
            road_warnings(&a.run, given, &mut warnings);
            if a.output.is_none() {
                warnings.extend(given.unused(&["output_interval"], "it needs --output"));
            }
        }
        Command::Stability(_) => {
            warnings.extend(given.unused(&["tau"], "stability scans tau from 0 to --tau-max"))
        }
        Command::Stable(a) => variant_warnings(&a.variant, given, &mut warnings),
        Command::Frf(a) => variant_warnings(&a.variant, given, &mut warnings),
        Command::Optimize(a) => {
            road_warnings(&a.run, given, &mut warnings);
            match parse_target(&a.target) {
                Ok(Target::Absorber) => {
                    warnings.extend(given.unused(
                        &["g", "tau"],
                        "the absorber is optimised as PVASS, without feedback",
                    ));
                    warnings.extend(
                        given.unused(&["k_h", "c_h"], "the absorber optimisation searches them"),
                    );
                    warnings.extend(given.unused(
                        &["g_min", "g_max", "tau_min", "tau_max"],
                        "they bound the controller optimisation only",
                    ));
                }
                Ok(Target::Controller) => warnings.extend(
                    given.unused(&["g", "tau"], "the controller optimisation searches them"),
                ),
                Err(_) => {}
            }
        }
        Command::Map(_) => warnings.extend(given.unused(
            &["g", "tau"],
            "the map scans g from --g-min to --g-max and tau from 0 to --tau-max",
        )),
        Command::Car(a) => {
            variant_warnings(&a.variant, given, &mut warnings);
            // The speed sets the rear wheels' delay on every road.
            let mut road_flags = GivenFlags(given.0.clone());
            road_flags.0.remove("vehicle_speed");
            road_warnings(&a.run, &road_flags, &mut warnings);
            warnings.extend(given.unused(
                &["m_s", "w_ba", "w_sdd", "w_tdd"],
                "each corner carries its share of --mass, and the car reports no J",
            ));
            if a.output.is_none() {
                warnings.extend(given.unused(&["output_interval"], "it needs --output"));
            }
        }
    }
    warnings
}
