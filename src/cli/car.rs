//! `tdvass car`: the monolithic full car (`tdvass::car`), the chassis on
//! four corners in one delay equation, with its JSON report.

use super::args::{CarArgs, io_error, parse_variant};
use serde_json::{Value, json};
use std::io::Write as _;
use std::sync::Arc;
use tdvass::car::{CORNERS, CarConfig, CarReport, CarSample, run_car_with};
use tdvass::chassis::Corner;
use tdvass::error::{Error, Result};
use tdvass::road::{RandomRoad, RoadSpec};

/// The car of the command line's arguments: the right track's road from
/// its own seed (`--right-seed`, default `--road-seed` + 1).
fn config(a: &CarArgs) -> Result<CarConfig> {
    let road = a.run.road_spec()?;
    let right_seed = a.right_seed.unwrap_or(a.run.road_seed.wrapping_add(1));
    let right_road = match &road {
        RoadSpec::Iso8608(random) => RoadSpec::Iso8608(RandomRoad {
            seed: right_seed,
            ..*random
        }),
        RoadSpec::PaperCompatible {
            road: random,
            sample_interval,
        } => RoadSpec::PaperCompatible {
            road: RandomRoad {
                seed: right_seed,
                ..*random
            },
            sample_interval: *sample_interval,
        },
        other => other.clone(),
    };
    let sim = a.run.config(a.model.params(), parse_variant(&a.variant)?)?;
    Ok(CarConfig {
        params: sim.params,
        variant: sim.variant,
        chassis: a.chassis.params(),
        road,
        right_road,
        right_phase: a.right_phase,
        corner_roads: corner_roads(&a.corner_road)?,
        vehicle_speed: a.run.vehicle_speed,
        tire_contact: sim.tire_contact,
        tolerance: sim.tolerance,
        max_internal_step: sim.max_internal_step,
    })
}

/// The corners' own roads of `--corner-road CORNER=file:PATH` (a corner
/// not named: flat), or none.
fn corner_roads(given: &[String]) -> Result<Option<[RoadSpec; CORNERS]>> {
    if given.is_empty() {
        return Ok(None);
    }
    let flat = RoadSpec::Samples(Arc::new(vec![(0.0, 0.0)]));
    let mut roads: [Option<RoadSpec>; CORNERS] = Default::default();
    for argument in given {
        let unknown = || Error::UnknownName {
            what: "corner road",
            given: argument.clone(),
            expected: "CORNER=file:PATH with CORNER one of fl, fr, rl, rr, each named once",
        };
        let (name, road) = argument.split_once('=').ok_or_else(unknown)?;
        let corner = Corner::ALL
            .into_iter()
            .find(|c| c.name() == name.trim())
            .ok_or_else(unknown)?;
        let path = road.trim().strip_prefix("file:").ok_or_else(unknown)?;
        let slot = &mut roads[corner as usize];
        if slot.is_some() {
            return Err(unknown());
        }
        *slot = Some(RoadSpec::from_csv_file(path)?);
    }
    Ok(Some(roads.map(|road| road.unwrap_or_else(|| flat.clone()))))
}

/// The roads in words: `--road`'s tracks, or the corners' own roads.
fn road_note(a: &CarArgs) -> String {
    if a.corner_road.is_empty() {
        a.run.road_note()
    } else {
        format!(
            "each wheel on a road of its own ({}; a corner not named: flat)",
            a.corner_road.join(", ")
        )
    }
}

/// Runs `tdvass car`.
pub(super) fn car_command(a: CarArgs) -> Result<String> {
    let config = config(&a)?;
    let choice = config.choose_step()?;
    let duration = a.run.duration;
    let report = match &a.output {
        Some(path) => write_history(&config, &choice, duration, a.output_interval, path)?,
        None => run_car_with(&config, &choice, duration, 0, &mut |_| {})?,
    };
    if a.json {
        return Ok(car_json(&a, &config, &report)?.to_string());
    }
    let mut out = format!(
        "full car, {} on every corner, {}, {} tire, {} s from rest (internal step {} s)\n  RMS heave acceleration      {:.4} m/s^2\n  RMS pitch acceleration      {:.4} rad/s^2\n  RMS roll acceleration       {:.4} rad/s^2\n  ISO 2631-1 a_w at the seat  {:.4} m/s^2\n  seat vibration dose value   {:.4} m/s^1.75\n  corner  RMS SDD (mm)  RMS TDD (mm)  tire load ratio  lift-offs\n",
        config.variant.label(),
        road_note(&a),
        config.tire_contact.name(),
        duration,
        report.internal_step,
        report.rms_heave_acceleration,
        report.rms_pitch_acceleration,
        report.rms_roll_acceleration,
        report.rms_weighted_seat_acceleration,
        report.seat_vibration_dose_value,
    );
    for (corner, c) in Corner::ALL.iter().zip(&report.corners) {
        out += &format!(
            "  {:<6}  {:>12.4}  {:>12.4}  {:>15.4}  {:>9}\n",
            corner.name(),
            c.rms_suspension_deflection * 1e3,
            c.rms_tire_deflection * 1e3,
            c.rms_dynamic_tire_load_ratio,
            c.lift_off_count
        );
    }
    Ok(out)
}

