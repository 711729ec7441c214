//! The assembled car: the chassis FMU carrying four corner FMUs, written as
//! the two system-structure files co-simulation masters read.
//!
//! - `SystemStructure.ssd` (SSP 1.0, the Modelica Association's System
//!   Structure and Parameterization): the system `full-car` as it sits in
//!   `full-car.ssp`, next to the FMUs under `resources/`. Any SSP tool
//!   (libcosim, ecos, OMSimulator, ...) imports it.
//! - `OspSystemStructure.xml` (the Open Simulation Platform's own format,
//!   read by libcosim and its Python and command line front ends): the same
//!   car, with a fixed step or with libcosim's energy-conserving step
//!   control (ECCO), which SSP 1.0 cannot express.
//!
//! Five instances: `chassis`, and the corners `fl`, `fr`, `rl`, `rr`
//! (front/rear, left/right). Each corner feeds the force it puts on the body
//! to the chassis, and the chassis feeds back the displacement and velocity
//! of that corner's attachment point: twelve connections. Every corner rolls
//! on the ISO 8608 random road of the quarter car at the default vehicle
//! speed; the rear wheels see their front wheel's road a wheelbase later,
//! `(a + b) / speed` with the chassis's default `a` and `b`, and the right
//! track rolls on a road of its own (the next seed), so that the car pitches
//! and rolls. Every value comes from the library's own defaults, so the
//! files follow the model when a default changes.
//!
//! The functions return the files' text; writing them and packing the SSP
//! archive is the caller's. (A long file on purpose: the two formats'
//! writers, element by element in document order, read best as one.)

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesText, Event};
use std::io::{self, Cursor};
use tdvass::chassis::{ChassisParams, Corner};
use tdvass::road::{RandomRoad, RoadType};
use tdvass_fmu::{DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME};

/// The name of the system, of its SSD and of its folder beside the FMUs.
pub const SYSTEM_NAME: &str = "full-car";
/// The chassis's instance name.
pub const CHASSIS_INSTANCE: &str = "chassis";
/// The name every corner's parameter set carries in the SSD. libcosim
/// applies every binding it finds; ecos gathers the sets of all components
/// by name and applies the one its `init` names, so one name for all four
/// lets `init(parameter_set="full-car")` set up the whole car.
pub const PARAMETER_SET_NAME: &str = "full-car";
/// The folder of an SSP archive that holds the FMUs its SSD names.
pub const SSP_RESOURCES: &str = "resources";

/// SSP 1.0 System Structure Description namespace (prefix `ssd`).
pub const SSD_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
/// SSP 1.0 common types namespace: connector types, units, annotations
/// (prefix `ssc`).
pub const SSC_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
/// SSP 1.0 parameter values namespace (prefix `ssv`).
pub const SSV_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";
/// The Open Simulation Platform's SSP annotations (prefix `osp`): libcosim
/// takes its co-simulation algorithm and base step from them.
pub const OSP_ANNOTATIONS_NAMESPACE: &str = "http://opensimulationplatform.com/SSP/OSPAnnotations";
/// The type that marks an SSP annotation as the Open Simulation Platform's.
pub const OSP_ANNOTATION_TYPE: &str = "com.opensimulationplatform";
/// libcosim's `OspSystemStructure.xml` namespace.
pub const OSP_SYSTEM_STRUCTURE_NAMESPACE: &str =
    "http://opensimulationplatform.com/MSMI/OSPSystemStructure";
/// The version of the OSP system-structure format libcosim requires.
pub const OSP_SYSTEM_STRUCTURE_VERSION: &str = "0.1";

/// The step-size control of libcosim's ECCO algorithm (energy-conservation
/// based co-simulation): after each step it measures, for every power bond,
/// the difference between the power one side delivers (force times
/// velocity) and the power the other side receives, and steers the next
/// step with a PI controller so that the energy lost or created per step
/// stays within the tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EccoSettings {
    /// Factor (< 1) on the step the controller proposes.
    pub safety_factor: f64,
    /// First step (s).
    pub step_size: f64,
    /// Smallest step (s).
    pub minimum_step_size: f64,
    /// Largest step (s).
    pub maximum_step_size: f64,
    /// Least ratio of one step to the one before.
    pub minimum_change_rate: f64,
    /// Greatest ratio of one step to the one before.
    pub maximum_change_rate: f64,
    /// Proportional gain of the controller.
    pub proportional_gain: f64,
    /// Integral gain of the controller.
    pub integral_gain: f64,
    /// Relative tolerance of a step's energy residual, against the largest
    /// residual of the bonds.
    pub relative_tolerance: f64,
    /// Absolute tolerance of a step's energy residual (J).
    pub absolute_tolerance: f64,
}

