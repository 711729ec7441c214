//! The FMI 3.0 model descriptions of every model, attribute by attribute
//! against the one variable table: one file for the whole description, so
//! that each test reads it the same way (hence its length).

use super::*;
use crate::parsed::{Element, elements};
use std::collections::{HashMap, HashSet};
use tdvass_fmu::LOG_CATEGORIES;
use tdvass_fmu::Model;
use tdvass_fmu::variables::{
    COMMON_VARIABLES, FMI3_VARIABLES, Initial, ROAD_CLASS_ITEMS, ROAD_ITEMS, TIRE_CONTACT_ITEMS,
    VARIANT_ITEMS,
};

/// The children of the first element called `parent`.
fn children<'a>(els: &'a [Element], parent: &str) -> Vec<&'a Element> {
    let at = els.iter().position(|e| e.name == parent).unwrap();
    els.iter().filter(|e| e.parent == Some(at)).collect()
}

fn vr_list_of(text: &str) -> Vec<u32> {
    text.split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect()
}

#[test]
fn root_co_simulation_and_experiment() {
    let els = elements(&model_description_xml(Model::QuarterCar));
    let root = &els[0];
    assert_eq!(root.name, "fmiModelDescription");
    assert_eq!(root.attr("fmiVersion"), "3.0");
    assert_eq!(root.attr("modelName"), "TDVASS");
    assert_eq!(
        root.attr("instantiationToken"),
        instantiation_token(Model::QuarterCar)
    );
    assert_eq!(root.attr("variableNamingConvention"), "flat");
    assert!(root.get("guid").is_none());
    let top: Vec<&str> = children(&els, "fmiModelDescription")
        .iter()
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
    assert_eq!(cs.attr("modelIdentifier"), "tdvass");
    assert_eq!(cs.attributes.len(), 1 + CO_SIMULATION_CAPABILITIES.len());
    for (flag, value) in CO_SIMULATION_CAPABILITIES {
        assert_eq!(cs.attr(flag), value, "{flag}");
    }
    for flag in [
        "canHandleVariableCommunicationStepSize",
        "canGetAndSetFMUState",
        "canSerializeFMUState",
        "providesDirectionalDerivatives",
        "providesAdjointDerivatives",
        "providesIntermediateUpdate",
        "canReturnEarlyAfterIntermediateUpdate",
    ] {
        assert_eq!(cs.attr(flag), "true", "{flag}");
    }
    assert_eq!(cs.attr("maxOutputDerivativeOrder"), "1");
    assert_eq!(cs.attr("hasEventMode"), "false");
    let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
    assert_eq!(me.attr("modelIdentifier"), "tdvass");
    assert_eq!(me.attributes.len(), 1 + MODEL_EXCHANGE_CAPABILITIES.len());
    for (flag, value) in [
        ("canGetAndSetFMUState", "true"),
        ("canSerializeFMUState", "true"),
        ("needsCompletedIntegratorStep", "true"),
        ("providesDirectionalDerivatives", "true"),
        ("providesAdjointDerivatives", "true"),
        ("providesEvaluateDiscreteStates", "false"),
        ("needsExecutionTool", "false"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ] {
        assert_eq!(me.attr(flag), value, "{flag}");
    }
    // FMI 3.0 has no numberOfEventIndicators: the EventIndicator elements say it.
    assert!(root.get("numberOfEventIndicators").is_none());
    let experiment = els.iter().find(|e| e.name == "DefaultExperiment").unwrap();
    assert_eq!(experiment.attr("startTime"), "0");
    assert_eq!(experiment.attr("stopTime"), "15");
    assert_eq!(experiment.attr("stepSize"), "0.001");
    let categories: Vec<(&str, &str)> = children(&els, "LogCategories")
        .iter()
        .map(|e| (e.attr("name"), e.attr("description")))
        .collect();
    assert_eq!(categories, LOG_CATEGORIES);
}

#[test]
fn every_variable_has_the_values_of_the_table() {
    let els = elements(&model_description_xml(Model::QuarterCar));
    let vars = children(&els, "ModelVariables");
    assert_eq!(vars.len(), FMI3_VARIABLES.len());
    // Exactly one independent variable: a Float64 in s without start or
    // initial.
    let independent: Vec<&&Element> = vars
        .iter()
        .filter(|e| e.get("causality") == Some("independent"))
        .collect();
    assert_eq!(independent.len(), 1);
    let time = independent[0];
    assert_eq!(time.name, "Float64");
    assert_eq!(time.attr("name"), "time");
    assert_eq!(time.attr("variability"), "continuous");
    assert_eq!(time.attr("unit"), "s");
    assert!(time.get("start").is_none() && time.get("initial").is_none());
    for (v, el) in FMI3_VARIABLES.iter().zip(&vars) {
        assert_eq!(el.name, fmi3_type(v).as_str(), "{}", v.name);
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("description"), v.description);
        assert_eq!(el.attr("causality"), v.causality.as_str());
        assert_eq!(el.attr("variability"), v.variability.as_str());
        assert_eq!(el.get("initial"), v.initial().map(Initial::as_str));
        assert_eq!(el.get("unit"), v.unit().filter(|_| v.enumeration.is_none()));
        assert_eq!(el.get("displayUnit"), v.display_unit);
        let declared = match (v.enumeration, v.quantity.type_definition()) {
            (Some(e), _) => Some(e.type_name),
            (None, Some((name, _, _))) => Some(name),
            (None, None) => None,
        };
        assert_eq!(el.get("declaredType"), declared, "{}", v.name);
        let parse = |s: &str| s.parse::<f64>().unwrap();
        assert_eq!(el.get("start").map(parse), v.start, "{}", v.name);
        let (min, max) = v.range.bounds();
        assert_eq!(el.get("min").map(parse), min, "{}", v.name);
        assert_eq!(el.get("max").map(parse), max, "{}", v.name);
        assert_eq!(
            el.get("intermediateUpdate"),
            v.intermediate_update.then_some("true"),
            "{}",
            v.name
        );
        if fmi3_type(v) != Fmi3Type::Float64 {
            for key in ["start", "min", "max"] {
                if let Some(text) = el.get(key) {
                    assert!(!text.contains('.'), "{} {key}={text}", v.name);
                }
            }
        }
    }
    let vrs: HashSet<&str> = vars.iter().map(|e| e.attr("valueReference")).collect();
    assert_eq!(vrs.len(), vars.len());
    // The FMI 2.0 variables keep their names and value references.
    for v in COMMON_VARIABLES {
        assert!(
            vars.iter()
                .any(|e| e.attr("name") == v.name && e.attr("valueReference") == v.vr.to_string())
        );
    }
}

