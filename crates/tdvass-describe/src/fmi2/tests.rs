//! The FMI 2.0 model descriptions of every model, attribute by attribute
//! against the one variable table: one file for the whole description, so
//! that each test reads it the same way (hence its length).

use super::*;
use crate::parsed::elements;
use tdvass::solver::CONTINUOUS_STATES;
use tdvass_fmu::variables::COMMON_VARIABLES;

#[test]
fn model_description_has_every_variable() {
    let xml = model_description_xml(Model::QuarterCar);
    let els = elements(&xml);
    let root = &els[0];
    assert_eq!(root.name, "fmiModelDescription");
    assert_eq!(root.attr("guid"), guid(Model::QuarterCar));
    assert_eq!(root.attr("modelName"), "TDVASS");
    assert_eq!(root.attr("fmiVersion"), "2.0");
    let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
    assert_eq!(cs.attr("modelIdentifier"), "tdvass");
    for flag in [
        "canHandleVariableCommunicationStepSize",
        "canInterpolateInputs",
        "canGetAndSetFMUstate",
        "canSerializeFMUstate",
        "providesDirectionalDerivative",
    ] {
        assert_eq!(cs.attr(flag), "true", "{flag}");
    }
    assert_eq!(cs.attr("maxOutputDerivativeOrder"), "1");
    let experiment = els.iter().find(|e| e.name == "DefaultExperiment").unwrap();
    assert_eq!(experiment.attr("stopTime"), "15");
    assert_eq!(experiment.attr("stepSize"), "0.001");
    let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
    assert_eq!(vars.len(), COMMON_VARIABLES.len());
    for (v, el) in COMMON_VARIABLES.iter().zip(&vars) {
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("causality"), v.causality.as_str());
    }
    let categories: Vec<_> = els
        .iter()
        .filter(|e| e.name == "Category")
        .map(|e| e.attr("name"))
        .collect();
    for c in [
        "logEvents",
        "logStatusWarning",
        "logStatusError",
        "logStatusFatal",
        "logAll",
    ] {
        assert!(categories.contains(&c), "{c}");
    }
    let mm = els
        .iter()
        .find(|e| e.name == "DisplayUnit" && e.attr("name") == "mm")
        .unwrap();
    assert_eq!(mm.attr("factor"), "1000");
    let tdd = els
        .iter()
        .position(|e| e.name == "ScalarVariable" && e.attr("name") == "tire_deflection")
        .unwrap();
    assert_eq!(els[tdd + 1].attr("displayUnit"), "mm");
    assert_eq!(els[tdd + 1].attr("unit"), "m");
}