/// The car's ECCO settings: the FMUs' own default step to start with,
/// between 0.1 ms and 10 ms, the controller gains of libcosim's own ECCO
/// examples, and tolerances of 1e-6. With the examples' 1e-4, the energy
/// residual of the corners a step under one wheel barely moves stays below
/// the tolerance while their RMS deflections come out 6 % off (the
/// `sedan-step` scenario of tests/interop/full_car.py); 1e-6 takes that to
/// 0.5 % and every other scenario within 0.12 %, at 1.2 to 3.2 s of wall
/// time for 2 s of the car instead of 0.3 to 2.4 s.
pub const ECCO_SETTINGS: EccoSettings = EccoSettings {
    safety_factor: 0.8,
    step_size: DEFAULT_STEP_SIZE,
    minimum_step_size: 1e-4,
    maximum_step_size: 1e-2,
    minimum_change_rate: 0.2,
    maximum_change_rate: 1.5,
    proportional_gain: 0.2,
    integral_gain: 0.15,
    relative_tolerance: 1e-6,
    absolute_tolerance: 1e-6,
};

/// The value a parameter is set to, in the type of its FMU variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParameterValue {
    /// A Real (FMI 2.0) / Float64 (FMI 3.0) variable.
    Real(f64),
    /// An Integer variable (`road` and `road_seed` in the FMI 2.0 FMU).
    Integer(i64),
}

/// A parameter set on one instance: name, value and unit (Real values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParameterSetting {
    /// The FMU variable.
    pub name: &'static str,
    /// Its value.
    pub value: ParameterValue,
    /// The unit of a Real value, as the FMU declares it.
    pub unit: Option<&'static str>,
}

/// One connection: an output of one instance drives an input of another.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    /// The instance whose output it is.
    pub from_instance: &'static str,
    /// The output.
    pub from_variable: String,
    /// The instance whose input it drives.
    pub to_instance: &'static str,
    /// The input.
    pub to_variable: String,
    /// The power bond the connection is half of, if any: the corner's force
    /// and velocity exchange with the chassis carry the power that flows
    /// through the suspension into the body.
    pub power_bond: Option<String>,
}

/// The direction of a connector, seen from its instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Input,
    Output,
    Parameter,
}

impl Kind {
    /// The SSD's `kind`, and libcosim's `causality` of a connection's end.
    fn name(self) -> &'static str {
        match self {
            Kind::Input => "input",
            Kind::Output => "output",
            Kind::Parameter => "parameter",
        }
    }
}

/// A connector an instance offers in the SSD.
#[derive(Debug, Clone, PartialEq)]
struct Connector {
    name: String,
    kind: Kind,
    /// `Some(unit)` for a Real connector, `None` for an Integer one.
    real_unit: Option<&'static str>,
}

/// The units the connectors use, as SI base-unit exponents (kg, m, s).
const UNITS: [(&str, [i32; 3]); 4] = [
    ("N", [1, 1, -2]),
    ("m", [0, 1, 0]),
    ("m/s", [0, 1, -1]),
    ("s", [0, 0, 1]),
];

/// A rear corner, whose road is its front wheel's, a wheelbase later.
fn is_rear(corner: Corner) -> bool {
    matches!(corner, Corner::RearLeft | Corner::RearRight)
}

/// A corner of the right track, which rolls on a road of its own.
fn is_right(corner: Corner) -> bool {
    matches!(corner, Corner::FrontRight | Corner::RearRight)
}

/// The chassis output that carries a corner's attachment displacement.
fn displacement_name(corner: Corner) -> String {
    format!("displacement_{}", corner.name())
}

/// The chassis output that carries a corner's attachment velocity.
fn velocity_name(corner: Corner) -> String {
    format!("velocity_{}", corner.name())
}

