use super::*;
use quick_xml::events::BytesStart;
use quick_xml::name::ResolveResult;
use quick_xml::{NsReader, XmlVersion};
use std::collections::{BTreeMap, BTreeSet};

const CORNER_FMU: &str = "tdvass-corner.fmu";
const CHASSIS_FMU: &str = "tdvass-chassis.fmu";

/// An element as read back: its namespace (resolved), prefix, local
/// name, attributes, children and text.
#[derive(Debug, Default)]
struct Node {
    namespace: String,
    prefix: String,
    name: String,
    attributes: BTreeMap<String, String>,
    children: Vec<Node>,
    text: String,
}

impl Node {
    /// The children of that local name.
    fn children_named<'a>(&'a self, name: &str) -> impl Iterator<Item = &'a Node> {
        let name = name.to_string();
        self.children.iter().filter(move |c| c.name == name)
    }

    /// The one child of that local name.
    fn child(&self, name: &str) -> &Node {
        let found: Vec<&Node> = self.children_named(name).collect();
        assert_eq!(found.len(), 1, "one <{name}> in <{}>", self.name);
        found[0]
    }

    /// An attribute that must be there.
    fn attribute(&self, name: &str) -> &str {
        self.attributes
            .get(name)
            .unwrap_or_else(|| panic!("<{}> has no attribute {name}", self.name))
    }

    /// This element and every element inside it, in document order.
    fn descendants(&self) -> Vec<&Node> {
        let mut all = vec![self];
        for c in &self.children {
            all.extend(c.descendants());
        }
        all
    }
}

/// An element without its content, from its start tag.
fn element(e: &BytesStart, namespace: String) -> Node {
    Node {
        namespace,
        prefix: e
            .name()
            .prefix()
            .map(|p| p.as_ref().to_string())
            .unwrap_or_default(),
        name: e.local_name().as_ref().to_string(),
        attributes: e
            .attributes()
            .map(|a| {
                let a = a.expect("a well-formed attribute");
                let value = a
                    .normalized_value(XmlVersion::Implicit1_0)
                    .expect("a well-formed value");
                (a.key.as_ref().to_string(), value.into_owned())
            })
            .collect(),
        ..Node::default()
    }
}

/// The root element of a document, every element's namespace resolved.
fn parse(xml: &str) -> Node {
    let mut reader = NsReader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut open = vec![Node::default()];
    loop {
        let (resolved, event) = reader.read_resolved_event().expect("well-formed XML");
        let namespace = match resolved {
            ResolveResult::Bound(ns) => ns.as_ref().to_string(),
            ResolveResult::Unbound => String::new(),
            ResolveResult::Unknown(prefix) => panic!("undeclared prefix {prefix}"),
        };
        match event {
            Event::Start(e) => open.push(element(&e, namespace)),
            Event::Empty(e) => {
                let node = element(&e, namespace);
                open.last_mut()
                    .expect("inside the document")
                    .children
                    .push(node);
            }
            Event::End(_) => {
                let node = open.pop().expect("an open element");
                open.last_mut()
                    .expect("inside the document")
                    .children
                    .push(node);
            }
            Event::Text(t) => open
                .last_mut()
                .expect("inside the document")
                .text
                .push_str(&t.xml10_content()),
            Event::Eof => break,
            _ => {}
        }
    }
    let mut document = open.pop().expect("the document");
    assert!(open.is_empty(), "every element is closed");
    assert_eq!(document.children.len(), 1, "one root element");
    document.children.remove(0)
}

/// The twelve connections the car needs, spelled out: (from instance,
/// output, to instance, input).
fn expected_connections() -> BTreeSet<(String, String, String, String)> {
    let mut all = BTreeSet::new();
    for c in ["fl", "fr", "rl", "rr"] {
        let mut add = |a: &str, b: String, c: &str, d: String| {
            all.insert((a.to_string(), b, c.to_string(), d));
        };
        add(c, "body_force".into(), "chassis", format!("force_{c}"));
        add(
            "chassis",
            format!("displacement_{c}"),
            c,
            "body_displacement".into(),
        );
        add(
            "chassis",
            format!("velocity_{c}"),
            c,
            "body_velocity".into(),
        );
    }
    all
}

