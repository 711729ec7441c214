//! The JSON of the `tdvass` library's reports (which knows nothing of
//! JSON): one `to_json` per report type. The subcommands in `cli.rs`
//! assemble their output objects from these and from their own
//! arguments. Keys are those of the interface (docs/cli.md).

use serde_json::{Value, json};
use tdvass::analysis::frf::FrfPeaks;
use tdvass::analysis::optimize::{Report, Target};
use tdvass::analysis::spectrum::StableReport;
use tdvass::analysis::stability::StabilityReport;

/// A report that the command line prints as one JSON object.
pub trait ToJson {
    /// The JSON object of the report.
    fn to_json(&self) -> Value;
}

impl ToJson for FrfPeaks {
    /// The `peaks_hz` JSON object of the `frf` subcommand:
    /// `{"body_displacement": [...], "body_acceleration": [...]}`.
    fn to_json(&self) -> Value {
        json!({
            "body_displacement": self.body_displacement,
            "body_acceleration": self.body_acceleration,
        })
    }
}

impl ToJson for StableReport {
    /// JSON object with the keys `stable`, `spectral_abscissa` and
    /// `rightmost_roots` (list of `[re, im]`).
    fn to_json(&self) -> Value {
        json!({
            "stable": self.stable,
            "spectral_abscissa": self.spectral_abscissa,
            "rightmost_roots": self.rightmost_roots.iter()
                .map(|r| json!([r.re, r.im]))
                .collect::<Vec<Value>>(),
        })
    }
}

impl ToJson for StabilityReport {
    /// The JSON object of the `stability` subcommand: `routh_hurwitz_g_max`,
    /// `delay_independent_g_max`, `crossings` (list of
    /// `{omega, direction, critical_delays}`), `stable_intervals` (list of
    /// `[from, to]`). Non-finite numbers become `null`.
    fn to_json(&self) -> Value {
        json!({
            "routh_hurwitz_g_max": self.routh_hurwitz_g_max,
            "delay_independent_g_max": self.delay_independent_g_max,
            "crossings": self.crossings.iter().map(|c| json!({
                "omega": c.crossing.omega,
                "direction": c.crossing.direction,
                "critical_delays": c.critical_delays,
            })).collect::<Vec<Value>>(),
            "stable_intervals": self.stable_intervals.iter()
                .map(|&(from, to)| json!([from, to]))
                .collect::<Vec<Value>>(),
        })
    }
}

impl ToJson for Report {
    /// The spec's JSON: `best` (object of parameter values), `objective`,
    /// `history`, plus `paper_points` and `evaluations`.
    fn to_json(&self) -> Value {
        let names = self.target.parameter_names();
        let mut best = serde_json::Map::new();
        for (name, value) in names.iter().zip(&self.swarm.best_position) {
            best.insert(name.to_string(), (*value).into());
        }
        let paper: Vec<Value> = self
            .paper
            .iter()
            .map(|p| {
                json!({
                    "label": p.label,
                    names[0]: p.position[0],
                    names[1]: p.position[1],
                    "objective": p.objective,
                })
            })
            .collect();
        let history: Vec<Option<f64>> = self
            .swarm
            .history
            .iter()
            .map(|&j| j.is_finite().then_some(j))
            .collect();
        json!({
            "target": match self.target { Target::Absorber => "absorber", Target::Controller => "controller" },
            "best": best,
            "objective": self.swarm.best_value,
            "history": history,
            "evaluations": self.swarm.evaluations,
            "paper_points": paper,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tdvass::analysis::frf::peaks_hz;
    use tdvass::model::{Params, Variant};

    #[test]
    fn stability_report_has_the_specified_keys() {
        let report = StabilityReport::compute(&Params::default(), 50000.0, 0.5).unwrap();
        let json = report.to_json();
        let object = json.as_object().unwrap();
        let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(
            keys,
            [
                "crossings",
                "delay_independent_g_max",
                "routh_hurwitz_g_max",
                "stable_intervals"
            ]
        );
        let crossing = &json["crossings"][0];
        assert!(crossing["omega"].is_f64());
        assert_eq!(crossing["direction"], -1);
        assert!(crossing["critical_delays"].is_array());
        assert_eq!(json["stable_intervals"][0][0], 0.0);
        assert_eq!(json["stable_intervals"].as_array().unwrap().len(), 4);
    }

    #[test]
    fn stable_report_has_the_specified_keys() {
        let params = Params::with_controller(40000.0, 0.03);
        let report = StableReport::compute(&params, Variant::Tdvass, 2).unwrap();
        let json = report.to_json();
        assert_eq!(json["stable"], true);
        assert!(json["spectral_abscissa"].as_f64().unwrap() < 0.0);
        let roots = json["rightmost_roots"].as_array().unwrap();
        assert_eq!(roots.len(), 2);
        assert_eq!(roots[0].as_array().unwrap().len(), 2);
        assert_eq!(json.as_object().unwrap().len(), 3);
    }

    #[test]
    fn frf_peaks_have_both_curves() {
        let params = Params::default();
        let curve = tdvass::analysis::frf::frequency_response(&params, Variant::Cs, 0.1, 30.0, 200)
            .unwrap();
        let json = peaks_hz(&params, Variant::Cs, &curve).unwrap().to_json();
        assert!(json["body_displacement"].is_array() && json["body_acceleration"].is_array());
        assert!(!json["body_displacement"].as_array().unwrap().is_empty());
    }

    #[test]
    fn optimization_report_names_its_parameters() {
        use tdvass::analysis::optimize::{Problem, optimize};
        use tdvass::analysis::pso::PsoSettings;
        use tdvass::solver::SimulationConfig;
        let settings = PsoSettings {
            particles: 4,
            iterations: 3,
            ..PsoSettings::default()
        };
        let problem = Problem::new(Target::Absorber, SimulationConfig::default(), 1.0);
        let report = optimize(&problem, &settings, None).unwrap();
        let json = report.to_json();
        assert!(json["best"]["k_h"].as_f64().unwrap() > 0.0);
        assert!(json["best"]["c_h"].is_f64());
        assert_eq!(json["history"].as_array().unwrap().len(), 3);
        assert_eq!(json["target"], "absorber");
    }
}