#[test]
fn model_structure_lists_outputs_derivatives_and_initial_unknowns() {
    let xml = model_description_xml(Model::QuarterCar);
    let els = elements(&xml);
    let at = |name: &str| els.iter().position(|e| e.name == name).unwrap();
    let (outputs_at, derivatives_at, initial_at) =
        (at("Outputs"), at("Derivatives"), at("InitialUnknowns"));
    let outputs: Vec<_> = els[outputs_at + 1..derivatives_at].iter().collect();
    let derivatives: Vec<_> = els[derivatives_at + 1..initial_at].iter().collect();
    let initial: Vec<_> = els[initial_at + 1..].iter().collect();
    let count = |c: Causality| COMMON_VARIABLES.iter().filter(|v| v.causality == c).count();
    // The locals are not outputs.
    assert_eq!(outputs.len(), count(Causality::Output));
    assert_eq!(outputs.len(), 23);
    let local_states = COMMON_VARIABLES
        .iter()
        .filter(|v| matches!(v.access, Access::ContinuousState(_)))
        .count();
    assert_eq!(local_states, 13);
    // FMI 2.0: the outputs and calculated parameters (all calculated),
    // the states with initial = calculated (the outputs among them
    // once) and every derivative; not the event indicator.
    assert_eq!(
        initial.len(),
        count(Causality::Output)
            + count(Causality::CalculatedParameter)
            + local_states
            + CONTINUOUS_STATES
    );
    assert_eq!(initial.len(), 25 + 13 + 20);
    let initial_indices: Vec<usize> = initial
        .iter()
        .map(|e| e.attr("index").parse().unwrap())
        .collect();
    assert!(initial_indices.windows(2).all(|w| w[0] < w[1]), "ascending");
    for (i, v) in COMMON_VARIABLES.iter().enumerate() {
        let listed = initial_indices.contains(&(i + 1));
        let expected = matches!(
            v.causality,
            Causality::Output | Causality::CalculatedParameter
        ) || matches!(
            v.access,
            Access::ContinuousState(_) | Access::StateDerivative(_)
        );
        assert_eq!(listed, expected, "{}", v.name);
    }
    // The outputs depend on the input x_g where it feeds through
    // (fixed) and on the continuous states they are computed from.
    let x_g = index_of(Model::QuarterCar, "x_g").unwrap();
    for o in &outputs {
        let deps: Vec<usize> = o
            .attr("dependencies")
            .split_whitespace()
            .map(|i| i.parse().unwrap())
            .collect();
        let kinds: Vec<&str> = o
            .get("dependenciesKind")
            .unwrap_or("")
            .split_whitespace()
            .collect();
        assert_eq!(deps.len(), kinds.len(), "{:?}", o.attributes);
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
        for (&d, &kind) in deps.iter().zip(&kinds) {
            let known = &COMMON_VARIABLES[d - 1];
            if d == x_g {
                assert_eq!(kind, "fixed");
            } else {
                assert!(known.state_index().is_some(), "{}", known.name);
                assert_eq!(kind, "dependent");
            }
        }
    }
    let output = |name: &str| {
        let index = index_of(Model::QuarterCar, name).unwrap().to_string();
        outputs.iter().find(|e| e.attr("index") == index).unwrap()
    };
    let plant: Vec<usize> = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"]
        .iter()
        .map(|n| index_of(Model::QuarterCar, n).unwrap())
        .collect();
    let mut expected: Vec<usize> = plant.iter().copied().chain([x_g]).collect();
    expected.sort_unstable();
    let listed =
        |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
    assert_eq!(
        listed(output("tire_deflection").attr("dependencies")),
        expected
    );
    let x_s = index_of(Model::QuarterCar, "x_s").unwrap().to_string();
    assert_eq!(output("x_s").attr("dependencies"), x_s);
    assert_eq!(
        output("rms_tire_deflection").attr("dependencies"),
        index_of(Model::QuarterCar, "integral_tire_deflection_squared")
            .unwrap()
            .to_string()
    );

    // One derivative per state, in state order, each without
    // dependencies (on every known), its `derivative` the state's index.
    assert_eq!(derivatives.len(), CONTINUOUS_STATES);
    assert_eq!(derivatives.len(), 20);
    let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
    // The type element (`Real`) of the variable of a 1-based index.
    let typed = |index: usize| {
        let at = els
            .iter()
            .position(|e| std::ptr::eq(e, vars[index - 1]))
            .unwrap();
        &els[at + 1]
    };
    for (i, d) in derivatives.iter().enumerate() {
        assert_eq!(d.get("dependencies"), None);
        let index: usize = d.attr("index").parse().unwrap();
        let der = &COMMON_VARIABLES[index - 1];
        assert!(
            matches!(der.access, Access::StateDerivative(j) if j == i),
            "{}",
            der.name
        );
        let state: usize = typed(index).attr("derivative").parse().unwrap();
        let state = &COMMON_VARIABLES[state - 1];
        assert_eq!(state.state_index(), Some(i));
        assert_eq!(der.name, format!("der({})", state.name));
        assert_eq!(state.variability.as_str(), "continuous");
    }
    let named = |name: &str| typed(index_of(Model::QuarterCar, name).unwrap());
    assert_eq!(
        named("der(x_s)").attr("derivative"),
        index_of(Model::QuarterCar, "x_s").unwrap().to_string()
    );
    assert_eq!(
        named("der(wk_filter_1)").attr("derivative"),
        index_of(Model::QuarterCar, "wk_filter_1")
            .unwrap()
            .to_string()
    );
    assert_eq!(
        named("der(contact_loss_time)").attr("derivative"),
        index_of(Model::QuarterCar, "contact_loss_time")
            .unwrap()
            .to_string()
    );
    // Only the derivatives have the attribute.
    let with_derivative = (1..=vars.len())
        .filter(|&index| typed(index).get("derivative").is_some())
        .count();
    assert_eq!(with_derivative, CONTINUOUS_STATES);
}