/// The parameters each corner must get, spelled out: (instance, name)
/// to value, Integer values as whole numbers.
fn expected_parameters() -> BTreeMap<(String, String), f64> {
    let mut all = BTreeMap::new();
    for (corner, seed, delay) in [
        ("fl", 1.0, 0.0),
        ("fr", 2.0, 0.0),
        ("rl", 1.0, 0.13),
        ("rr", 2.0, 0.13),
    ] {
        for (name, value) in [
            ("road", 2.0),
            ("vehicle_speed", 20.0),
            ("road_seed", seed),
            ("road_delay", delay),
            ("input_extrapolation", 1.0),
        ] {
            all.insert((corner.to_string(), name.to_string()), value);
        }
    }
    all.insert(
        ("chassis".to_string(), "input_extrapolation".to_string()),
        1.0,
    );
    all
}

/// Value type (`Real`, `Integer`) and value of one parameter element.
fn typed_value(value: &Node) -> (String, f64) {
    let number: f64 = value.attribute("value").parse().expect("a number");
    (value.name.clone(), number)
}

/// The car's SSD, read back.
fn ssd() -> Node {
    parse(&system_structure_description(CORNER_FMU, CHASSIS_FMU))
}

/// The SSD's components.
fn components(root: &Node) -> Vec<&Node> {
    root.child("System")
        .child("Elements")
        .children_named("Component")
        .collect()
}

/// (instance, name) to (type, value) of every parameter the SSD binds.
fn ssd_parameters(root: &Node) -> BTreeMap<(String, String), (String, f64)> {
    let mut all = BTreeMap::new();
    for component in components(root) {
        for binding in component.children_named("ParameterBindings") {
            for b in binding.children_named("ParameterBinding") {
                let set = b.child("ParameterValues").child("ParameterSet");
                assert_eq!(set.namespace, SSV_NAMESPACE);
                assert_eq!(set.attribute("name"), "full-car", "one set name for ecos");
                for p in set.child("Parameters").children_named("Parameter") {
                    assert_eq!(p.children.len(), 1, "one value per parameter");
                    let key = (
                        component.attribute("name").to_string(),
                        p.attribute("name").to_string(),
                    );
                    let previous = all.insert(key, typed_value(&p.children[0]));
                    assert!(previous.is_none(), "each parameter bound once");
                }
            }
        }
    }
    all
}

/// The car's OSP file, read back.
fn osp(ecco: bool) -> Node {
    parse(&osp_system_structure(CORNER_FMU, CHASSIS_FMU, ecco))
}

/// (simulator, variable) to (type, value) of every initial value.
fn osp_initial_values(root: &Node) -> BTreeMap<(String, String), (String, f64)> {
    let mut all = BTreeMap::new();
    for s in root.child("Simulators").children_named("Simulator") {
        for values in s.children_named("InitialValues") {
            for v in values.children_named("InitialValue") {
                assert_eq!(v.children.len(), 1, "one value per initial value");
                let key = (
                    s.attribute("name").to_string(),
                    v.attribute("variable").to_string(),
                );
                let previous = all.insert(key, typed_value(&v.children[0]));
                assert!(previous.is_none(), "each initial value set once");
            }
        }
    }
    all
}

/// One end of an OSP connection: (simulator, variable, causality).
type OspEnd = (String, String, String);

/// The connections of an OSP file, with the power bond each names.
fn osp_connections(root: &Node) -> Vec<(OspEnd, OspEnd, Option<String>)> {
    let connections = root.child("Connections");
    assert!(
        connections
            .children
            .iter()
            .all(|c| c.name == "VariableConnection"),
        "plain variable connections only"
    );
    connections
        .children
        .iter()
        .map(|c| {
            let ends: Vec<OspEnd> = c
                .children_named("Variable")
                .map(|v| {
                    (
                        v.attribute("simulator").to_string(),
                        v.attribute("name").to_string(),
                        v.attribute("causality").to_string(),
                    )
                })
                .collect();
            assert_eq!(ends.len(), 2, "a connection joins two variables");
            (
                ends[0].clone(),
                ends[1].clone(),
                c.attributes.get("powerBond").cloned(),
            )
        })
        .collect()
}