/// The JSON of a run: the chassis's RMS outputs, `corners`, and every
/// parameter the run used.
fn car_json(a: &CarArgs, config: &CarConfig, report: &CarReport) -> Result<Value> {
    let mut corners = serde_json::Map::new();
    for (corner, c) in Corner::ALL.iter().zip(&report.corners) {
        corners.insert(
            corner.name().into(),
            json!({
                "rms_suspension_deflection": c.rms_suspension_deflection,
                "rms_tire_deflection": c.rms_tire_deflection,
                "rms_dynamic_tire_load_ratio": c.rms_dynamic_tire_load_ratio,
                "lift_off_count": c.lift_off_count,
                "contact_loss_time": c.contact_loss_time,
                "max_suspension_deflection": c.max_suspension_deflection,
                "static_load": c.static_load,
            }),
        );
    }
    let mut value = json!({
        "variant": config.variant.name(),
        "road_note": road_note(a),
        "rms_heave_acceleration": report.rms_heave_acceleration,
        "rms_pitch_acceleration": report.rms_pitch_acceleration,
        "rms_roll_acceleration": report.rms_roll_acceleration,
        "rms_weighted_seat_acceleration": report.rms_weighted_seat_acceleration,
        "seat_vibration_dose_value": report.seat_vibration_dose_value,
        "corners": corners,
    });
    for (name, parameter) in config.params.named_values() {
        if name != "m_s" {
            value[name] = parameter.into();
        }
    }
    let p = &config.chassis;
    for (name, parameter) in [
        ("mass", p.mass),
        ("a", p.a),
        ("b", p.b),
        ("track_front", p.track_front),
        ("track_rear", p.track_rear),
        ("pitch_inertia", p.pitch_inertia),
        ("roll_inertia", p.roll_inertia),
        ("seat_x", p.seat_x),
        ("seat_y", p.seat_y),
    ] {
        value[name] = parameter.into();
    }
    a.run.record(&mut value)?;
    if let RoadSpec::Iso8608(right) | RoadSpec::PaperCompatible { road: right, .. } =
        &config.right_road
    {
        value["right_seed"] = right.seed.into();
    }
    value["right_phase"] = config.right_phase.into();
    value["rear_road_delay"] = config.road_shift(Corner::RearLeft).delay.into();
    if !a.corner_road.is_empty() {
        value["corner_roads"] = a.corner_road.clone().into();
    }
    value["internal_step"] = report.internal_step.into();
    Ok(value)
}

/// Runs the car writing a CSV row every `interval` (whole internal steps).
fn write_history(
    config: &CarConfig,
    choice: &tdvass::solver::StepChoice,
    duration: f64,
    interval: f64,
    path: &str,
) -> Result<CarReport> {
    if !(interval.is_finite() && interval > 0.0) {
        return Err(Error::InvalidParameter {
            name: "output_interval",
            value: interval,
            reason: "must be finite and > 0",
        });
    }
    let file = std::fs::File::create(path).map_err(|e| io_error("creating", path, &e))?;
    let mut csv = std::io::BufWriter::new(file);
    let step = tdvass::solver::DelayGrid::new(
        if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        },
        choice.step_bound,
    )?
    .step;
    let every = (interval / step).round().max(1.0) as u64;
    let mut failure = None;
    let header = "time,heave,pitch,roll,seat_acceleration,suspension_deflection_fl,suspension_deflection_fr,suspension_deflection_rl,suspension_deflection_rr";
    writeln!(csv, "{header}").map_err(|e| io_error("writing", path, &e))?;
    let mut row = |s: CarSample| {
        let [z, pitch, roll] = s.position;
        let [fl, fr, rl, rr] = s.suspension_deflection;
        if let Err(e) = writeln!(
            csv,
            "{},{z},{pitch},{roll},{},{fl},{fr},{rl},{rr}",
            s.time, s.seat_acceleration
        ) {
            failure.get_or_insert(e);
        }
    };
    let report = run_car_with(config, choice, duration, every, &mut row)?;
    if let Some(e) = failure {
        return Err(io_error("writing", path, &e));
    }
    csv.flush().map_err(|e| io_error("writing", path, &e))?;
    Ok(report)
}