#[test]
fn enumerations_types_and_units_are_declared() {
    let els = elements(&model_description_xml(Model::QuarterCar));
    let types = children(&els, "TypeDefinitions");
    let units: HashMap<&str, usize> = els
        .iter()
        .enumerate()
        .filter(|(_, e)| e.name == "Unit")
        .map(|(i, e)| (e.attr("name"), i))
        .collect();
    for t in types.iter().filter(|t| t.name == "Float64Type") {
        assert!(units.contains_key(t.attr("unit")), "{}", t.attr("unit"));
    }
    let declared: HashSet<&str> = types.iter().map(|t| t.attr("name")).collect();
    assert_eq!(declared.len(), types.len());
    for v in children(&els, "ModelVariables") {
        if let Some(name) = v.get("declaredType") {
            assert!(declared.contains(name), "{name}");
        }
        if let Some(unit) = v.get("unit") {
            assert!(units.contains_key(unit), "{unit}");
        }
        if let Some(display) = v.get("displayUnit") {
            let unit = units[v.attr("unit")];
            assert!(
                els.iter().any(|e| e.parent == Some(unit)
                    && e.name == "DisplayUnit"
                    && e.attr("name") == display),
                "{display}"
            );
        }
    }
    assert_eq!(
        enumerations(Model::QuarterCar)
            .iter()
            .map(|e| e.type_name)
            .collect::<Vec<_>>(),
        ["Variant", "Road", "RoadClass", "TireContact"]
    );
    for e in [
        &VARIANT_ITEMS,
        &ROAD_ITEMS,
        &ROAD_CLASS_ITEMS,
        &TIRE_CONTACT_ITEMS,
    ] {
        let at = els
            .iter()
            .position(|t| t.name == "EnumerationType" && t.attr("name") == e.type_name)
            .unwrap_or_else(|| panic!("no EnumerationType {}", e.type_name));
        let items: Vec<(&str, i32, &str)> = els
            .iter()
            .filter(|i| i.parent == Some(at))
            .map(|i| {
                assert_eq!(i.name, "Item");
                (
                    i.attr("name"),
                    i.attr("value").parse().unwrap(),
                    i.attr("description"),
                )
            })
            .collect();
        let expected: Vec<(&str, i32, &str)> = e
            .items
            .iter()
            .map(|i| (i.name, i.value, i.description))
            .collect();
        assert_eq!(items, expected);
    }
    let tdd = children(&els, "ModelVariables")
        .into_iter()
        .find(|e| e.attr("name") == "tire_deflection")
        .unwrap();
    assert_eq!(tdd.attr("displayUnit"), "mm");
    assert_eq!(tdd.attr("unit"), "m");
    let variant = children(&els, "ModelVariables")
        .into_iter()
        .find(|e| e.attr("name") == "variant")
        .unwrap();
    assert_eq!(variant.name, "Enumeration");
    assert_eq!(variant.attr("declaredType"), "Variant");
    assert_eq!(variant.attr("start"), "3");
    let contact = children(&els, "ModelVariables")
        .into_iter()
        .find(|e| e.attr("name") == "tire_contact")
        .unwrap();
    assert_eq!(contact.name, "Enumeration");
    assert_eq!(contact.attr("declaredType"), "TireContact");
    assert_eq!(
        (contact.attr("causality"), contact.attr("variability")),
        ("parameter", "fixed")
    );
    assert_eq!(contact.attr("start"), "0");
    let count = children(&els, "ModelVariables")
        .into_iter()
        .find(|e| e.attr("name") == "lift_off_count")
        .unwrap();
    assert_eq!(count.name, "Int32");
    assert_eq!(
        (count.attr("causality"), count.attr("variability")),
        ("output", "discrete")
    );
    assert!(count.get("intermediateUpdate").is_none());
}

