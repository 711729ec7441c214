use super::*;
use crate::outputs::{Known, Linearization};
use crate::variables::FMI3_VARIABLES;
use std::collections::HashSet;
use tdvass::model::Params;
use tdvass::solver::SimulationConfig;

#[test]
fn names_and_value_references_are_unique() {
    let names: HashSet<_> = COMMON_VARIABLES.iter().map(|v| v.name).collect();
    let vrs: HashSet<_> = COMMON_VARIABLES.iter().map(|v| v.vr).collect();
    assert_eq!(names.len(), COMMON_VARIABLES.len());
    assert_eq!(vrs.len(), COMMON_VARIABLES.len());
}

#[test]
fn interface_of_the_spec_is_present() {
    let spec: [(&str, Causality, VarType); 47] = {
        use Causality::*;
        use VarType::*;
        [
            ("variant", Parameter, Integer),
            ("m_s", Parameter, Real),
            ("m_h", Parameter, Real),
            ("m_t", Parameter, Real),
            ("k_s", Parameter, Real),
            ("k_h", Parameter, Real),
            ("k_t", Parameter, Real),
            ("c_s", Parameter, Real),
            ("c_h", Parameter, Real),
            ("g", Parameter, Real),
            ("tau", Parameter, Real),
            ("road", Parameter, Integer),
            ("road_amplitude", Parameter, Real),
            ("road_angular_frequency", Parameter, Real),
            ("road_class", Parameter, Integer),
            ("vehicle_speed", Parameter, Real),
            ("road_cutoff_frequency", Parameter, Real),
            ("road_seed", Parameter, Integer),
            ("road_sample_interval", Parameter, Real),
            ("max_internal_step", Parameter, Real),
            ("w_ba", Parameter, Real),
            ("w_sdd", Parameter, Real),
            ("w_tdd", Parameter, Real),
            ("input_extrapolation", Parameter, Integer),
            ("tire_contact", Parameter, Integer),
            ("x_g", Input, Real),
            ("x_s", Output, Real),
            ("x_h", Output, Real),
            ("x_t", Output, Real),
            ("v_s", Output, Real),
            ("v_h", Output, Real),
            ("v_t", Output, Real),
            ("body_acceleration", Output, Real),
            ("suspension_deflection", Output, Real),
            ("tire_deflection", Output, Real),
            ("road_displacement", Output, Real),
            ("control_force", Output, Real),
            ("rms_body_acceleration", Output, Real),
            ("rms_suspension_deflection", Output, Real),
            ("rms_tire_deflection", Output, Real),
            ("objective", Output, Real),
            ("lift_off_count", Output, Integer),
            ("spectral_abscissa", CalculatedParameter, Real),
            ("stable", CalculatedParameter, Boolean),
            ("x_s_start", Parameter, Real),
            ("v_s_start", Parameter, Real),
            ("x_t_start", Parameter, Real),
        ]
    };
    for (name, causality, ty) in spec {
        let v = by_name(Model::QuarterCar, FmiVersion::Fmi3, name)
            .unwrap_or_else(|| panic!("{name} missing"));
        assert_eq!(v.causality, causality, "{name}");
        assert_eq!(v.var_type(), ty, "{name}");
    }
    let tunable: Vec<_> = COMMON_VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Parameter && v.variability == Tunable)
        .map(|v| v.name)
        .collect();
    assert_eq!(tunable, ["g", "w_ba", "w_sdd", "w_tdd"]);
    assert_eq!(
        by_name(Model::QuarterCar, FmiVersion::Fmi3, "tire_deflection")
            .unwrap()
            .display_unit,
        Some("mm")
    );
}