/// The SSD is an SSP 1.0 description of `full-car` with the five instances and their FMUs.
#[test]
fn the_ssd_is_an_ssp_1_0_description_of_the_five_instances() {
    let root = ssd();
    assert_eq!(root.namespace, SSD_NAMESPACE);
    assert_eq!(root.name, "SystemStructureDescription");
    assert_eq!(root.attribute("version"), "1.0");
    assert_eq!(root.attribute("name"), "full-car");
    assert_eq!(root.child("System").attribute("name"), "full-car");
    let sources: BTreeMap<&str, &str> = components(&root)
        .iter()
        .map(|c| (c.attribute("name"), c.attribute("source")))
        .collect();
    assert_eq!(
        sources,
        BTreeMap::from([
            ("chassis", "resources/tdvass-chassis.fmu"),
            ("fl", "resources/tdvass-corner.fmu"),
            ("fr", "resources/tdvass-corner.fmu"),
            ("rl", "resources/tdvass-corner.fmu"),
            ("rr", "resources/tdvass-corner.fmu"),
        ])
    );
    for c in components(&root) {
        assert_eq!(c.attribute("type"), "application/x-fmu-sharedlibrary");
        assert_eq!(c.attribute("implementation"), "CoSimulation");
    }
}

/// The twelve connections, each from a declared Real output to a declared Real input.
#[test]
fn the_ssd_connects_every_corner_to_the_chassis_through_declared_connectors() {
    let root = ssd();
    let mut connectors = BTreeMap::new();
    for c in components(&root) {
        for connector in c.child("Connectors").children_named("Connector") {
            assert_eq!(connector.children.len(), 1, "a typed connector");
            let key = (
                c.attribute("name").to_string(),
                connector.attribute("name").to_string(),
            );
            let value = (
                connector.attribute("kind").to_string(),
                connector.children[0].name.clone(),
            );
            assert!(connectors.insert(key, value).is_none(), "declared once");
        }
    }
    let connections: Vec<&Node> = root
        .child("System")
        .child("Connections")
        .children_named("Connection")
        .collect();
    let found: BTreeSet<_> = connections
        .iter()
        .map(|c| {
            (
                c.attribute("startElement").to_string(),
                c.attribute("startConnector").to_string(),
                c.attribute("endElement").to_string(),
                c.attribute("endConnector").to_string(),
            )
        })
        .collect();
    assert_eq!(connections.len(), 12);
    assert_eq!(found, expected_connections());
    for (from, output, to, input) in found {
        assert_eq!(
            connectors.get(&(from, output)),
            Some(&("output".to_string(), "Real".to_string()))
        );
        assert_eq!(
            connectors.get(&(to, input)),
            Some(&("input".to_string(), "Real".to_string()))
        );
    }
}

/// Each corner's road: ISO 8608, 20 m/s, seed 2 on the right, 0.13 s delay at the rear, and every instance's input extrapolation, typed as the FMI 2.0 FMU declares them.
#[test]
fn the_ssd_puts_every_corner_on_its_own_iso_8608_road() {
    let root = ssd();
    let bound = ssd_parameters(&root);
    let values: BTreeMap<_, f64> = bound.iter().map(|(k, (_, v))| (k.clone(), *v)).collect();
    assert_eq!(
        values.keys().collect::<Vec<_>>(),
        expected_parameters().keys().collect::<Vec<_>>()
    );
    for (key, expected) in expected_parameters() {
        assert!(
            (values[&key] - expected).abs() < 1e-12,
            "{key:?}: {} where {expected} was expected",
            values[&key]
        );
    }
    for c in components(&root) {
        let instance = c.attribute("name");
        for ((owner, name), (value_type, _)) in &bound {
            if owner != instance {
                continue;
            }
            let expected_type =
                if ["road", "road_seed", "input_extrapolation"].contains(&name.as_str()) {
                    "Integer"
                } else {
                    "Real"
                };
            assert_eq!(value_type, expected_type, "{owner}.{name}");
            let connector = c
                .child("Connectors")
                .children_named("Connector")
                .find(|k| k.attribute("name") == name)
                .unwrap_or_else(|| panic!("{owner}.{name} is declared"));
            assert_eq!(connector.attribute("kind"), "parameter");
            assert_eq!(connector.children[0].name, expected_type);
        }
    }
    let chassis = components(&root)
        .into_iter()
        .find(|c| c.attribute("name") == "chassis")
        .expect("the chassis");
    assert_eq!(chassis.children_named("ParameterBindings").count(), 1);
}