#[test]
fn arrays_have_their_dimensions() {
    let els = elements(&model_description_xml(Model::QuarterCar));
    let at = |name: &str| {
        els.iter()
            .position(|e| e.parent.is_some() && e.get("name") == Some(name))
            .unwrap()
    };
    let dimensions = |i: usize| -> Vec<&Element> {
        els.iter()
            .filter(|e| e.parent == Some(i) && e.name == "Dimension")
            .collect()
    };
    let root_count = &els[at("root_count")];
    assert_eq!(root_count.name, "UInt64");
    assert_eq!(root_count.attr("causality"), "structuralParameter");
    assert!(root_count.attr("start").parse::<u64>().unwrap() > 0);
    let roots = dimensions(at("rightmost_roots"));
    assert_eq!(roots.len(), 2);
    assert_eq!(
        roots[0].attributes,
        HashMap::from([(
            "valueReference".to_string(),
            root_count.attr("valueReference").to_string()
        )])
    );
    assert_eq!(
        roots[1].attributes,
        HashMap::from([("start".to_string(), "2".to_string())])
    );
    for v in FMI3_VARIABLES {
        assert_eq!(
            dimensions(at(v.name)).len(),
            v.dimensions.len(),
            "{}",
            v.name
        );
    }
    // Every Dimension refers to a UInt64 structural parameter with a
    // positive start.
    for d in els.iter().filter(|e| e.name == "Dimension") {
        if let Some(vr) = d.get("valueReference") {
            let p = els
                .iter()
                .find(|e| e.name == "UInt64" && e.get("valueReference") == Some(vr))
                .unwrap();
            assert_eq!(p.attr("causality"), "structuralParameter");
            assert!(p.attr("start").parse::<u64>().unwrap() > 0);
        }
    }
}