#[test]
fn model_exchange_beside_co_simulation() {
    let xml = model_description_xml(Model::QuarterCar);
    let els = elements(&xml);
    let root = &els[0];
    assert_eq!(
        root.attr("numberOfEventIndicators"),
        EVENT_INDICATORS.to_string()
    );
    let top: Vec<&str> = els
        .iter()
        .filter(|e| e.parent == Some(0))
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(
        &top[..3],
        ["ModelExchange", "CoSimulation", "UnitDefinitions"]
    );
    let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
    assert_eq!(me.attr("modelIdentifier"), "tdvass");
    for (flag, value) in [
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("completedIntegratorStepNotNeeded", "false"),
        ("canNotUseMemoryManagementFunctions", "true"),
        ("providesDirectionalDerivative", "true"),
        ("needsExecutionTool", "false"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ] {
        assert_eq!(me.attr(flag), value, "{flag}");
    }
    assert_eq!(me.attributes.len(), 1 + MODEL_EXCHANGE_CAPABILITIES.len());
    // The locals are continuous with initial = calculated.
    for v in els
        .iter()
        .filter(|e| e.name == "ScalarVariable" && e.attr("causality") == "local")
    {
        assert_eq!(v.attr("variability"), "continuous", "{}", v.attr("name"));
        assert_eq!(v.attr("initial"), "calculated", "{}", v.attr("name"));
    }
}

#[test]
fn documentation_describes_every_variable() {
    let html = documentation_html(Model::QuarterCar);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    for v in COMMON_VARIABLES {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    assert!(html.contains("1 - g/k_h"));
    assert!(html.contains("0.3068"));
    assert!(html.contains("FMI 2.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains("<td>local, continuous</td>"));
    assert!(html.contains("x_s, v_s, x_h, v_h, x_t, v_t, wk_filter_1"));
    assert!(html.contains("integral_weighted_acceleration_fourth, contact_loss_time."));
    assert!(html.contains("The event indicator contact_indicator"));
}

#[test]
fn output_is_deterministic() {
    for model in Model::ALL {
        assert_eq!(model_description_xml(model), model_description_xml(model));
        assert_eq!(documentation_html(model), documentation_html(model));
    }
}

/// The corner's description: Co-Simulation and Model Exchange (its own
/// states, no directional derivatives), its own name, GUID and
/// variables, and a ModelStructure that refers to them.
#[test]
fn the_corner_is_described_with_model_exchange() {
    let model = Model::Corner;
    let xml = model_description_xml(model);
    let els = elements(&xml);
    let root = &els[0];
    assert_eq!(root.name, "fmiModelDescription");
    assert_eq!(root.attr("fmiVersion"), "2.0");
    assert_eq!(root.attr("modelName"), "TDVASS corner");
    assert_eq!(root.attr("modelName"), model.name());
    assert_eq!(root.attr("guid"), guid(Model::Corner));
    assert_eq!(
        root.attr("guid"),
        tdvass_fmu::variables::guid(Model::Corner)
    );
    assert_ne!(root.attr("guid"), guid(Model::QuarterCar));
    assert_eq!(root.attr("description"), crate::markup::CORNER_DESCRIPTION);
    assert_eq!(root.get("numberOfEventIndicators"), Some("1"));
    let top: Vec<&str> = els
        .iter()
        .filter(|e| e.parent == Some(0))
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(
        top,
        [
            "ModelExchange",
            "CoSimulation",
            "UnitDefinitions",
            "TypeDefinitions",
            "LogCategories",
            "DefaultExperiment",
            "ModelVariables",
            "ModelStructure"
        ]
    );
    let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
    assert_eq!(me.attributes.len(), 1 + MODEL_EXCHANGE_CAPABILITIES.len());
    for (flag, value) in MODEL_EXCHANGE_CAPABILITIES {
        assert_eq!(me.attr(flag), value, "{flag}");
    }
    assert_eq!(me.attr("providesDirectionalDerivative"), "true");
    let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
    assert_eq!(cs.attr("modelIdentifier"), MODEL_IDENTIFIER);
    assert_eq!(cs.attributes.len(), 1 + CO_SIMULATION_CAPABILITIES.len());

    let variables = variables_of(model, FmiVersion::Fmi2);
    let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
    assert_eq!(vars.len(), variables.len());
    for (v, el) in variables.iter().zip(&vars) {
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("causality"), v.causality.as_str());
    }
    // The corner's 7 states: x_h, v_h, x_t, v_t, the integrals of SDD^2
    // and TDD^2, the time without contact; each with its derivative.
    let states = Model::Corner.continuous_states();
    assert_eq!(states.len(), 7);
    assert_eq!(
        els.iter().filter(|e| e.get("derivative").is_some()).count(),
        states.len()
    );

    // ModelStructure: the outputs, the derivatives and the initial
    // unknowns; every dependency an index of an existing variable.
    let structure = els.iter().position(|e| e.name == "ModelStructure").unwrap();
    let parts: Vec<&str> = els
        .iter()
        .filter(|e| e.parent == Some(structure))
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(parts, ["Outputs", "Derivatives", "InitialUnknowns"]);
    let unknowns_of = |part: &str| -> Vec<&crate::parsed::Element> {
        let at = els.iter().position(|e| e.name == part).unwrap();
        els.iter().filter(|e| e.parent == Some(at)).collect()
    };
    let listed =
        |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
    let derivatives = unknowns_of("Derivatives");
    assert_eq!(derivatives.len(), states.len());
    for (d, &i) in derivatives.iter().zip(states) {
        let v = &variables[d.attr("index").parse::<usize>().unwrap() - 1];
        assert!(
            matches!(v.access, Access::StateDerivative(j) if j == i),
            "{}",
            v.name
        );
    }
    let outputs = unknowns_of("Outputs");
    let expected: Vec<String> = variables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    let indices: Vec<&str> = outputs.iter().map(|e| e.attr("index")).collect();
    assert_eq!(indices, expected);
    for unknown in outputs.iter().chain(&unknowns_of("InitialUnknowns")) {
        let deps = listed(unknown.get("dependencies").unwrap_or(""));
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
        for d in deps {
            assert!(
                (1..=variables.len()).contains(&d),
                "{:?}",
                unknown.attributes
            );
        }
    }
    for o in &outputs {
        let deps = listed(o.attr("dependencies"));
        let kinds: Vec<&str> = o
            .get("dependenciesKind")
            .unwrap_or("")
            .split_whitespace()
            .collect();
        assert_eq!(deps.len(), kinds.len(), "{:?}", o.attributes);
        // The inputs and the corner's own states (never the body's
        // coordinates, which are inputs).
        for d in deps {
            let known = &variables[d - 1];
            assert!(
                known.causality == Causality::Input
                    || known.state_index().is_some_and(|i| states.contains(&i)),
                "{}",
                known.name
            );
        }
    }
    let index = |name: &str| index_of(model, name).unwrap();
    let body_force = outputs
        .iter()
        .find(|e| e.attr("index") == index("body_force").to_string())
        .unwrap();
    // The body's coordinates feed through; the wheel's and the
    // absorber's are states.
    assert_eq!(
        listed(body_force.attr("dependencies")),
        [
            index("x_h"),
            index("v_h"),
            index("x_t"),
            index("v_t"),
            index("body_displacement"),
            index("body_velocity")
        ]
    );
    assert_eq!(
        body_force.attr("dependenciesKind"),
        "dependent dependent dependent dependent fixed fixed"
    );
}

#[test]
fn the_corner_documentation_describes_its_variables() {
    let html = documentation_html(Model::Corner);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    assert!(html.contains("<title>TDVASS corner FMI 2.0 FMU</title>"));
    assert!(html.contains("TDVASS corner: FMI 2.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains(&guid(Model::Corner)));
    assert!(html.contains("integrates its 7 continuous states"));
    for v in variables_of(Model::Corner, FmiVersion::Fmi2) {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    for (flag, _) in CO_SIMULATION_CAPABILITIES {
        assert!(html.contains(&format!("<td>{flag}</td>")), "{flag}");
    }
    assert!(html.contains("body_force (output, N)"));
    assert!(!html.contains("m_s (start"));
}

/// Every model's description defines the types and units its
/// variables use, each once, and no others.
#[test]
fn types_and_units_are_those_the_variables_use() {
    for model in Model::ALL {
        let xml = model_description_xml(model);
        let els = elements(&xml);
        let types: Vec<&str> = els
            .iter()
            .filter(|e| e.name == "SimpleType")
            .map(|e| e.attr("name"))
            .collect();
        let units: Vec<&str> = els
            .iter()
            .filter(|e| e.name == "Unit")
            .map(|e| e.attr("name"))
            .collect();
        let vars: Vec<_> = els.iter().filter(|e| e.parent.is_some()).collect();
        let declared: Vec<&str> = vars.iter().filter_map(|e| e.get("declaredType")).collect();
        let used: Vec<&str> = vars.iter().filter_map(|e| e.get("unit")).collect();
        for t in &types {
            assert!(declared.contains(t), "{model:?}: {t} unused");
            assert_eq!(types.iter().filter(|u| *u == t).count(), 1, "{t}");
        }
        for t in &declared {
            assert!(types.contains(t), "{model:?}: {t} undefined");
        }
        for u in &units {
            assert!(used.contains(u), "{model:?}: {u} unused");
            assert_eq!(units.iter().filter(|v| *v == u).count(), 1, "{u}");
        }
        for u in &used {
            assert!(units.contains(u), "{model:?}: {u} undefined");
        }
    }
    // The quarter car uses the twelve of the suspension; the chassis
    // its angles and inertias, which the suspension does not.
    assert_eq!(quantities(Model::QuarterCar).len(), 12);
    for q in [
        Quantity::Angle,
        Quantity::AngularVelocity,
        Quantity::AngularAcceleration,
        Quantity::Inertia,
    ] {
        assert!(!quantities(Model::QuarterCar).contains(&q), "{q:?}");
        assert!(quantities(Model::Chassis).contains(&q), "{q:?}");
    }
}

/// The chassis's description: Co-Simulation and Model Exchange with its own
/// capabilities, its own name, GUID and variables, and a ModelStructure
/// whose outputs depend on the forces where they feed through.
#[test]
fn the_chassis_is_described_with_its_own_capabilities() {
    let model = Model::Chassis;
    let xml = model_description_xml(model);
    let els = elements(&xml);
    let root = &els[0];
    assert_eq!(root.attr("fmiVersion"), "2.0");
    assert_eq!(root.attr("modelName"), "TDVASS chassis");
    assert_eq!(root.attr("guid"), guid(Model::Chassis));
    for other in [Model::QuarterCar, Model::Corner] {
        assert_ne!(root.attr("guid"), guid(other));
    }
    assert_eq!(root.attr("description"), crate::markup::CHASSIS_DESCRIPTION);
    assert_eq!(root.get("numberOfEventIndicators"), Some("0"));
    let top: Vec<&str> = els
        .iter()
        .filter(|e| e.parent == Some(0))
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(
        top,
        [
            "ModelExchange",
            "CoSimulation",
            "UnitDefinitions",
            "TypeDefinitions",
            "LogCategories",
            "DefaultExperiment",
            "ModelVariables",
            "ModelStructure"
        ]
    );
    let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
    assert_eq!(cs.attr("modelIdentifier"), MODEL_IDENTIFIER);
    assert_eq!(
        cs.attributes.len(),
        1 + CHASSIS_CO_SIMULATION_CAPABILITIES.len()
    );
    for (flag, value) in [
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canInterpolateInputs", "true"),
        ("maxOutputDerivativeOrder", "0"),
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("providesDirectionalDerivative", "false"),
        ("needsExecutionTool", "false"),
    ] {
        assert_eq!(cs.attr(flag), value, "{flag}");
    }
    // The same attributes as the quarter car's, in the same order.
    let names = |c: &[(&str, &str)]| c.iter().map(|(n, _)| n.to_string()).collect::<Vec<_>>();
    assert_eq!(
        names(&CHASSIS_CO_SIMULATION_CAPABILITIES),
        names(&CO_SIMULATION_CAPABILITIES)
    );

    let variables = variables_of(model, FmiVersion::Fmi2);
    let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
    assert_eq!(vars.len(), variables.len());
    for (v, el) in variables.iter().zip(&vars) {
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("causality"), v.causality.as_str());
    }
    let pitch = els
        .iter()
        .position(|e| e.get("name") == Some("pitch"))
        .unwrap();
    assert_eq!(els[pitch + 1].attr("declaredType"), "Angle");
    assert_eq!(els[pitch + 1].attr("unit"), "rad");

    let structure = els.iter().position(|e| e.name == "ModelStructure").unwrap();
    let parts: Vec<&str> = els
        .iter()
        .filter(|e| e.parent == Some(structure))
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(parts, ["Outputs", "Derivatives", "InitialUnknowns"]);
    let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
    for (flag, value) in CHASSIS_MODEL_EXCHANGE_CAPABILITIES {
        assert_eq!(me.attr(flag), value, "{flag}");
    }
    let unknowns_of = |part: &str| -> Vec<&crate::parsed::Element> {
        let at = els.iter().position(|e| e.name == part).unwrap();
        els.iter().filter(|e| e.parent == Some(at)).collect()
    };
    let listed =
        |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
    let index = |name: &str| index_of(model, name).unwrap();
    let forces: Vec<usize> = ["force_fl", "force_fr", "force_rl", "force_rr"]
        .iter()
        .map(|n| index(n))
        .collect();
    let outputs = unknowns_of("Outputs");
    let expected: Vec<String> = variables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    let output_indices: Vec<&str> = outputs.iter().map(|e| e.attr("index")).collect();
    assert_eq!(output_indices, expected);
    let feedthrough = [
        "heave_acceleration",
        "pitch_acceleration",
        "roll_acceleration",
        "seat_acceleration",
    ];
    for o in &outputs {
        let v = &variables[o.attr("index").parse::<usize>().unwrap() - 1];
        let deps = listed(o.attr("dependencies"));
        if feedthrough.contains(&v.name) {
            assert_eq!(deps, forces, "{}", v.name);
            assert_eq!(
                o.attr("dependenciesKind"),
                "fixed fixed fixed fixed",
                "{}",
                v.name
            );
        } else {
            // The attachment points' motion, the states and the time
            // averages: from the continuous states alone, no algebraic
            // loop.
            assert!(!deps.is_empty(), "{}", v.name);
            for d in deps {
                assert!(variables[d - 1].state_index().is_some(), "{}", v.name);
            }
        }
    }
    let displacement = outputs
        .iter()
        .find(|e| e.attr("index") == index("displacement_fl").to_string())
        .unwrap();
    assert_eq!(
        listed(displacement.attr("dependencies")),
        [index("heave"), index("pitch"), index("roll")]
    );
    assert_eq!(
        unknowns_of("Derivatives").len(),
        tdvass::chassis::CHASSIS_STATES
    );
    // Every output is an initial unknown, with the initial dependencies
    // of the table; so are the local states and the derivatives (on
    // every known).
    let initial = unknowns_of("InitialUnknowns");
    assert_eq!(
        initial.len(),
        outputs.len() + 2 * tdvass::chassis::CHASSIS_STATES - 6
    );
    for u in &initial {
        let v = &variables[u.attr("index").parse::<usize>().unwrap() - 1];
        if v.causality == Causality::Local {
            assert_eq!(u.get("dependencies"), None, "{}", v.name);
            continue;
        }
        assert_eq!(
            u.attr("dependencies"),
            indices(model, v.initial_dependencies),
            "{}",
            v.name
        );
    }
    let seat = initial
        .iter()
        .find(|e| e.attr("index") == index("seat_acceleration").to_string())
        .unwrap();
    assert!(listed(seat.attr("dependencies")).contains(&index("seat_x")));
}

#[test]
fn the_chassis_documentation_describes_its_variables_and_capabilities() {
    let html = documentation_html(Model::Chassis);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    assert!(html.contains("<title>TDVASS chassis FMI 2.0 FMU</title>"));
    assert!(html.contains("TDVASS chassis: FMI 2.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains(&guid(Model::Chassis)));
    assert!(html.contains("integrates its 19 continuous states"));
    assert!(html.contains("picks the chassis when the FMU is instantiated"));
    for v in variables_of(Model::Chassis, FmiVersion::Fmi2) {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    for (flag, value) in CHASSIS_CO_SIMULATION_CAPABILITIES {
        assert!(
            html.contains(&format!("<td>{flag}</td>\n        <td>{value}</td>")),
            "{flag}"
        );
    }
    for text in [
        "positive nose up",
        "positive left side up",
        "z + x theta + y phi",
        "front and rear decouple",
        "fmi2SetRealInputDerivatives",
        "no algebraic loop",
        "mass = 4 x 345 kg = 1380 kg",
        "a = 1.3 m, b = 1.3 m",
        "pitch_inertia = m a b = 2332.2 kg m2, roll_inertia = 400 kg m2",
        "track_front = 1.5 m, track_rear = 1.5 m",
        "ISO 2631-1",
        "mass (start 1380 kg)",
        "force_fl (input, N)",
    ] {
        assert!(html.contains(text), "{text}");
    }
    // Its legend is its own: no symbol of the suspension's.
    assert!(!html.contains("m_s (start"));
    assert!(!html.contains("control_force"));
    assert!(!html.contains("<h3>Enumerations</h3>"));
}