/// The default experiment, libcosim's algorithm annotation, and a unit declaration for every unit named.
#[test]
fn the_ssd_runs_15_s_with_the_fixed_step_libcosim_reads() {
    let root = ssd();
    let experiment = root.child("DefaultExperiment");
    assert_eq!(experiment.attribute("startTime").parse::<f64>(), Ok(0.0));
    assert_eq!(experiment.attribute("stopTime").parse::<f64>(), Ok(15.0));
    let annotation = experiment.child("Annotations").child("Annotation");
    assert_eq!(annotation.namespace, SSC_NAMESPACE);
    assert_eq!(annotation.attribute("type"), "com.opensimulationplatform");
    let algorithm = annotation.child("Algorithm");
    assert_eq!(algorithm.namespace, OSP_ANNOTATIONS_NAMESPACE);
    assert!(algorithm.attributes.is_empty());
    let fixed = algorithm.child("FixedStepAlgorithm");
    assert_eq!(fixed.attribute("baseStepSize").parse::<f64>(), Ok(0.001));
    let declared: BTreeSet<&str> = root
        .child("Units")
        .children_named("Unit")
        .map(|u| u.attribute("name"))
        .collect();
    for node in root.descendants() {
        if let Some(unit) = node.attributes.get("unit") {
            assert!(declared.contains(unit.as_str()), "unit {unit} is declared");
        }
    }
}

/// The standard prefixes on every element and namespace declarations on the root only, as libcosim and ecos read them.
#[test]
fn the_ssd_writes_the_prefixes_libcosim_looks_elements_up_by() {
    let root = ssd();
    let prefixes = BTreeMap::from([
        (SSD_NAMESPACE, "ssd"),
        (SSC_NAMESPACE, "ssc"),
        (SSV_NAMESPACE, "ssv"),
        (OSP_ANNOTATIONS_NAMESPACE, "osp"),
    ]);
    for node in root.descendants() {
        assert_eq!(
            prefixes.get(node.namespace.as_str()),
            Some(&node.prefix.as_str()),
            "<{}:{}> in {}",
            node.prefix,
            node.name,
            node.namespace
        );
        if !std::ptr::eq(node, &root) {
            assert!(
                node.attributes.keys().all(|k| !k.starts_with("xmlns")),
                "namespaces are declared on the root only"
            );
        }
    }
}

/// The fixed-step OSP file: schema order, the five simulators, the SSD's values and its twelve connections.
#[test]
fn the_fixed_step_osp_file_holds_the_car_of_the_ssd() {
    let root = osp(false);
    assert_eq!(root.namespace, OSP_SYSTEM_STRUCTURE_NAMESPACE);
    assert_eq!(root.name, "OspSystemStructure");
    assert_eq!(root.attribute("version"), "0.1");
    let order: Vec<&str> = root.children.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        order,
        [
            "StartTime",
            "EndTime",
            "BaseStepSize",
            "Algorithm",
            "Simulators",
            "Connections"
        ]
    );
    assert_eq!(root.child("StartTime").text.parse::<f64>(), Ok(0.0));
    assert_eq!(root.child("EndTime").text.parse::<f64>(), Ok(15.0));
    assert_eq!(root.child("BaseStepSize").text.parse::<f64>(), Ok(0.001));
    assert_eq!(root.child("Algorithm").text, "fixedStep");
    let sources: BTreeMap<&str, &str> = root
        .child("Simulators")
        .children_named("Simulator")
        .map(|s| (s.attribute("name"), s.attribute("source")))
        .collect();
    assert_eq!(
        sources,
        BTreeMap::from([
            ("chassis", "../tdvass-chassis.fmu"),
            ("fl", "../tdvass-corner.fmu"),
            ("fr", "../tdvass-corner.fmu"),
            ("rl", "../tdvass-corner.fmu"),
            ("rr", "../tdvass-corner.fmu"),
        ])
    );
    assert_eq!(osp_initial_values(&root), ssd_parameters(&ssd()));
    let connections = osp_connections(&root);
    assert_eq!(connections.len(), 12);
    let found: BTreeSet<_> = connections
        .iter()
        .map(|(from, to, bond)| {
            assert_eq!((from.2.as_str(), to.2.as_str()), ("output", "input"));
            assert_eq!(bond, &None, "no power bonds at a fixed step");
            (from.0.clone(), from.1.clone(), to.0.clone(), to.1.clone())
        })
        .collect();
    assert_eq!(found, expected_connections());
}