#[test]
fn model_structure_lists_outputs_and_initial_unknowns_by_value_reference() {
    let els = elements(&model_description_xml(Model::QuarterCar));
    let structure = children(&els, "ModelStructure");
    let outputs: Vec<&Element> = structure
        .iter()
        .copied()
        .filter(|e| e.name == "Output")
        .collect();
    let initial: Vec<&Element> = structure
        .iter()
        .copied()
        .filter(|e| e.name == "InitialUnknown")
        .collect();
    let derivatives: Vec<&Element> = structure
        .iter()
        .copied()
        .filter(|e| e.name == "ContinuousStateDerivative")
        .collect();
    let indicators: Vec<&Element> = structure
        .iter()
        .copied()
        .filter(|e| e.name == "EventIndicator")
        .collect();
    assert_eq!(
        outputs.len() + derivatives.len() + initial.len() + indicators.len(),
        structure.len()
    );
    // The schema's order: Output, ContinuousStateDerivative, InitialUnknown, EventIndicator.
    let order: Vec<&str> = structure.iter().map(|e| e.name.as_str()).collect();
    let rank = |name: &str| {
        [
            "Output",
            "ContinuousStateDerivative",
            "InitialUnknown",
            "EventIndicator",
        ]
        .iter()
        .position(|n| *n == name)
        .unwrap()
    };
    assert!(order.windows(2).all(|w| rank(w[0]) <= rank(w[1])));
    assert_eq!(derivatives.len(), tdvass::solver::CONTINUOUS_STATES);
    assert_eq!(derivatives.len(), 20);
    for (i, d) in derivatives.iter().enumerate() {
        assert_eq!(d.get("dependencies"), None);
        let der = by_vr_any(d.attr("valueReference"));
        assert!(
            matches!(der.access, Access::StateDerivative(j) if j == i),
            "{}",
            der.name
        );
        let element = els
            .iter()
            .find(|e| e.name == "Float64" && e.get("name") == Some(der.name))
            .unwrap();
        let state = by_vr_any(element.attr("derivative"));
        assert_eq!(state.state_index(), Some(i));
        assert_eq!(state_vr(Model::QuarterCar, i), state.vr);
        assert_eq!(der.name, format!("der({})", state.name));
        assert_eq!(state.variability.as_str(), "continuous");
    }
    // Only the derivatives have the attribute.
    let with_derivative = els
        .iter()
        .filter(|e| e.name == "Float64" && e.get("derivative").is_some())
        .count();
    assert_eq!(with_derivative, tdvass::solver::CONTINUOUS_STATES);
    let derivative_of = |name: &str| {
        els.iter()
            .find(|e| e.name == "Float64" && e.get("name") == Some(name))
            .unwrap()
            .attr("derivative")
    };
    assert_eq!(
        derivative_of("der(x_s)"),
        vr_of(Model::QuarterCar, "x_s").to_string()
    );
    assert_eq!(
        derivative_of("der(wk_filter_1)"),
        vr_of(Model::QuarterCar, "wk_filter_1").to_string()
    );
    assert_eq!(
        derivative_of("der(contact_loss_time)"),
        vr_of(Model::QuarterCar, "contact_loss_time").to_string()
    );
    // One continuous Float64 variable per event indicator.
    assert_eq!(indicators.len(), tdvass::exchange::EVENT_INDICATORS);
    let indicator = by_vr_any(indicators[0].attr("valueReference"));
    assert_eq!(indicator.name, "contact_indicator");
    assert!(matches!(indicator.access, Access::EventIndicator(0)));
    let element = els
        .iter()
        .find(|e| e.get("name") == Some(indicator.name))
        .unwrap();
    assert_eq!(element.name, "Float64");
    assert_eq!(element.attr("variability"), "continuous");
    // Outputs first, in ModelVariables order.
    assert!(
        structure[..outputs.len()]
            .iter()
            .all(|e| e.name == "Output")
    );
    let expected_outputs: Vec<String> = FMI3_VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .map(|v| v.vr.to_string())
        .collect();
    let listed: Vec<&str> = outputs.iter().map(|e| e.attr("valueReference")).collect();
    assert_eq!(listed, expected_outputs);
    assert_eq!(outputs.len(), 23);
    let expected_initial: Vec<String> = FMI3_VARIABLES
        .iter()
        .filter(|v| is_initial_unknown(v))
        .map(|v| v.vr.to_string())
        .collect();
    let listed: Vec<&str> = initial.iter().map(|e| e.attr("valueReference")).collect();
    assert_eq!(listed, expected_initial);
    // Outputs (the 7 states among them) and calculated parameters, the 13
    // local states and the 20 derivatives; not the event indicator.
    assert_eq!(initial.len(), 26 + 13 + tdvass::solver::CONTINUOUS_STATES);
    let local_states = FMI3_VARIABLES
        .iter()
        .filter(|v| matches!(v.access, Access::ContinuousState(_)))
        .count();
    assert_eq!(local_states, 13);
    for v in FMI3_VARIABLES {
        let listed = expected_initial.contains(&v.vr.to_string());
        let state_or_derivative =
            v.state_index().is_some() || matches!(v.access, Access::StateDerivative(_));
        if state_or_derivative {
            assert!(listed, "{}", v.name);
        }
        if matches!(v.access, Access::EventIndicator(_)) {
            assert!(!listed, "{}", v.name);
        }
    }
    // The local states and derivatives depend on every known.
    for u in &initial {
        let v = by_vr_any(u.attr("valueReference"));
        let on_every_known = matches!(
            v.access,
            Access::ContinuousState(_) | Access::StateDerivative(_)
        );
        assert_eq!(
            u.get("dependencies").is_none(),
            on_every_known,
            "{}",
            v.name
        );
    }

    let by_vr = |vr: u32| FMI3_VARIABLES.iter().find(|v| v.vr == vr).unwrap();
    let x_g = by_name(Model::QuarterCar, FmiVersion::Fmi3, "x_g")
        .unwrap()
        .vr;
    for o in &outputs {
        let deps = vr_list_of(o.attr("dependencies"));
        let kinds: Vec<&str> = o
            .get("dependenciesKind")
            .unwrap_or("")
            .split_whitespace()
            .collect();
        assert_eq!(kinds.len(), deps.len(), "{:?}", o.attributes);
        // Outputs depend on the knowns of both interfaces: the input x_g
        // (a factor fixed by `road`) and the continuous states.
        for (&d, &kind) in deps.iter().zip(&kinds) {
            if d == x_g {
                assert_eq!(kind, "fixed");
            } else {
                assert!(by_vr(d).state_index().is_some(), "{:?}", o.attributes);
                assert_eq!(kind, "dependent");
            }
        }
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
        let v = by_vr(o.attr("valueReference").parse().unwrap());
        let listed: Vec<(u32, &str)> = deps.iter().copied().zip(kinds).collect();
        assert_eq!(listed, output_dependencies(Model::QuarterCar, v));
    }
    let vr_of = |name: &str| {
        by_name(Model::QuarterCar, FmiVersion::Fmi3, name)
            .unwrap()
            .vr
    };
    let output = |name: &str| {
        outputs
            .iter()
            .find(|e| e.attr("valueReference") == vr_of(name).to_string())
            .unwrap()
    };
    let rms = output("rms_body_acceleration");
    assert_eq!(
        rms.attr("dependencies"),
        vr_of("integral_body_acceleration_squared").to_string()
    );
    assert_eq!(rms.attr("dependenciesKind"), "dependent");
    let tdd = outputs
        .iter()
        .find(|e| {
            e.attr("valueReference")
                == by_name(Model::QuarterCar, FmiVersion::Fmi3, "tire_deflection")
                    .unwrap()
                    .vr
                    .to_string()
        })
        .unwrap();
    let tdd_deps = vr_list_of(tdd.attr("dependencies"));
    let mut plant_and_x_g: Vec<u32> = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t", "x_g"]
        .iter()
        .map(|n| vr_of(n))
        .collect();
    plant_and_x_g.sort_unstable();
    assert_eq!(tdd_deps, plant_and_x_g);
    // A state output depends on itself only.
    let x_s = output("x_s");
    assert_eq!(x_s.attr("dependencies"), vr_of("x_s").to_string());
    assert_eq!(x_s.attr("dependenciesKind"), "dependent");

    // Initial dependencies are knowns of initialization mode: inputs and
    // variables with initial = exact; ascending, each once.
    for u in initial.iter().filter(|u| u.get("dependencies").is_some()) {
        let deps = vr_list_of(u.attr("dependencies"));
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "{deps:?}");
        for d in &deps {
            let known = by_vr(*d);
            assert!(
                known.causality == Causality::Input || known.initial() == Some(Initial::Exact),
                "{}",
                known.name
            );
        }
        let v = by_vr(u.attr("valueReference").parse().unwrap());
        assert_eq!(deps, initial_dependencies(Model::QuarterCar, v));
    }
    let roots = initial
        .iter()
        .find(|e| {
            e.attr("valueReference")
                == by_name(Model::QuarterCar, FmiVersion::Fmi3, "rightmost_roots")
                    .unwrap()
                    .vr
                    .to_string()
        })
        .unwrap();
    assert!(
        vr_list_of(roots.attr("dependencies")).contains(
            &by_name(Model::QuarterCar, FmiVersion::Fmi3, "root_count")
                .unwrap()
                .vr
        )
    );
}