/// The name of a corner's power bond with the chassis.
fn power_bond_name(corner: Corner) -> String {
    format!("suspension_{}", corner.name())
}

/// The parameters each corner is given: the ISO 8608 road (`road`), at the
/// default vehicle speed (`vehicle_speed`, on which both the road's
/// spectrum and the rear wheels' delay depend), its seed (`road_seed`: the
/// default on the left track, the next seed on the right) and its delay
/// (`road_delay`: 0 at the front, wheelbase / speed at the rear), and
/// [`extrapolation`]. The static load is left at the corner's default, a
/// quarter of the default chassis mass with the centre of gravity midway
/// between the axles.
pub fn corner_parameters(corner: Corner) -> Vec<ParameterSetting> {
    let road = RandomRoad::default();
    let chassis = ChassisParams::default();
    let seed = road.seed + u64::from(is_right(corner));
    let delay = if is_rear(corner) {
        (chassis.a + chassis.b) / road.speed
    } else {
        0.0
    };
    vec![
        ParameterSetting {
            name: "road",
            value: ParameterValue::Integer(RoadType::Iso8608.code()),
            unit: None,
        },
        ParameterSetting {
            name: "vehicle_speed",
            value: ParameterValue::Real(road.speed),
            unit: Some("m/s"),
        },
        ParameterSetting {
            name: "road_seed",
            value: ParameterValue::Integer(
                i64::try_from(seed).expect("the default seed is a small number"),
            ),
            unit: None,
        },
        ParameterSetting {
            name: "road_delay",
            value: ParameterValue::Real(delay),
            unit: Some("s"),
        },
        extrapolation(),
    ]
}

/// `input_extrapolation = 1`, set on the chassis and on every corner: each
/// continues its bond's inputs (the forces; the body's attachment) over a
/// communication step from their last two values instead of holding them,
/// which makes the Jacobi coupling second order in the step
/// (docs/full-car.md).
pub fn extrapolation() -> ParameterSetting {
    ParameterSetting {
        name: "input_extrapolation",
        value: ParameterValue::Integer(1),
        unit: None,
    }
}

/// The parameters the chassis is given: [`extrapolation`] (its other
/// defaults are the paper's car).
pub fn chassis_parameters() -> Vec<ParameterSetting> {
    vec![extrapolation()]
}

/// The twelve connections of the car, corner by corner: the corner's
/// `body_force` drives the chassis's `force_<corner>`, and the chassis's
/// `displacement_<corner>` and `velocity_<corner>` drive the corner's
/// `body_displacement` and `body_velocity`. The force and the velocity
/// connection of a corner form its power bond.
pub fn connections() -> Vec<Connection> {
    Corner::ALL
        .iter()
        .flat_map(|&corner| {
            let instance = corner.name();
            let bond = power_bond_name(corner);
            [
                Connection {
                    from_instance: instance,
                    from_variable: "body_force".to_string(),
                    to_instance: CHASSIS_INSTANCE,
                    to_variable: corner.force_name().to_string(),
                    power_bond: Some(bond.clone()),
                },
                Connection {
                    from_instance: CHASSIS_INSTANCE,
                    from_variable: displacement_name(corner),
                    to_instance: instance,
                    to_variable: "body_displacement".to_string(),
                    power_bond: None,
                },
                Connection {
                    from_instance: CHASSIS_INSTANCE,
                    from_variable: velocity_name(corner),
                    to_instance: instance,
                    to_variable: "body_velocity".to_string(),
                    power_bond: Some(bond),
                },
            ]
        })
        .collect()
}

/// The chassis's connectors: per corner, the force input and the
/// displacement and velocity outputs; then the parameters it is given.
fn chassis_connectors() -> Vec<Connector> {
    let parameters = parameter_connectors(chassis_parameters());
    Corner::ALL
        .iter()
        .flat_map(|&corner| {
            [
                Connector {
                    name: corner.force_name().to_string(),
                    kind: Kind::Input,
                    real_unit: Some("N"),
                },
                Connector {
                    name: displacement_name(corner),
                    kind: Kind::Output,
                    real_unit: Some("m"),
                },
                Connector {
                    name: velocity_name(corner),
                    kind: Kind::Output,
                    real_unit: Some("m/s"),
                },
            ]
        })
        .chain(parameters)
        .collect()
}