/// The ECCO OSP file: one power bond per corner whose sides libcosim pairs as corner and chassis, and a complete ECCO configuration.
#[test]
fn the_ecco_osp_file_bonds_force_and_velocity_of_every_corner() {
    let root = osp(true);
    let order: Vec<&str> = root.children.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        order,
        [
            "StartTime",
            "EndTime",
            "BaseStepSize",
            "Algorithm",
            "Simulators",
            "Connections",
            "EccoConfiguration"
        ]
    );
    assert_eq!(root.child("Algorithm").text, "ecco");
    assert_eq!(osp_initial_values(&root), ssd_parameters(&ssd()));
    let connections = osp_connections(&root);
    let found: BTreeSet<_> = connections
        .iter()
        .map(|(from, to, _)| (from.0.clone(), from.1.clone(), to.0.clone(), to.1.clone()))
        .collect();
    assert_eq!(found, expected_connections());

    let mut bonds: BTreeMap<&str, Vec<(&OspEnd, &OspEnd)>> = BTreeMap::new();
    for (a, b, bond) in &connections {
        match bond {
            Some(name) => bonds.entry(name.as_str()).or_default().push((a, b)),
            None => assert!(
                b.1 == "body_displacement",
                "only displacements are unbonded"
            ),
        }
    }
    assert_eq!(bonds.len(), 4, "one bond per corner");
    for (name, pair) in bonds {
        assert_eq!(pair.len(), 2, "{name} joins two connections");
        // libcosim's pairing: the input end of the first connection and
        // the output end of the second are one side of the bond, and
        // the other two ends the other side.
        let end = |(a, b): (&OspEnd, &OspEnd), causality: &str| -> OspEnd {
            let end = if a.2 == causality { a } else { b };
            assert_eq!(end.2, causality);
            end.clone()
        };
        let side_a = [end(pair[0], "input"), end(pair[1], "output")];
        let side_b = [end(pair[1], "input"), end(pair[0], "output")];
        let mut sides: Vec<(String, BTreeSet<String>)> = [side_a, side_b]
            .iter()
            .map(|side| {
                assert_eq!(side[0].0, side[1].0, "{name}: one simulator per side");
                (
                    side[0].0.clone(),
                    side.iter().map(|e| e.1.clone()).collect::<BTreeSet<_>>(),
                )
            })
            .collect();
        sides.sort();
        let corner = sides[1].0.clone();
        assert_eq!(
            sides,
            vec![
                (
                    "chassis".to_string(),
                    BTreeSet::from([format!("force_{corner}"), format!("velocity_{corner}")])
                ),
                (
                    corner.clone(),
                    BTreeSet::from(["body_force".to_string(), "body_velocity".to_string()])
                ),
            ]
        );
    }

    let settings: BTreeMap<&str, f64> = root
        .child("EccoConfiguration")
        .children
        .iter()
        .map(|s| (s.name.as_str(), s.text.parse().expect("a number")))
        .collect();
    let names: BTreeSet<&str> = settings.keys().copied().collect();
    assert_eq!(
        names,
        BTreeSet::from([
            "SafetyFactor",
            "StepSize",
            "MinimumStepSize",
            "MaximumStepSize",
            "MinimumChangeRate",
            "MaximumChangeRate",
            "ProportionalGain",
            "IntegralGain",
            "RelativeTolerance",
            "AbsoluteTolerance",
        ])
    );
    assert!(settings.values().all(|v| *v > 0.0));
    assert!(settings["SafetyFactor"] < 1.0);
    assert!(settings["MinimumStepSize"] <= settings["StepSize"]);
    assert!(settings["StepSize"] <= settings["MaximumStepSize"]);
    assert!(settings["MinimumChangeRate"] < 1.0 && settings["MaximumChangeRate"] > 1.0);
}