#[test]
fn documentation_describes_every_variable_and_capability() {
    let html = documentation_html(Model::QuarterCar);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    assert!(html.contains("FMI 3.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains("fmi3InstantiateModelExchange"));
    assert!(html.contains("<td>local, continuous</td>"));
    for (flag, _) in MODEL_EXCHANGE_CAPABILITIES {
        assert!(html.contains(&format!("<td>{flag}</td>")), "{flag}");
    }
    assert!(html.contains(&instantiation_token(Model::QuarterCar)));
    assert!(html.contains("<td>time</td>"));
    for v in FMI3_VARIABLES {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    for e in enumerations(Model::QuarterCar) {
        for item in e.items {
            assert!(
                html.contains(&format!("<td>{}</td>", item.name)),
                "{}",
                item.name
            );
        }
    }
    for (flag, _) in CO_SIMULATION_CAPABILITIES {
        assert!(html.contains(&format!("<td>{flag}</td>")), "{flag}");
    }
    assert!(html.contains("Float64 [root_count][2]"));
    assert!(html.contains("0.3068"));
}

#[test]
fn output_is_deterministic() {
    for model in Model::ALL {
        assert_eq!(model_description_xml(model), model_description_xml(model));
        assert_eq!(documentation_html(model), documentation_html(model));
    }
}

/// The corner's description: Co-Simulation and Model Exchange (its own
/// states, no directional or adjoint derivatives), its own name, token
/// and variables, and a ModelStructure that refers to them.
#[test]
fn the_corner_is_described_with_model_exchange() {
    let model = Model::Corner;
    let els = elements(&model_description_xml(model));
    let root = &els[0];
    assert_eq!(root.attr("fmiVersion"), "3.0");
    assert_eq!(root.attr("modelName"), "TDVASS corner");
    assert_eq!(root.attr("modelName"), model.name());
    assert_eq!(
        root.attr("instantiationToken"),
        instantiation_token(Model::Corner)
    );
    assert_eq!(
        root.attr("instantiationToken"),
        tdvass_fmu::variables::instantiation_token(Model::Corner)
    );
    assert_ne!(
        root.attr("instantiationToken"),
        instantiation_token(Model::QuarterCar)
    );
    assert_eq!(root.attr("description"), crate::markup::CORNER_DESCRIPTION);
    let top: Vec<&str> = children(&els, "fmiModelDescription")
        .iter()
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
    for flag in [
        "providesDirectionalDerivatives",
        "providesAdjointDerivatives",
    ] {
        assert_eq!(me.attr(flag), "true", "{flag}");
    }
    let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
    assert_eq!(cs.attr("modelIdentifier"), "tdvass");
    for (flag, value) in CO_SIMULATION_CAPABILITIES {
        assert_eq!(cs.attr(flag), value, "{flag}");
    }

    let variables = variables_of(model, FmiVersion::Fmi3);
    let vars = children(&els, "ModelVariables");
    assert_eq!(vars.len(), variables.len());
    for (v, el) in variables.iter().zip(&vars) {
        assert_eq!(el.name, fmi3_type(v).as_str(), "{}", v.name);
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("causality"), v.causality.as_str());
    }
    let states = Model::Corner.continuous_states();
    assert_eq!(
        vars.iter()
            .filter(|e| e.get("derivative").is_some())
            .count(),
        states.len()
    );
    assert_eq!(
        vars.iter()
            .filter(|e| e.get("causality") == Some("independent"))
            .count(),
        1
    );
    // Every declared type is defined.
    let declared: HashSet<&str> = children(&els, "TypeDefinitions")
        .iter()
        .map(|t| t.attr("name"))
        .collect();
    for v in &vars {
        if let Some(name) = v.get("declaredType") {
            assert!(declared.contains(name), "{name}");
        }
    }
    assert_eq!(
        enumerations(model)
            .iter()
            .map(|e| e.type_name)
            .collect::<Vec<_>>(),
        ["Variant", "Road", "RoadClass", "TireContact"]
    );

    // ModelStructure: outputs, the derivatives in the order of the
    // states, initial unknowns and the tire's event indicator.
    let structure = children(&els, "ModelStructure");
    let derivatives: Vec<u32> = structure
        .iter()
        .filter(|e| e.name == "ContinuousStateDerivative")
        .map(|e| e.attr("valueReference").parse().unwrap())
        .collect();
    let expected_derivatives: Vec<u32> = states.iter().map(|&i| derivative_vr(model, i)).collect();
    assert_eq!(derivatives, expected_derivatives);
    assert_eq!(
        structure
            .iter()
            .filter(|e| e.name == "EventIndicator")
            .count(),
        1
    );
    let structure: Vec<&Element> = structure
        .into_iter()
        .filter(|e| e.name == "Output" || e.name == "InitialUnknown")
        .collect();
    let vrs: HashSet<u32> = variables.iter().map(|v| v.vr).collect();
    let by_vr = |vr: u32| variables.iter().find(|v| v.vr == vr).unwrap();
    let outputs: Vec<&&Element> = structure.iter().filter(|e| e.name == "Output").collect();
    let expected: Vec<String> = variables
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .map(|v| v.vr.to_string())
        .collect();
    let listed: Vec<&str> = outputs.iter().map(|e| e.attr("valueReference")).collect();
    assert_eq!(listed, expected);
    for unknown in &structure {
        let deps = vr_list_of(unknown.get("dependencies").unwrap_or(""));
        assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
        for d in &deps {
            assert!(vrs.contains(d), "{:?}", unknown.attributes);
        }
        let v = by_vr(unknown.attr("valueReference").parse().unwrap());
        if unknown.name == "Output" {
            // The inputs and the corner's own states.
            for d in &deps {
                let known = by_vr(*d);
                assert!(
                    known.causality == Causality::Input
                        || known.state_index().is_some_and(|i| states.contains(&i)),
                    "{}",
                    v.name
                );
            }
            let kinds: Vec<&str> = unknown
                .get("dependenciesKind")
                .unwrap_or("")
                .split_whitespace()
                .collect();
            let pairs: Vec<(u32, &str)> = deps.iter().copied().zip(kinds).collect();
            assert_eq!(pairs, output_dependencies(model, v));
        } else if v.causality != Causality::Local {
            assert_eq!(deps, initial_dependencies(model, v));
        }
    }
    let vr = |name: &str| vr_of(model, name);
    let body_force = outputs
        .iter()
        .find(|e| e.attr("valueReference") == vr("body_force").to_string())
        .unwrap();
    // The body's coordinates feed through; the wheel's and the
    // absorber's are states.
    assert_eq!(
        vr_list_of(body_force.attr("dependencies")),
        [
            vr("x_h"),
            vr("v_h"),
            vr("x_t"),
            vr("v_t"),
            vr("body_displacement"),
            vr("body_velocity")
        ]
    );
    assert_eq!(
        body_force.attr("dependenciesKind"),
        "dependent dependent dependent dependent fixed fixed"
    );
}

#[test]
fn the_corner_documentation_describes_its_variables_and_enumerations() {
    let html = documentation_html(Model::Corner);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    assert!(html.contains("<title>TDVASS corner FMI 3.0 FMU</title>"));
    assert!(html.contains("TDVASS corner: FMI 3.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains("integrates its 7 continuous states"));
    assert!(html.contains(&instantiation_token(Model::Corner)));
    for v in variables_of(Model::Corner, FmiVersion::Fmi3) {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    for e in enumerations(Model::Corner) {
        for item in e.items {
            assert!(
                html.contains(&format!("<td>{}</td>", item.name)),
                "{}",
                item.name
            );
        }
    }
    assert!(html.contains("fmi3InstantiateModelExchange"));
    assert!(html.contains("body_force (output, N)"));
}

/// Every model's description defines the Float64 types and units its
/// variables use, each once, and no others; the enumerations are those of
/// its variables.
#[test]
fn types_and_units_are_those_the_variables_use() {
    for model in Model::ALL {
        let els = elements(&model_description_xml(model));
        let types: Vec<&str> = children(&els, "TypeDefinitions")
            .iter()
            .filter(|t| t.name == "Float64Type")
            .map(|t| t.attr("name"))
            .collect();
        let units: Vec<&str> = children(&els, "UnitDefinitions")
            .iter()
            .map(|u| u.attr("name"))
            .collect();
        let vars = children(&els, "ModelVariables");
        let declared: Vec<&str> = vars
            .iter()
            .filter(|v| v.name == "Float64")
            .filter_map(|v| v.get("declaredType"))
            .collect();
        let used: Vec<&str> = vars.iter().filter_map(|v| v.get("unit")).collect();
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
        let enumerations_declared = children(&els, "TypeDefinitions")
            .iter()
            .filter(|t| t.name == "EnumerationType")
            .count();
        assert_eq!(enumerations_declared, enumerations(model).len());
    }
    assert!(enumerations(Model::Chassis).is_empty());
}

/// The chassis's description: Co-Simulation and Model Exchange with its
/// own capabilities (no derivatives, no intermediate update), its own name,
/// token and variables (with `time`), and a ModelStructure of outputs and
/// initial unknowns in which the accelerations depend on the forces.
#[test]
fn the_chassis_is_described_with_its_own_capabilities() {
    let model = Model::Chassis;
    let els = elements(&model_description_xml(model));
    let root = &els[0];
    assert_eq!(root.attr("fmiVersion"), "3.0");
    assert_eq!(root.attr("modelName"), "TDVASS chassis");
    assert_eq!(
        root.attr("instantiationToken"),
        instantiation_token(Model::Chassis)
    );
    for other in [Model::QuarterCar, Model::Corner] {
        assert_ne!(root.attr("instantiationToken"), instantiation_token(other));
    }
    assert_eq!(root.attr("description"), crate::markup::CHASSIS_DESCRIPTION);
    let top: Vec<&str> = children(&els, "fmiModelDescription")
        .iter()
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
    assert_eq!(cs.attr("modelIdentifier"), "tdvass");
    assert_eq!(
        cs.attributes.len(),
        1 + CHASSIS_CO_SIMULATION_CAPABILITIES.len()
    );
    for (flag, value) in [
        ("canHandleVariableCommunicationStepSize", "true"),
        ("canGetAndSetFMUState", "true"),
        ("canSerializeFMUState", "true"),
        ("maxOutputDerivativeOrder", "0"),
        ("providesDirectionalDerivatives", "false"),
        ("providesAdjointDerivatives", "false"),
        ("providesIntermediateUpdate", "false"),
        ("mightReturnEarlyFromDoStep", "false"),
        ("canReturnEarlyAfterIntermediateUpdate", "false"),
        ("hasEventMode", "false"),
    ] {
        assert_eq!(cs.attr(flag), value, "{flag}");
    }
    let names = |c: &[(&str, &str)]| c.iter().map(|(n, _)| n.to_string()).collect::<Vec<_>>();
    assert_eq!(
        names(&CHASSIS_CO_SIMULATION_CAPABILITIES),
        names(&CO_SIMULATION_CAPABILITIES)
    );

    let variables = variables_of(model, FmiVersion::Fmi3);
    let vars = children(&els, "ModelVariables");
    assert_eq!(vars.len(), variables.len());
    for (v, el) in variables.iter().zip(&vars) {
        assert_eq!(el.name, fmi3_type(v).as_str(), "{}", v.name);
        assert_eq!(el.attr("name"), v.name);
        assert_eq!(el.attr("valueReference"), v.vr.to_string());
        assert_eq!(el.attr("causality"), v.causality.as_str());
        assert!(el.get("intermediateUpdate").is_none(), "{}", v.name);
    }
    let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
    for (flag, value) in CHASSIS_MODEL_EXCHANGE_CAPABILITIES {
        assert_eq!(me.attr(flag), value, "{flag}");
    }
    assert_eq!(
        vars.iter()
            .filter(|e| e.get("derivative").is_some())
            .count(),
        tdvass::chassis::CHASSIS_STATES
    );
    let time: Vec<&&Element> = vars
        .iter()
        .filter(|e| e.get("causality") == Some("independent"))
        .collect();
    assert_eq!(time.len(), 1);
    assert_eq!(time[0].attr("name"), "time");
    let inertia = vars
        .iter()
        .find(|e| e.attr("name") == "roll_inertia")
        .unwrap();
    assert_eq!(
        (inertia.attr("declaredType"), inertia.attr("unit")),
        ("Inertia", "kg.m2")
    );

    let structure = children(&els, "ModelStructure");
    for e in &structure {
        assert!(
            e.name == "Output"
                || e.name == "InitialUnknown"
                || e.name == "ContinuousStateDerivative",
            "{}",
            e.name
        );
    }
    assert_eq!(
        structure
            .iter()
            .filter(|e| e.name == "ContinuousStateDerivative")
            .count(),
        tdvass::chassis::CHASSIS_STATES
    );
    let vr = |name: &str| vr_of(model, name);
    let forces: Vec<u32> = ["force_fl", "force_fr", "force_rl", "force_rr"]
        .iter()
        .map(|n| vr(n))
        .collect();
    let by_vr = |vr: u32| variables.iter().find(|v| v.vr == vr).unwrap();
    let outputs: Vec<&&Element> = structure.iter().filter(|e| e.name == "Output").collect();
    let expected: Vec<String> = variables
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .map(|v| v.vr.to_string())
        .collect();
    let listed: Vec<&str> = outputs.iter().map(|e| e.attr("valueReference")).collect();
    assert_eq!(listed, expected);
    let feedthrough = [
        "heave_acceleration",
        "pitch_acceleration",
        "roll_acceleration",
        "seat_acceleration",
    ];
    for o in &outputs {
        let v = by_vr(o.attr("valueReference").parse().unwrap());
        let deps = vr_list_of(o.attr("dependencies"));
        if feedthrough.contains(&v.name) {
            assert_eq!(deps, forces, "{}", v.name);
            assert_eq!(o.attr("dependenciesKind"), "fixed fixed fixed fixed");
        } else {
            // From the continuous states alone: no algebraic loop.
            assert!(!deps.is_empty(), "{}", v.name);
            for d in &deps {
                assert!(by_vr(*d).state_index().is_some(), "{}", v.name);
            }
        }
        let pairs: Vec<(u32, &str)> = deps
            .iter()
            .copied()
            .zip(o.get("dependenciesKind").unwrap_or("").split_whitespace())
            .collect();
        assert_eq!(pairs, output_dependencies(model, v));
    }
    let initial: Vec<&&Element> = structure
        .iter()
        .filter(|e| e.name == "InitialUnknown")
        .collect();
    assert_eq!(
        initial.len(),
        outputs.len() + 2 * tdvass::chassis::CHASSIS_STATES - 6
    );
    for u in &initial {
        let v = by_vr(u.attr("valueReference").parse().unwrap());
        if v.causality == Causality::Local {
            assert!(u.get("dependencies").is_none(), "{}", v.name);
            continue;
        }
        assert_eq!(
            vr_list_of(u.attr("dependencies")),
            initial_dependencies(model, v),
            "{}",
            v.name
        );
    }
}

#[test]
fn the_chassis_documentation_describes_its_variables_and_capabilities() {
    let html = documentation_html(Model::Chassis);
    assert!(html.starts_with("<!DOCTYPE html>"));
    elements(html.trim_start_matches("<!DOCTYPE html>"));
    assert!(html.contains("<title>TDVASS chassis FMI 3.0 FMU</title>"));
    assert!(html.contains("TDVASS chassis: FMI 3.0 FMU (Co-Simulation and Model Exchange)"));
    assert!(html.contains("integrates its 19 continuous states"));
    assert!(html.contains(&instantiation_token(Model::Chassis)));
    for v in variables_of(Model::Chassis, FmiVersion::Fmi3) {
        assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
    }
    for (flag, _) in CHASSIS_CO_SIMULATION_CAPABILITIES {
        assert!(html.contains(&format!("<td>{flag}</td>")), "{flag}");
    }
    for text in [
        "positive nose up",
        "positive left side up",
        "z + x theta + y phi",
        "front and rear decouple",
        "no algebraic loop",
        "FMI 3.0 has no input derivatives",
        "no intermediate update",
    ] {
        assert!(html.contains(text), "{text}");
    }
    // No enumerations to list, no input derivatives of FMI 2.0.
    assert!(!html.contains("<h3>Enumerations</h3>"));
    assert!(html.contains("fmi3InstantiateModelExchange"));
    assert!(!html.contains("fmi2SetRealInputDerivatives"));
}

/// The variable of a value reference given as text.
fn by_vr_any(vr: &str) -> &'static Variable {
    let vr: u32 = vr.parse().unwrap();
    FMI3_VARIABLES.iter().find(|v| v.vr == vr).unwrap()
}