#[test]
fn start_values_are_admissible_and_match_the_library_defaults() {
    for v in COMMON_VARIABLES {
        match v.causality {
            Causality::Parameter | Causality::Input => {
                let start = v.start.unwrap_or_else(|| panic!("{} has no start", v.name));
                v.range.check(v.name, start).unwrap();
                let (min, max) = v.range.bounds();
                assert!(min.is_none_or(|m| start >= m) && max.is_none_or(|m| start <= m));
            }
            _ => assert!(v.start.is_none(), "{} is calculated", v.name),
        }
    }
    let s = Settings::start_values(Model::QuarterCar);
    let config = s.to_config(0.0).unwrap();
    // The library's defaults, with every metric computed (the FMU's level)
    // and the internal step dividing the DefaultExperiment stepSize.
    assert_eq!(
        config,
        SimulationConfig {
            metrics: tdvass::solver::Metrics::Comfort,
            communication_step: crate::defaults::DEFAULT_STEP_SIZE,
            ..SimulationConfig::default()
        }
    );
    assert_eq!(s.x_g, 0.0);
}

#[test]
fn table_ranges_are_the_ones_the_model_enforces() {
    // One declaration: a physical parameter is admissible in the table
    // exactly when `Params::validate` accepts it.
    let probes = [
        -1.0,
        -1e-300,
        -0.0,
        0.0,
        1e-300,
        1.0,
        1e300,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for (name, _) in Params::default().named_values() {
        let variable = by_name(Model::QuarterCar, FmiVersion::Fmi3, name)
            .unwrap_or_else(|| panic!("`{name}` is not in the table"));
        for probe in probes {
            let mut params = Params::default();
            match name {
                "m_s" => params.m_s = probe,
                "m_h" => params.m_h = probe,
                "m_t" => params.m_t = probe,
                "k_s" => params.k_s = probe,
                "k_h" => params.k_h = probe,
                "k_t" => params.k_t = probe,
                "c_s" => params.c_s = probe,
                "c_h" => params.c_h = probe,
                "g" => params.g = probe,
                "tau" => params.tau = probe,
                other => panic!("a parameter `{other}` this test does not know"),
            }
            assert_eq!(
                variable.range.check(name, probe).is_ok(),
                params.validate().is_ok(),
                "`{name}` = {probe}: the table and Params::validate disagree"
            );
        }
    }
}

#[test]
fn every_variable_is_readable_and_settings_round_trip() {
    for model in Model::ALL {
        settings_round_trip(model);
    }
}

/// Every variable of `model` is readable, and its settings are distinct
/// fields.
fn settings_round_trip(model: Model) {
    let variables = variables_of(model, FmiVersion::Fmi3);
    let mut s = Settings::start_values(model);
    for (i, v) in variables.iter().enumerate() {
        match v.access {
            Access::Real { get, set } => {
                set(&mut s, 1000.0 + i as f64);
                assert_eq!(get(&s), 1000.0 + i as f64, "{}", v.name);
            }
            Access::Integer { get, set } => {
                set(&mut s, 1000 + i as i32);
                assert_eq!(get(&s), 1000 + i as i32, "{}", v.name);
            }
            Access::Output(_) | Access::IntegerOutput(_) | Access::ChassisOutput(_) => {
                assert_eq!(v.causality, Causality::Output)
            }
            Access::Calculated(_) => assert_eq!(v.causality, Causality::CalculatedParameter),
            Access::Time => assert_eq!(v.causality, Causality::Independent),
            Access::ContinuousState(_) | Access::StateDerivative(_) | Access::EventIndicator(_) => {
                assert_eq!(v.causality, Causality::Local)
            }
        }
    }
    // Distinct fields: every value written is still there.
    for (i, v) in variables.iter().enumerate() {
        match v.access {
            Access::Real { get, .. } => assert_eq!(get(&s), 1000.0 + i as f64, "{}", v.name),
            Access::Integer { get, .. } => assert_eq!(get(&s), 1000 + i as i32, "{}", v.name),
            _ => {}
        }
    }
    let outputs: Vec<_> = COMMON_VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .collect();
    assert_eq!(outputs.len(), 23);
    // The Real outputs are continuous; the counts are Integers, discrete,
    // and not read inside a step.
    for v in outputs {
        match v.access {
            Access::Output(_) => assert_eq!(v.variability, Variability::Continuous, "{}", v.name),
            Access::IntegerOutput(_) => {
                assert_eq!(v.variability, Variability::Discrete, "{}", v.name);
                assert!(!v.intermediate_update, "{}", v.name);
            }
            _ => panic!("`{}` is an output without an output access", v.name),
        }
    }
}

#[test]
fn tire_contact_codes_are_the_library_codes() {
    use tdvass::TireContact;
    let v = by_name(Model::QuarterCar, FmiVersion::Fmi3, "tire_contact").unwrap();
    assert_eq!(v.variability, Fixed);
    assert_eq!(v.start, Some(TireContact::default().code() as f64));
    let items = v.enumeration.unwrap().items;
    assert_eq!(items.len(), TireContact::ALL.len());
    for (item, contact) in items.iter().zip(TireContact::ALL) {
        assert_eq!((item.name, item.value), (contact.name(), contact.code()));
    }
    // The table's range and the library's codes agree.
    for code in -1..=2 {
        assert_eq!(
            v.range.check(v.name, code as f64).is_ok(),
            TireContact::from_code(code).is_ok(),
            "{code}"
        );
    }
    let mut s = Settings::start_values(Model::QuarterCar);
    for contact in TireContact::ALL {
        s.tire_contact = contact.code();
        assert_eq!(s.to_config(0.0).unwrap().tire_contact, contact);
    }
    s.tire_contact = 2;
    let e = s.to_config(0.0).unwrap_err().to_string();
    assert!(e.contains("tire_contact") && e.contains('2'), "{e}");
}

#[test]
fn units_and_dependencies_are_declared() {
    for v in COMMON_VARIABLES {
        if let Some(unit) = v.unit() {
            let def = UNITS.iter().find(|u| u.name == unit).expect(unit);
            if let Some(d) = v.display_unit {
                assert!(def.display.iter().any(|(n, _)| *n == d), "{}", v.name);
            }
        }
        for dep in v.feedthrough {
            assert_eq!(
                by_name(Model::QuarterCar, FmiVersion::Fmi3, dep)
                    .unwrap()
                    .causality,
                Causality::Input
            );
        }
        for dep in v.initial_dependencies {
            let known = by_name(Model::QuarterCar, FmiVersion::Fmi3, dep)
                .unwrap_or_else(|| panic!("{dep}"));
            assert!(matches!(
                known.causality,
                Causality::Input | Causality::Parameter
            ));
        }
    }
}

#[test]
fn range_checks_name_variable_and_value() {
    let e = Range::Positive.check("m_s", -1.0).unwrap_err();
    assert!(
        e.message.contains("m_s") && e.message.contains("-1"),
        "{}",
        e.message
    );
    assert!(Range::Finite.check("g", f64::NAN).is_err());
    assert!(Range::AtLeast(0.0).check("tau", f64::INFINITY).is_err());
    assert!(Range::Integers(1, 8).check("road_class", 9.0).is_err());
    assert!(Range::Integers(1, 8).check("road_class", 8.0).is_ok());
    assert!(Range::Computed.check("x_s", f64::NAN).is_ok());
}

#[test]
fn guid_is_stable_and_tracks_the_interface() {
    let g = guid(Model::QuarterCar);
    assert_eq!(g, guid(Model::QuarterCar));
    assert_eq!(g.len(), 38);
    assert!(g.starts_with('{') && g.ends_with('}'));
    let mut changed: Vec<Variable> = COMMON_VARIABLES.to_vec();
    changed[3].vr = 999;
    assert_ne!(guid_of(Model::QuarterCar, &changed), g);
    let mut renamed: Vec<Variable> = COMMON_VARIABLES.to_vec();
    renamed[0].name = "variant2";
    assert_ne!(guid_of(Model::QuarterCar, &renamed), g);
    let mut retuned: Vec<Variable> = COMMON_VARIABLES.to_vec();
    retuned[1].variability = Tunable;
    assert_ne!(guid_of(Model::QuarterCar, &retuned), g);
    // Descriptions and start values are not part of the interface.
    let mut described: Vec<Variable> = COMMON_VARIABLES.to_vec();
    described[1].description = "another text";
    described[1].start = Some(1.0);
    assert_eq!(guid_of(Model::QuarterCar, &described), g);
}

#[test]
fn partials_of_the_outputs() {
    let lin = Linearization {
        body_acceleration_row: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        body_force_row: [-1.0, -2.0, -3.0, -4.0, -5.0, -6.0],
        conventional: true,
        road_is_input: true,
        tire_stiffness: 7.0,
        instantaneous_control: Some((10.0, 0.5)),
    };
    assert_eq!(OutputId::State(X_H).partial(Known::State(X_T), &lin), 1.0);
    assert_eq!(
        OutputId::DynamicTireLoad.partial(Known::State(X_T), &lin),
        -7.0
    );
    assert_eq!(
        OutputId::DynamicTireLoad.partial(Known::RoadInput, &lin),
        7.0
    );
    assert_eq!(
        OutputId::WeightedBodyAcceleration.partial(Known::State(X_S), &lin),
        0.0
    );
    assert_eq!(OutputId::State(X_H).partial(Known::State(X_H), &lin), 0.0);
    assert_eq!(
        OutputId::BodyAcceleration.partial(Known::State(V_H), &lin),
        4.0
    );
    assert_eq!(OutputId::BodyForce.partial(Known::State(V_H), &lin), -4.0);
    assert_eq!(OutputId::BodyForce.partial(Known::RoadInput, &lin), 0.0);
    assert_eq!(
        OutputId::TireDeflection.partial(Known::RoadInput, &lin),
        -1.0
    );
    assert_eq!(
        OutputId::ControlForce.partial(Known::State(V_T), &lin),
        -5.0
    );
    assert_eq!(OutputId::Objective.partial(Known::State(X_S), &lin), 0.0);
    let lin = Linearization {
        road_is_input: false,
        ..lin
    };
    assert_eq!(
        OutputId::RoadDisplacement.partial(Known::RoadInput, &lin),
        0.0
    );
}

#[test]
fn the_fmi3_additions_follow_the_common_variables() {
    let first = FMI3_VARIABLES.iter().position(|v| v.fmi3_only).unwrap();
    assert!(FMI3_VARIABLES[first..].iter().all(|v| v.fmi3_only));
    assert_eq!(COMMON_VARIABLES.len(), first);
    assert!(COMMON_VARIABLES.iter().all(|v| v.is_in(FmiVersion::Fmi2)));
    assert!(!FMI3_VARIABLES[first].is_in(FmiVersion::Fmi2));
}

#[test]
fn the_value_reference_table_finds_what_a_search_finds() {
    for model in Model::ALL {
        for version in [FmiVersion::Fmi2, FmiVersion::Fmi3] {
            let variables = variables_of(model, version);
            let largest = variables.iter().map(|v| v.vr).max().unwrap();
            for vr in (0..=largest + 10).chain([u32::MAX]) {
                let searched = variables.iter().find(|v| v.vr == vr);
                assert_eq!(
                    by_vr(model, version, vr).map(|v| v.name),
                    searched.map(|v| v.name),
                    "{model:?} {version:?} {vr}"
                );
            }
        }
    }
}

#[test]
fn every_continuous_state_has_one_variable_and_one_derivative() {
    use tdvass::solver::CONTINUOUS_STATES;
    for i in 0..CONTINUOUS_STATES {
        let states: Vec<_> = COMMON_VARIABLES
            .iter()
            .filter(|v| v.state_index() == Some(i))
            .collect();
        assert_eq!(states.len(), 1, "state {i}");
        let derivatives: Vec<_> = COMMON_VARIABLES
            .iter()
            .filter(|v| matches!(v.access, Access::StateDerivative(j) if j == i))
            .collect();
        assert_eq!(derivatives.len(), 1, "derivative of state {i}");
        assert_eq!(derivatives[0].name, format!("der({})", states[0].name));
        assert_eq!(
            states[0].name,
            tdvass::exchange::state_names()[i],
            "the library's name of state {i}"
        );
    }
}