/// The connectors of the parameters `parameters` (a Real's with its unit).
fn parameter_connectors(parameters: Vec<ParameterSetting>) -> impl Iterator<Item = Connector> {
    parameters.into_iter().map(|p| Connector {
        name: p.name.to_string(),
        kind: Kind::Parameter,
        real_unit: match p.value {
            ParameterValue::Real(_) => p.unit,
            ParameterValue::Integer(_) => None,
        },
    })
}

/// A corner's connectors: the force output, the body inputs and the
/// parameters it is given.
fn corner_connectors(corner: Corner) -> Vec<Connector> {
    let signals = [
        ("body_force", Kind::Output, "N"),
        ("body_displacement", Kind::Input, "m"),
        ("body_velocity", Kind::Input, "m/s"),
    ]
    .map(|(name, kind, unit)| Connector {
        name: name.to_string(),
        kind,
        real_unit: Some(unit),
    });
    signals
        .into_iter()
        .chain(parameter_connectors(corner_parameters(corner)))
        .collect()
}

/// A number as XML Schema's `xs:double` reads it back: Rust's shortest
/// representation that round-trips.
fn number(x: f64) -> String {
    format!("{x}")
}

/// A parameter's value as text.
fn value_text(value: ParameterValue) -> String {
    match value {
        ParameterValue::Real(x) => number(x),
        ParameterValue::Integer(n) => n.to_string(),
    }
}

/// A writer into memory, indenting by two spaces.
type XmlWriter = Writer<Cursor<Vec<u8>>>;

/// An XML document: the declaration, then what `write` writes, and a final
/// newline.
fn document(write: impl FnOnce(&mut XmlWriter) -> io::Result<()>) -> String {
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .and_then(|()| write(&mut w))
        .expect("writing to memory cannot fail");
    let mut text = String::from_utf8(w.into_inner().into_inner()).expect("quick-xml writes UTF-8");
    text.push('\n');
    text
}

/// `<name>text</name>`.
fn text_element(w: &mut XmlWriter, name: &str, text: &str) -> io::Result<()> {
    w.create_element(name)
        .write_text_content(BytesText::new(text))?;
    Ok(())
}

/// Every instance with the FMU it instantiates: the chassis first, then the
/// corners.
fn instances<'a>(corner_fmu: &'a str, chassis_fmu: &'a str) -> Vec<(&'static str, &'a str)> {
    std::iter::once((CHASSIS_INSTANCE, chassis_fmu))
        .chain(Corner::ALL.iter().map(|c| (c.name(), corner_fmu)))
        .collect()
}

/// The parameters set on an instance.
fn parameters_of(instance: &str) -> Vec<ParameterSetting> {
    Corner::ALL
        .iter()
        .find(|c| c.name() == instance)
        .map_or_else(chassis_parameters, |&c| corner_parameters(c))
}

/// `SystemStructure.ssd`, the SSP 1.0 description of the car for
/// `full-car.ssp`, whose `resources/` folder holds `corner_fmu` and
/// `chassis_fmu` (file names, such as `tdvass-corner.fmu`): the five
/// components with the connectors they use, the twelve connections, each
/// instance's parameters as an inline parameter set (the corners' roads,
/// and [`extrapolation`] on all five; every set named
/// [`PARAMETER_SET_NAME`]), the units, and the
/// default experiment (0 s to 15 s) with libcosim's fixed-step algorithm at
/// the FMUs' 1 ms step as an OSP annotation.
///
/// Namespaces: `ssd` (the description), `ssc` (connector types, units,
/// annotations), `ssv` (the parameter sets) from SSP 1.0, and `osp` for the
/// Open Simulation Platform's annotation. The prefixes are the ones the SSP
/// standard uses throughout, and they are load-bearing: libcosim's SSP
/// parser looks elements up by their prefixed names. Every namespace is
/// declared on the root, because libcosim reads an element's attributes as
/// one of its children, and an algorithm element with an attribute would
/// read as an unknown algorithm.
///
/// The components are Co-Simulation FMUs (`implementation="CoSimulation"`):
/// their own integration of the delay equation is exact, where a Model
/// Exchange import would be as accurate as the master's solver. `road` and
/// `road_seed` are Integer connectors, as the FMI 2.0 FMU declares them
/// (libcosim imports FMI 1.0 and 2.0 FMUs only).
pub fn system_structure_description(corner_fmu: &str, chassis_fmu: &str) -> String {
    document(|w| {
        w.create_element("ssd:SystemStructureDescription")
            .with_attribute(("xmlns:ssd", SSD_NAMESPACE))
            .with_attribute(("xmlns:ssc", SSC_NAMESPACE))
            .with_attribute(("xmlns:ssv", SSV_NAMESPACE))
            .with_attribute(("xmlns:osp", OSP_ANNOTATIONS_NAMESPACE))
            .with_attribute(("version", "1.0"))
            .with_attribute(("name", SYSTEM_NAME))
            .write_inner_content(|w| {
                write_ssd_system(w, corner_fmu, chassis_fmu)?;
                write_ssd_units(w)?;
                write_ssd_default_experiment(w)
            })?;
        Ok(())
    })
}

