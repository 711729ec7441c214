//! The documentation page of the corner ([`Model::Corner`]), shorter than
//! the quarter car's: what the corner is (its body inputs, the force on
//! the body, its static load and road), its diagram, its variables, the
//! default experiment and its Co-Simulation capabilities. The FMI 2.0 and
//! FMI 3.0 pages differ only in what [`CornerPage`] holds.

use crate::markup::{
    CORNER_DESCRIPTION, REFERENCE_RESULTS, XmlResult, XmlWriter, diagram, html_page, list,
    paragraph, table, text_element, variable_table,
};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, MODEL_IDENTIFIER, Model,
};

/// What the corner's page of one FMI version says in its own words.
pub(crate) struct CornerPage<'a> {
    /// `FMI 2.0` or `FMI 3.0`.
    pub(crate) version: &'a str,
    /// How the model description identifies the interface, with what it
    /// hashes: `GUID {...} (a hash of ...)`.
    pub(crate) identity: String,
    /// The header of the type column of the variable table.
    pub(crate) type_header: &'a str,
    /// The rows of the variable table, one per variable.
    pub(crate) rows: Vec<Vec<String>>,
    /// What follows the variable table (FMI 3.0: the enumerations).
    pub(crate) after_variables: &'a dyn Fn(&mut XmlWriter) -> XmlResult,
    /// The attributes of the `CoSimulation` element after `modelIdentifier`.
    pub(crate) co_simulation: &'a [(&'a str, &'a str)],
    /// The standard, for the references.
    pub(crate) specification: &'a str,
}

/// The complete `documentation/index.html` of the corner's FMU.
pub(crate) fn corner_page(page: &CornerPage<'_>) -> String {
    let model = Model::Corner;
    html_page(&format!("{} {} FMU", model.name(), page.version), |w| {
        write_body(w, page)
    })
}

fn write_body(w: &mut XmlWriter, page: &CornerPage<'_>) -> XmlResult {
    let name = Model::Corner.name();
    text_element(
        w,
        "h1",
        &format!("{name}: {} FMU (Co-Simulation)", page.version),
    )?;
    paragraph(w, CORNER_DESCRIPTION)?;
    paragraph(
        w,
        &format!(
            "modelIdentifier {MODEL_IDENTIFIER}, {}, version {}. The shared library is the quarter car's, byte for byte (the quarter car's {} FMU of the same build carries it too): the token of this model description picks the corner when the FMU is instantiated.",
            page.identity,
            env!("CARGO_PKG_VERSION"),
            page.version
        ),
    )?;

    text_element(w, "h2", "The model")?;
    diagram(w, Model::Corner)?;
    paragraph(
        w,
        "The quarter car's suspension and wheel without its body: the annular absorber (m_h) on the wheel through k_h, c_h, the wheel (m_t) on the road through the tire k_t, the control force u = g x_t(t - tau) between absorber and wheel (TDVASS; PVASS is g = 0; CS has no absorber, and x_h, v_h mirror x_t, v_t), and the suspension spring and damper k_s, c_s up to the body's attachment point. The body is not part of the FMU: another FMU (a chassis) or the master moves it.",
    )?;
    list(
        w,
        &[
            "Inputs body_displacement and body_velocity: the attachment point's displacement from the static equilibrium and its velocity, positive up. They are held over a communication step: from the body_displacement set for the step, the attachment moves at body_velocity until the end of the step (their input derivatives are not used). At their start values (0) the body is fixed at its static equilibrium, and the corner is the suspension under a fixed body.",
            "Output body_force: the force of k_s and c_s on the body at the attachment point, positive up and zero at the static equilibrium (the body's weight is not in it). It depends directly on body_displacement and body_velocity (direct feedthrough; ModelStructure lists both). The suspension deflection is SDD = body_displacement - x_t; the other outputs are the quarter car's, with the attachment point in place of the body.",
            "static_load: this corner's share W_c of the body's weight (default 345 kg g0, the paper's body). The tire's static load W = static_load + (m_h + m_t) g0 (CS: static_load + m_t g0) sets where the unilateral tire (tire_contact = 1) lifts off, and divides the dynamic tire load in rms_dynamic_tire_load_ratio.",
            "Road: road = 0 takes the input x_g (positive up, as the master sets it); road = 1 (the default) is the harmonic road x_g = road_amplitude sin(road_angular_frequency (t - road_delay) + road_phase); road = 2 and 3 are the quarter car's random roads. road_delay (s) is how much later this wheel sees the profile (a rear wheel: wheelbase / speed; must be 0 with road = 0); road_phase (rad) shifts the harmonic road (a right track out of phase with the left excites roll).",
        ],
    )?;

    text_element(w, "h2", "Variables")?;
    variable_table(w, page.type_header, &page.rows)?;
    paragraph(
        w,
        "Parameters are fixed (settable before the end of initialization) unless tunable. Values outside the range, NaN or infinite are refused with an error naming the variable and value.",
    )?;
    (page.after_variables)(w)?;

    text_element(w, "h2", "Default experiment")?;
    paragraph(
        w,
        &format!(
            "startTime {DEFAULT_START_TIME} s, stopTime {DEFAULT_STOP_TIME} s, stepSize {DEFAULT_STEP_SIZE} s. With the start values (TDVASS, g = 5386 N/m, tau = 0.2 ms, harmonic road 0.05 sin 5t, from rest, body_displacement = body_velocity = 0) the corner is the suspension under a body fixed at its static equilibrium, and body_force the dynamic force the suspension puts on that body."
        ),
    )?;
    paragraph(w, REFERENCE_RESULTS)?;

    text_element(w, "h2", "Co-Simulation")?;
    paragraph(
        w,
        &format!(
            "Co-Simulation only in this version: the corner offers no Model Exchange (its model description has no ModelExchange element, and instantiating it for Model Exchange fails); the quarter car's {} FMU offers both.",
            page.version
        ),
    )?;
    let rows: Vec<Vec<String>> = page
        .co_simulation
        .iter()
        .map(|(name, value)| vec![name.to_string(), value.to_string()])
        .collect();
    table(w, &["attribute", "value"], &rows)?;

    text_element(w, "h2", "References")?;
    list(
        w,
        &[
            "Mechanism of time-delay feedback control of suspension damping with an annular vibration-absorbing structure (the source paper: model Eq. 1-2, Table 1 parameters).",
            page.specification,
        ],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::markup::{CORNER_LEGEND, DIAGRAM_LEGEND, legend};
    use tdvass_fmu::Model;
    use tdvass_fmu::variables::{FmiVersion, by_name};

    #[test]
    fn the_corner_legend_replaces_the_body_and_the_road_with_its_own_variables() {
        assert_eq!(legend(Model::QuarterCar), DIAGRAM_LEGEND);
        let corner = legend(Model::Corner);
        assert_eq!(corner.len(), DIAGRAM_LEGEND.len());
        for own in CORNER_LEGEND {
            assert!(corner.contains(own), "{}", own.0);
            assert!(DIAGRAM_LEGEND.iter().any(|row| row.0 == own.0), "{}", own.0);
        }
        for model in Model::ALL {
            for (symbol, _, names) in legend(model) {
                for name in names {
                    assert!(
                        by_name(model, FmiVersion::Fmi2, name).is_some(),
                        "{model:?}: {symbol} names {name}"
                    );
                }
            }
        }
    }
}