/// `ssd:System`: the components and the connections.
fn write_ssd_system(w: &mut XmlWriter, corner_fmu: &str, chassis_fmu: &str) -> io::Result<()> {
    w.create_element("ssd:System")
        .with_attribute(("name", SYSTEM_NAME))
        .with_attribute((
            "description",
            "A rigid chassis on four suspension corners, each on the ISO 8608 random road; the rear wheels follow the front ones a wheelbase later, the right track rolls on a road of its own",
        ))
        .write_inner_content(|w| {
            w.create_element("ssd:Elements").write_inner_content(|w| {
                for (instance, fmu) in instances(corner_fmu, chassis_fmu) {
                    write_ssd_component(w, instance, fmu)?;
                }
                Ok(())
            })?;
            w.create_element("ssd:Connections")
                .write_inner_content(|w| {
                    for c in connections() {
                        w.create_element("ssd:Connection")
                            .with_attribute(("startElement", c.from_instance))
                            .with_attribute(("startConnector", c.from_variable.as_str()))
                            .with_attribute(("endElement", c.to_instance))
                            .with_attribute(("endConnector", c.to_variable.as_str()))
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// One `ssd:Component`: its connectors and, for a corner, its parameter
/// binding.
fn write_ssd_component(w: &mut XmlWriter, instance: &str, fmu: &str) -> io::Result<()> {
    let connectors = match Corner::ALL.iter().find(|c| c.name() == instance) {
        Some(&corner) => corner_connectors(corner),
        None => chassis_connectors(),
    };
    let parameters = parameters_of(instance);
    let source = format!("{SSP_RESOURCES}/{fmu}");
    w.create_element("ssd:Component")
        .with_attribute(("name", instance))
        .with_attribute(("type", "application/x-fmu-sharedlibrary"))
        .with_attribute(("source", source.as_str()))
        .with_attribute(("implementation", "CoSimulation"))
        .write_inner_content(|w| {
            w.create_element("ssd:Connectors")
                .write_inner_content(|w| {
                    for c in &connectors {
                        let connector = w
                            .create_element("ssd:Connector")
                            .with_attribute(("name", c.name.as_str()))
                            .with_attribute(("kind", c.kind.name()));
                        connector.write_inner_content(|w| {
                            match c.real_unit {
                                Some(unit) => w
                                    .create_element("ssc:Real")
                                    .with_attribute(("unit", unit))
                                    .write_empty()?,
                                None => w.create_element("ssc:Integer").write_empty()?,
                            };
                            Ok(())
                        })?;
                    }
                    Ok(())
                })?;
            if !parameters.is_empty() {
                write_ssd_parameter_binding(w, &parameters)?;
            }
            Ok(())
        })?;
    Ok(())
}

/// `ssd:ParameterBindings` with one binding whose values are inline: an
/// `ssv:ParameterSet` named [`PARAMETER_SET_NAME`].
fn write_ssd_parameter_binding(
    w: &mut XmlWriter,
    parameters: &[ParameterSetting],
) -> io::Result<()> {
    w.create_element("ssd:ParameterBindings")
        .write_inner_content(|w| {
            w.create_element("ssd:ParameterBinding")
                .write_inner_content(|w| {
                    w.create_element("ssd:ParameterValues")
                        .write_inner_content(|w| {
                            w.create_element("ssv:ParameterSet")
                                .with_attribute(("version", "1.0"))
                                .with_attribute(("name", PARAMETER_SET_NAME))
                                .write_inner_content(|w| {
                                    w.create_element("ssv:Parameters").write_inner_content(
                                        |w| {
                                            for p in parameters {
                                                write_ssv_parameter(w, p)?;
                                            }
                                            Ok(())
                                        },
                                    )?;
                                    Ok(())
                                })?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// One `ssv:Parameter`.
fn write_ssv_parameter(w: &mut XmlWriter, p: &ParameterSetting) -> io::Result<()> {
    let value = value_text(p.value);
    w.create_element("ssv:Parameter")
        .with_attribute(("name", p.name))
        .write_inner_content(|w| {
            match (p.value, p.unit) {
                (ParameterValue::Real(_), Some(unit)) => w
                    .create_element("ssv:Real")
                    .with_attribute(("value", value.as_str()))
                    .with_attribute(("unit", unit))
                    .write_empty()?,
                (ParameterValue::Real(_), None) => w
                    .create_element("ssv:Real")
                    .with_attribute(("value", value.as_str()))
                    .write_empty()?,
                (ParameterValue::Integer(_), _) => w
                    .create_element("ssv:Integer")
                    .with_attribute(("value", value.as_str()))
                    .write_empty()?,
            };
            Ok(())
        })?;
    Ok(())
}

/// `ssd:Units`: the units the connectors and parameters name.
fn write_ssd_units(w: &mut XmlWriter) -> io::Result<()> {
    w.create_element("ssd:Units").write_inner_content(|w| {
        for (name, [kg, m, s]) in UNITS {
            w.create_element("ssc:Unit")
                .with_attribute(("name", name))
                .write_inner_content(|w| {
                    let (kg, m, s) = (kg.to_string(), m.to_string(), s.to_string());
                    w.create_element("ssc:BaseUnit")
                        .with_attribute(("kg", kg.as_str()))
                        .with_attribute(("m", m.as_str()))
                        .with_attribute(("s", s.as_str()))
                        .write_empty()?;
                    Ok(())
                })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `ssd:DefaultExperiment`, with libcosim's algorithm as an OSP annotation.
fn write_ssd_default_experiment(w: &mut XmlWriter) -> io::Result<()> {
    let (start, stop, step) = (
        number(DEFAULT_START_TIME),
        number(DEFAULT_STOP_TIME),
        number(DEFAULT_STEP_SIZE),
    );
    w.create_element("ssd:DefaultExperiment")
        .with_attribute(("startTime", start.as_str()))
        .with_attribute(("stopTime", stop.as_str()))
        .write_inner_content(|w| {
            w.create_element("ssd:Annotations")
                .write_inner_content(|w| {
                    w.create_element("ssc:Annotation")
                        .with_attribute(("type", OSP_ANNOTATION_TYPE))
                        .write_inner_content(|w| {
                            w.create_element("osp:Algorithm").write_inner_content(|w| {
                                w.create_element("osp:FixedStepAlgorithm")
                                    .with_attribute(("baseStepSize", step.as_str()))
                                    .write_empty()?;
                                Ok(())
                            })?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// `OspSystemStructure.xml`, libcosim's description of the car, for the
/// folder `full-car/` beside the FMUs (`corner_fmu` and `chassis_fmu` are
/// their file names; the simulators' sources are `../<fmu>`): start and
/// stop time of the default experiment, the five simulators with the same
/// parameter values as the SSD, and the twelve connections.
///
/// With `ecco == false` the algorithm is libcosim's fixed step at the FMUs'
/// 1 ms. With `ecco == true` it is ECCO ([`ECCO_SETTINGS`], which libcosim
/// requires in full): each corner's force and velocity connections carry
/// the name of the corner's power bond, and each of their ends its
/// causality (the FMU variable's own), from which libcosim pairs the
/// variables of each side of the bond; the displacement connections stay
/// plain. `BaseStepSize` is written in both, for tools that read it.
///
/// One namespace, `http://opensimulationplatform.com/MSMI/OSPSystemStructure`,
/// as the default namespace: libcosim's schema (`OspSystemStructure.xsd`,
/// version 0.1) qualifies every element.
pub fn osp_system_structure(corner_fmu: &str, chassis_fmu: &str, ecco: bool) -> String {
    let algorithm = if ecco { "ecco" } else { "fixedStep" };
    document(|w| {
        w.create_element("OspSystemStructure")
            .with_attribute(("xmlns", OSP_SYSTEM_STRUCTURE_NAMESPACE))
            .with_attribute(("version", OSP_SYSTEM_STRUCTURE_VERSION))
            .write_inner_content(|w| {
                text_element(w, "StartTime", &number(DEFAULT_START_TIME))?;
                text_element(w, "EndTime", &number(DEFAULT_STOP_TIME))?;
                text_element(w, "BaseStepSize", &number(DEFAULT_STEP_SIZE))?;
                text_element(w, "Algorithm", algorithm)?;
                w.create_element("Simulators").write_inner_content(|w| {
                    for (instance, fmu) in instances(corner_fmu, chassis_fmu) {
                        write_osp_simulator(w, instance, fmu)?;
                    }
                    Ok(())
                })?;
                w.create_element("Connections").write_inner_content(|w| {
                    for c in connections() {
                        write_osp_connection(w, &c, ecco)?;
                    }
                    Ok(())
                })?;
                if ecco {
                    write_ecco_configuration(w, &ECCO_SETTINGS)?;
                }
                Ok(())
            })?;
        Ok(())
    })
}

/// One `Simulator` with its initial values.
fn write_osp_simulator(w: &mut XmlWriter, instance: &str, fmu: &str) -> io::Result<()> {
    let source = format!("../{fmu}");
    let parameters = parameters_of(instance);
    let simulator = w
        .create_element("Simulator")
        .with_attribute(("name", instance))
        .with_attribute(("source", source.as_str()));
    if parameters.is_empty() {
        simulator.write_empty()?;
        return Ok(());
    }
    simulator.write_inner_content(|w| {
        w.create_element("InitialValues").write_inner_content(|w| {
            for p in &parameters {
                let value = value_text(p.value);
                let type_name = match p.value {
                    ParameterValue::Real(_) => "Real",
                    ParameterValue::Integer(_) => "Integer",
                };
                w.create_element("InitialValue")
                    .with_attribute(("variable", p.name))
                    .write_inner_content(|w| {
                        w.create_element(type_name)
                            .with_attribute(("value", value.as_str()))
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
        Ok(())
    })?;
    Ok(())
}

/// One `VariableConnection`, output end first; in the ECCO file a
/// connection of a power bond names it.
fn write_osp_connection(w: &mut XmlWriter, c: &Connection, ecco: bool) -> io::Result<()> {
    let mut connection = w.create_element("VariableConnection");
    if let (true, Some(bond)) = (ecco, &c.power_bond) {
        connection = connection.with_attribute(("powerBond", bond.as_str()));
    }
    connection.write_inner_content(|w| {
        for (instance, variable, kind) in [
            (c.from_instance, &c.from_variable, Kind::Output),
            (c.to_instance, &c.to_variable, Kind::Input),
        ] {
            w.create_element("Variable")
                .with_attribute(("simulator", instance))
                .with_attribute(("name", variable.as_str()))
                .with_attribute(("causality", kind.name()))
                .write_empty()?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `EccoConfiguration`: every setting libcosim reads.
fn write_ecco_configuration(w: &mut XmlWriter, s: &EccoSettings) -> io::Result<()> {
    let settings = [
        ("SafetyFactor", s.safety_factor),
        ("StepSize", s.step_size),
        ("MinimumStepSize", s.minimum_step_size),
        ("MaximumStepSize", s.maximum_step_size),
        ("MinimumChangeRate", s.minimum_change_rate),
        ("MaximumChangeRate", s.maximum_change_rate),
        ("ProportionalGain", s.proportional_gain),
        ("IntegralGain", s.integral_gain),
        ("RelativeTolerance", s.relative_tolerance),
        ("AbsoluteTolerance", s.absolute_tolerance),
    ];
    w.create_element("EccoConfiguration")
        .write_inner_content(|w| {
            for (name, value) in settings {
                text_element(w, name, &number(value))?;
            }
            Ok(())
        })?;
    Ok(())
}

#[cfg(test)]
mod tests;
