//! Serialized FMU states: a versioned, position-independent byte format.
//!
//! ```text
//! offset  size  content
//! 0       8     magic "TDVASSFS"
//! 8       4     format version (u32 LE), currently 7 (6 is read too)
//! 12      4     GUID length n (u32 LE)
//! 16      n     GUID of the FMU that wrote the state (ASCII)
//! 16+n    8     payload length (u64 LE)
//! 24+n    4     CRC-32 (IEEE) of the payload (u32 LE)
//! 28+n    ...   payload
//! ```
//!
//! The payload is the FMU-level state ([`SlaveState`]): the phase, every
//! setting (by value reference, so the layout follows the variable table),
//! input slope and its origin, the last two input values (for
//! `input_extrapolation`), the hold-warning and contact-loss flags, start
//! and stop time, the tolerance, last successful time, the terminate flag,
//! the Model Exchange model if any ([`ModelExchange::to_bytes`], after a
//! flag and its length; the flag 2 for the chassis in Model Exchange,
//! whose motion follows as in Co-Simulation), then
//! [`Simulator::to_bytes`] (time, solver state, the delay history, the
//! road generator, the RMS accumulators, the configuration) or, for the
//! chassis, its force rates and [`Chassis::write_motion`].
//! All numbers are little-endian; floats are stored as their bit patterns,
//! so a restored state continues bit-identically.
//!
//! Reading checks the header field by field, the CRC (which detects every
//! single-bit error), the admissible range of every setting and the
//! consistency of the settings with the simulator: truncated, corrupted or
//! foreign bytes give an error, never a panic.
//!
//! The file is over 700 lines because the format's tests stand beside it
//! (the code is about 520 lines): round trips that must continue to the
//! bit, a broken envelope, every single-bit flip, bad content under a good
//! checksum.

use crate::defaults::Model;
use crate::error::FmiError;
use crate::phase::Phase;
use crate::settings::Settings;
use crate::state::{BondHistory, Engine, SlaveState};
use crate::variables::{Access, FmiVersion, by_vr, variables_of};
use tdvass::bytes::{ByteReader, ByteWriter};
use tdvass::chassis::Chassis;
use tdvass::exchange::ModelExchange;
use tdvass::solver::{SimulationConfig, Simulator};

/// First bytes of every serialized state.
pub const MAGIC: &[u8; 8] = b"TDVASSFS";
/// Format version written. Version 2 added the
/// time integral of the RMS outputs and the input extrapolation state,
/// version 3 the FMI 3.0 settings (`intermediate_update_interval`,
/// `root_count`) and the simulator's own versioned bytes with the
/// comfort, road-holding and working-space accumulators; older states are
/// refused; version 4 the experiment's tolerance (after the stop time) and
/// the simulator's step bound; version 5 the setting `tire_contact` and the
/// simulator's contact mode; version 6 the Model Exchange model (its own
/// versioned bytes: time, states, contact mode, delay history), before the
/// simulator; version 7 the history of the body inputs and forces for
/// `input_extrapolation`, after the terminate flag (a version 6 state
/// reads as one without it: [`OLDEST_READ`]). Both FMI versions write the
/// same format; the header's token (the FMI 2.0 GUID or the FMI 3.0
/// instantiation token) keeps a state of one from being read by the other.
pub const FORMAT_VERSION: u32 = 7;
/// The oldest format version read.
pub const OLDEST_READ: u32 = 6;
/// The code of the Model Exchange model's presence that says the chassis
/// runs in Model Exchange (its motion follows where the co-simulation's
/// does; 0: no Model Exchange model, 1: the suspension's follows).
const CHASSIS_EXCHANGE: u8 = 2;
/// Longest GUID accepted in a header.
const MAX_GUID_LEN: usize = 64;
/// Most internal steps between the start and a restored state (2^52: node
/// indices stay exact in f64).
const MAX_STEPS: f64 = 4_503_599_627_370_496.0;

const fn crc32_table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
}

const CRC32_TABLE: [u32; 256] = crc32_table();

/// CRC-32 (IEEE 802.3, as in zip and PNG).
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, &b| {
        CRC32_TABLE[((c ^ b as u32) & 0xff) as usize] ^ (c >> 8)
    })
}

fn invalid(message: impl std::fmt::Display) -> FmiError {
    FmiError::error(format!("invalid serialized FMU state: {message}"))
}

/// The library's [`ByteReader`] with each read named in its error.
struct Reader<'a>(ByteReader<'a>);

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Reader(ByteReader::new(bytes))
    }
    fn named<T>(
        &mut self,
        what: &str,
        read: impl FnOnce(&mut ByteReader<'a>) -> tdvass::Result<T>,
    ) -> Result<T, FmiError> {
        let at = self.0.offset();
        read(&mut self.0).map_err(|e| match e {
            tdvass::Error::InvalidState(reason) => {
                invalid(format_args!("reading {what} at byte {at}: {reason}"))
            }
            other => invalid(other),
        })
    }
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], FmiError> {
        self.named(what, |r| r.take(n))
    }
    fn u8(&mut self, what: &str) -> Result<u8, FmiError> {
        self.named(what, ByteReader::u8)
    }
    fn flag(&mut self, what: &str) -> Result<bool, FmiError> {
        match self.u8(what)? {
            0 => Ok(false),
            1 => Ok(true),
            other => Err(invalid(format_args!("{what} flag is {other}, not 0 or 1"))),
        }
    }
    fn u32(&mut self, what: &str) -> Result<u32, FmiError> {
        self.named(what, ByteReader::u32)
    }
    fn u64(&mut self, what: &str) -> Result<u64, FmiError> {
        self.named(what, ByteReader::u64)
    }
    fn f64(&mut self, what: &str) -> Result<f64, FmiError> {
        self.named(what, ByteReader::f64)
    }
    fn finite(&mut self, what: &str) -> Result<f64, FmiError> {
        let v = self.f64(what)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(invalid(format_args!("{what} = {v} is not finite")))
        }
    }
    /// A value at a time, if any ([`write_timed`]): its flag, its time,
    /// the value; `what` names it in an error.
    fn timed(&mut self, what: &str) -> Result<Option<(f64, f64)>, FmiError> {
        let defined = self.flag(&format!("{what} defined"))?;
        let time = self.finite(&format!("{what}'s time"))?;
        let value = self.finite(what)?;
        Ok(defined.then_some((time, value)))
    }
    fn rest(&mut self) -> &'a [u8] {
        self.0.rest()
    }
}

/// A value at a time, if any: a flag, the time, the value (zeros when
/// there is none); [`Reader::timed`] reads it.
fn write_timed(w: &mut ByteWriter, value: Option<(f64, f64)>) {
    w.u8(value.is_some() as u8);
    let (time, value) = value.unwrap_or((0.0, 0.0));
    w.f64(time);
    w.f64(value);
}

fn encode_payload(model: &SlaveState) -> Vec<u8> {
    let mut w = ByteWriter::default();
    w.u8(model.phase.code());
    let settings: Vec<_> = variables_of(model.settings.model, FmiVersion::Fmi3)
        .iter()
        .filter_map(|v| match v.access {
            Access::Real { get, .. } => Some((v.vr, get(&model.settings).to_bits())),
            Access::Integer { get, .. } => Some((v.vr, get(&model.settings) as i64 as u64)),
            _ => None,
        })
        .collect();
    w.u32(settings.len() as u32);
    for (vr, bits) in settings {
        w.u32(vr);
        w.u64(bits);
    }
    w.f64(model.input_slope);
    w.u8(model.input_pending as u8);
    w.u8(model.input_slope_given as u8);
    write_timed(&mut w, model.previous_input);
    write_timed(&mut w, model.earlier_input);
    w.u8(model.hold_warned as u8);
    w.u8(model.contact_warned as u8);
    w.f64(model.start_time);
    w.u8(model.stop_time.is_some() as u8);
    w.f64(model.stop_time.unwrap_or(0.0));
    w.f64(model.settings.tolerance);
    w.f64(model.last_successful_time);
    w.u8(model.terminate_requested as u8);
    encode_bond_history(&mut w, &model.bonds);
    match (model.engine.exchange(), &model.engine) {
        (Some(exchange), _) => {
            let bytes = exchange.to_bytes();
            w.u8(1);
            w.u64(bytes.len() as u64);
            w.raw(&bytes);
        }
        // The chassis in Model Exchange: its motion follows as the
        // co-simulation's does.
        (None, Engine::ChassisExchange(Some(_))) => w.u8(CHASSIS_EXCHANGE),
        (None, _) => w.u8(0),
    }
    match (model.engine.simulator(), model.engine.chassis()) {
        (Some(sim), _) => {
            let bytes = sim.to_bytes();
            w.u8(1);
            w.u64(bytes.len() as u64);
            w.raw(&bytes);
        }
        (None, Some(chassis)) => {
            let mut motion = ByteWriter::default();
            model
                .settings
                .force_rates
                .iter()
                .for_each(|&rate| motion.f64(rate));
            chassis.write_motion(&mut motion);
            w.u8(1);
            w.u64(motion.bytes.len() as u64);
            w.raw(&motion.bytes);
        }
        (None, None) => w.u8(0),
    }
    w.bytes
}

/// The history of the body inputs and forces (version 7 on), for
/// `input_extrapolation`: the last body velocity set and its time, the
/// attachment's acceleration and whether new body inputs wait; each
/// force's last value and time; the forces that wait (a bit each).
fn encode_bond_history(w: &mut ByteWriter, bonds: &BondHistory) {
    for value in std::iter::once(bonds.previous_body).chain(bonds.previous_forces) {
        write_timed(w, value);
    }
    w.f64(bonds.body_acceleration);
    w.u8(bonds.body_pending as u8);
    w.u8(bonds.forces_pending);
}

/// The bond history [`encode_bond_history`] wrote, from `r`.
fn decode_bond_history(r: &mut Reader) -> Result<BondHistory, FmiError> {
    let mut values = [None; 5];
    for value in values.iter_mut() {
        *value = r.timed("a bond value")?;
    }
    let body_acceleration = r.finite("the body attachment's acceleration")?;
    let body_pending = r.flag("body inputs pending")?;
    let forces_pending = r.u8("the forces pending")?;
    if forces_pending > 0b1111 {
        return Err(invalid(format_args!("forces pending {forces_pending:#b}")));
    }
    Ok(BondHistory {
        previous_body: values[0],
        body_pending,
        body_acceleration,
        previous_forces: [values[1], values[2], values[3], values[4]],
        forces_pending,
    })
}

/// The chassis's engine from `bytes` (the force rates, then its motion;
/// [`encode_payload`]), its rates written into `settings`.
fn decode_chassis(bytes: &[u8], settings: &mut Settings) -> Result<Chassis, FmiError> {
    let mut r = ByteReader::new(bytes);
    let mut rates = [0.0; 4];
    for rate in rates.iter_mut() {
        *rate = r.f64().map_err(invalid)?;
        if !rate.is_finite() {
            return Err(invalid(format_args!("a force rate {rate}")));
        }
    }
    settings.force_rates = rates;
    let chassis = Chassis::read_motion(settings.chassis, &mut r).map_err(invalid)?;
    if !r.is_empty() {
        return Err(invalid("trailing bytes after the chassis"));
    }
    if let Some((name, value)) = crate::guards::non_finite_chassis_output(&chassis) {
        return Err(invalid(format_args!("output `{name}` = {value}")));
    }
    Ok(chassis)
}

/// The settings by value reference. A state of an older `version` may
/// lack settings added since (the chassis's `input_extrapolation` in
/// version 7): they keep their start values.
fn decode_settings(r: &mut Reader, model: Model, version: u32) -> Result<Settings, FmiError> {
    let mut settings = Settings::start_values(model);
    let expected: Vec<_> = variables_of(model, FmiVersion::Fmi3)
        .iter()
        .filter(|v| matches!(v.access, Access::Real { .. } | Access::Integer { .. }))
        .collect();
    let count = r.u32("the number of settings")? as usize;
    if count > expected.len() || (version == FORMAT_VERSION && count != expected.len()) {
        return Err(invalid(format_args!(
            "{count} settings where {} were expected",
            expected.len()
        )));
    }
    let mut seen = vec![false; expected.len()];
    for _ in 0..count {
        let vr = r.u32("a value reference")?;
        let bits = r.u64("a setting")?;
        let position = expected.iter().position(|v| v.vr == vr);
        let (Some(i), Some(var)) = (position, by_vr(model, FmiVersion::Fmi3, vr)) else {
            return Err(invalid(format_args!(
                "unknown setting value reference {vr}"
            )));
        };
        if std::mem::replace(&mut seen[i], true) {
            return Err(invalid(format_args!(
                "setting `{}` appears twice",
                var.name
            )));
        }
        match var.access {
            Access::Real { set, .. } => {
                let value = f64::from_bits(bits);
                var.range
                    .check(var.name, value)
                    .and_then(|()| crate::guards::check_variable(var, value))
                    .map_err(|e| invalid(e.message))?;
                set(&mut settings, value);
            }
            Access::Integer { set, .. } => {
                let value = i32::try_from(bits as i64).map_err(|_| {
                    invalid(format_args!(
                        "`{}` = {} is not a 32-bit integer",
                        var.name, bits as i64
                    ))
                })?;
                var.range
                    .check(var.name, value as f64)
                    .map_err(|e| invalid(e.message))?;
                set(&mut settings, value);
            }
            _ => unreachable!("only settings are listed"),
        }
    }
    Ok(settings)
}

/// Whether a saved simulator's configuration is the one `settings` give:
/// the same, or the same but for more metrics (a corner saved while it
/// still weighed a comfort it has no body for continues with it; see
/// [`Settings::metrics`]).
fn saved_config_matches(saved: &SimulationConfig, settings: &SimulationConfig) -> bool {
    saved.metrics >= settings.metrics
        && *saved
            == (SimulationConfig {
                metrics: saved.metrics,
                ..settings.clone()
            })
}

fn decode_payload(bytes: &[u8], model: Model, version: u32) -> Result<SlaveState, FmiError> {
    let mut r = Reader::new(bytes);
    let code = r.u8("the phase")?;
    let phase = Phase::from_code(code)
        .filter(|s| *s != Phase::Fatal)
        .ok_or_else(|| invalid(format_args!("phase code {code}")))?;
    let mut settings = decode_settings(&mut r, model, version)?;
    let input_slope = r.finite("the input slope")?;
    let input_pending = r.flag("input pending")?;
    let input_slope_given = r.flag("input slope given")?;
    let previous_input = r.timed("an input value")?;
    let earlier_input = r.timed("an input value")?;
    let hold_warned = r.flag("hold warning logged")?;
    let contact_warned = r.flag("contact loss logged")?;
    let start_time = r.finite("the start time")?;
    let stop_defined = r.flag("stop time defined")?;
    let stop = r.f64("the stop time")?;
    let stop_time = if stop_defined {
        if !(stop.is_finite() && stop >= start_time) {
            return Err(invalid(format_args!(
                "stop time {stop} before the start time {start_time}"
            )));
        }
        Some(stop)
    } else {
        None
    };
    let tolerance = r.f64("the tolerance")?;
    tdvass::solver::accuracy::check_tolerance(tolerance).map_err(invalid)?;
    settings.tolerance = tolerance;
    let last_successful_time = r.finite("the last successful time")?;
    let terminate_requested = r.flag("terminate requested")?;
    let bonds = if version >= 7 {
        decode_bond_history(&mut r)?
    } else {
        BondHistory::default()
    };
    let exchange_code = r.u8("the Model Exchange model's presence")?;
    if exchange_code > CHASSIS_EXCHANGE
        || (exchange_code == CHASSIS_EXCHANGE && model != Model::Chassis)
        || (exchange_code == 1 && model == Model::Chassis)
    {
        return Err(invalid(format_args!("Model Exchange code {exchange_code}")));
    }
    let chassis_exchange = exchange_code == CHASSIS_EXCHANGE;
    let exchange = if exchange_code == 1 {
        let len = r.u64("the Model Exchange model length")?;
        let len = usize::try_from(len)
            .map_err(|_| invalid(format_args!("a Model Exchange model of {len} bytes")))?;
        let bytes = r.take(len, "the Model Exchange model")?;
        crate::guards::check_rates(&settings).map_err(|e| invalid(e.message))?;
        let config = settings.to_config(start_time).map_err(invalid)?;
        let mut model = ModelExchange::new(config).map_err(invalid)?;
        if settings.road_is_input() {
            model.set_road_input(settings.x_g).map_err(invalid)?;
        }
        model.restore(bytes).map_err(invalid)?;
        Some(model)
    } else {
        None
    };
    let mut chassis = None;
    let mut sim = if r.flag("simulator present")? {
        let len = r.u64("the simulator length")?;
        let bytes = r.rest();
        if len != bytes.len() as u64 {
            return Err(invalid(format_args!(
                "simulator of {len} bytes where {} remain",
                bytes.len()
            )));
        }
        if model == Model::Chassis {
            chassis = Some(decode_chassis(bytes, &mut settings)?);
            None
        } else {
            Some(Simulator::from_bytes(bytes).map_err(invalid)?)
        }
    } else {
        None
    };
    if !r.rest().is_empty() {
        return Err(invalid("trailing bytes"));
    }
    let model_exchange_phase = matches!(phase, Phase::EventMode | Phase::ContinuousTimeMode);
    if exchange.is_some() && sim.is_some() {
        return Err(invalid("both a simulator and a Model Exchange model"));
    }
    let stepping_phase = matches!(phase, Phase::StepComplete | Phase::StepFailed);
    let stepper = sim.is_some() || chassis.is_some();
    if chassis_exchange && chassis.is_none() {
        return Err(invalid("a chassis in Model Exchange without its motion"));
    }
    if phase.is_simulating() != (stepper || exchange.is_some())
        || (model_exchange_phase && exchange.is_none() && !chassis_exchange)
        || (stepping_phase && !stepper)
    {
        let holding = match (&sim, &exchange, &chassis) {
            (Some(_), _, _) => "a simulator",
            (None, Some(_), _) => "a Model Exchange model",
            (None, None, Some(_)) => "a chassis",
            (None, None, None) => "neither a simulator nor a Model Exchange model",
        };
        return Err(invalid(format_args!(
            "state {} with {holding}",
            phase.name()
        )));
    }
    if let Some(sim) = &mut sim {
        crate::guards::check_rates(&settings).map_err(|e| invalid(e.message))?;
        let config = settings.to_config(start_time).map_err(invalid)?;
        if !saved_config_matches(sim.config(), &config) {
            return Err(invalid("the simulator does not match the settings"));
        }
        // The committed time lies a representable number of steps after the
        // start (`Simulator::from_bytes` checked that it lies in the internal
        // step of its grid index, and the current time in reach of it).
        let (now, committed, step) = (sim.time(), sim.committed_time(), sim.grid().step);
        let steps = (committed - start_time) / step;
        if !(0.0..MAX_STEPS).contains(&steps) {
            return Err(invalid(format_args!(
                "simulator time {now} s (committed {committed} s) does not fit its start {start_time} s and internal step {step} s"
            )));
        }
        // A current state saved to be found later stays so (its bytes
        // round-trip): the outputs are checked on a copy that finds it.
        let outputs = match sim.computed_state() {
            Some(_) => sim.outputs(),
            None => sim.clone().outputs(),
        };
        if let Some((name, value)) = crate::guards::non_finite_output(settings.model, &outputs) {
            return Err(invalid(format_args!("output `{name}` = {value}")));
        }
    }
    Ok(SlaveState {
        phase,
        settings,
        input_slope,
        input_pending,
        input_slope_given,
        previous_input,
        earlier_input,
        hold_warned,
        contact_warned,
        start_time,
        stop_time,
        last_successful_time,
        terminate_requested,
        bonds,
        // The kind of a state from before initialization is not in its
        // bytes: the instance that restores it gives its own.
        engine: match (sim, exchange, chassis) {
            (_, Some(model), _) => Engine::ModelExchange(Some(Box::new(model))),
            (_, None, Some(chassis)) if chassis_exchange => {
                Engine::ChassisExchange(Some(Box::new(chassis)))
            }
            (_, None, Some(chassis)) => Engine::Chassis(Some(Box::new(chassis))),
            (sim, None, None) => Engine::CoSimulation(sim.map(Box::new)),
        },
    })
}

/// Serializes `model` for the FMU with `guid`.
pub fn serialize(model: &SlaveState, guid: &str) -> Vec<u8> {
    let payload = encode_payload(model);
    let mut w = ByteWriter::default();
    w.raw(MAGIC);
    w.u32(FORMAT_VERSION);
    w.u32(guid.len() as u32);
    w.raw(guid.as_bytes());
    w.u64(payload.len() as u64);
    w.u32(crc32(&payload));
    w.raw(&payload);
    w.bytes
}

/// Reads what [`serialize`] wrote, for the FMU with `guid` of `model`.
pub fn deserialize(bytes: &[u8], guid: &str, model: Model) -> Result<SlaveState, FmiError> {
    let mut r = Reader::new(bytes);
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(invalid(format_args!(
            "not a tdvass FMU state ({} bytes without the magic `TDVASSFS`)",
            bytes.len()
        )));
    }
    r.take(MAGIC.len(), "the magic")?;
    let version = r.u32("the format version")?;
    if !(OLDEST_READ..=FORMAT_VERSION).contains(&version) {
        return Err(invalid(format_args!(
            "format version {version} is not supported (this FMU reads versions {OLDEST_READ} to {FORMAT_VERSION})"
        )));
    }
    let guid_len = r.u32("the GUID length")? as usize;
    if guid_len > MAX_GUID_LEN {
        return Err(invalid(format_args!("GUID length {guid_len}")));
    }
    let written_by = r.take(guid_len, "the GUID")?;
    if written_by != guid.as_bytes() {
        return Err(invalid(format_args!(
            "written by the FMU with GUID {}, this FMU has GUID {guid}",
            String::from_utf8_lossy(written_by)
        )));
    }
    let len = r.u64("the payload length")?;
    let checksum = r.u32("the checksum")?;
    let payload = r.rest();
    if len != payload.len() as u64 {
        return Err(invalid(format_args!(
            "payload of {len} bytes announced, {} present",
            payload.len()
        )));
    }
    let actual = crc32(payload);
    if actual != checksum {
        return Err(invalid(format_args!(
            "checksum mismatch (stored {checksum:08x}, computed {actual:08x})"
        )));
    }
    decode_payload(payload, model, version)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guid;
    use tdvass::solver::Metrics;

    /// The simulator of a Co-Simulation state.
    fn simulator(state: SlaveState) -> Simulator {
        match state.engine {
            Engine::CoSimulation(Some(sim)) => *sim,
            other => panic!("no simulator in {other:?}"),
        }
    }

    fn running_model() -> SlaveState {
        let mut model = SlaveState::default();
        let config = model.settings.to_config(0.0).unwrap();
        let mut sim = Simulator::new(config).unwrap();
        sim.advance_to(0.0123).unwrap();
        model.engine = Engine::CoSimulation(Some(Box::new(sim)));
        model.phase = Phase::StepComplete;
        model.stop_time = Some(15.0);
        model.last_successful_time = 0.0123;
        model
    }

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn round_trip_is_exact() {
        let model = running_model();
        let bytes = serialize(&model, &guid(Model::QuarterCar));
        let back = deserialize(&bytes, &guid(Model::QuarterCar), Model::QuarterCar).unwrap();
        assert_eq!(serialize(&back, &guid(Model::QuarterCar)), bytes);
        assert_eq!(back.phase, Phase::StepComplete);
        assert_eq!(back.stop_time, Some(15.0));
        let (mut a, mut b) = (simulator(model), simulator(back));
        a.advance_to(0.5).unwrap();
        b.advance_to(0.5).unwrap();
        assert_eq!(a.outputs(), b.outputs());
        let fresh = SlaveState::default();
        let back = deserialize(
            &serialize(&fresh, &guid(Model::QuarterCar)),
            &guid(Model::QuarterCar),
            Model::QuarterCar,
        )
        .unwrap();
        assert!(back.engine.simulator().is_none());
        assert_eq!(back.settings, fresh.settings);
    }

    #[test]
    fn a_corner_saved_while_it_weighed_comfort_loads_and_fewer_metrics_are_refused() {
        let corner = SlaveState::new(Engine::CoSimulation(None), Model::Corner);
        let config = corner.settings.to_config(0.0).unwrap();
        assert_eq!(config.metrics, Metrics::RoadHolding);
        let with = |metrics: Metrics, mut model: SlaveState| {
            let mut sim = Simulator::new(SimulationConfig {
                metrics,
                ..model.settings.to_config(0.0).unwrap()
            })
            .unwrap();
            sim.advance_to(0.0123).unwrap();
            model.engine = Engine::CoSimulation(Some(Box::new(sim)));
            model.phase = Phase::StepComplete;
            model
        };
        let older = with(Metrics::Comfort, corner.clone());
        let bytes = serialize(&older, &guid(Model::Corner));
        let back = deserialize(&bytes, &guid(Model::Corner), Model::Corner).unwrap();
        assert_eq!(simulator(back).config().metrics, Metrics::Comfort);
        let (mut a, mut b) = (
            simulator(older),
            simulator(with(Metrics::RoadHolding, corner)),
        );
        a.advance_to(0.5).unwrap();
        b.advance_to(0.5).unwrap();
        let (a, b) = (a.outputs(), b.outputs());
        assert_eq!((a.rms, a.road_holding), (b.rms, b.road_holding));

        let fewer = with(Metrics::RoadHolding, SlaveState::default());
        let bytes = serialize(&fewer, &guid(Model::QuarterCar));
        let refused = deserialize(&bytes, &guid(Model::QuarterCar), Model::QuarterCar);
        assert!(
            refused
                .unwrap_err()
                .message
                .contains("the simulator does not match the settings")
        );
    }

    #[test]
    fn a_unilateral_state_in_flight_round_trips_and_continues_exactly() {
        // TDVASS on an ISO 8608 class D road: stopped in a flight.
        let mut model = SlaveState::default();
        model.settings.road = 2;
        model.settings.road_class = 4;
        model.settings.tire_contact = 1;
        let config = model.settings.to_config(0.0).unwrap();
        let mut sim = Simulator::new(config).unwrap();
        let mut t = 0.0;
        while !sim.in_flight() {
            t += 1e-3;
            assert!(t < 2.0, "no flight within 2 s");
            sim.advance_to(t).unwrap();
        }
        // The slave takes the lift-offs after every step (they are not
        // part of the state).
        assert!(!sim.lift_offs().events().is_empty());
        sim.clear_lift_offs();
        model.engine = Engine::CoSimulation(Some(Box::new(sim)));
        model.phase = Phase::StepComplete;
        model.last_successful_time = t;
        let bytes = serialize(&model, &guid(Model::QuarterCar));
        let back = deserialize(&bytes, &guid(Model::QuarterCar), Model::QuarterCar).unwrap();
        assert_eq!(back.settings.tire_contact, 1);
        assert_eq!(serialize(&back, &guid(Model::QuarterCar)), bytes);
        let (mut a, mut b) = (simulator(model), simulator(back));
        assert!(b.in_flight());
        a.advance_to(1.5).unwrap();
        b.advance_to(1.5).unwrap();
        assert_eq!(a.outputs(), b.outputs());
        assert_eq!(a.lift_offs(), b.lift_offs());
        // The setting is checked like every other one.
        let mut bad = SlaveState::default();
        bad.settings.tire_contact = 2;
        let e = deserialize(
            &serialize(&bad, &guid(Model::QuarterCar)),
            &guid(Model::QuarterCar),
            Model::QuarterCar,
        )
        .unwrap_err()
        .message;
        assert!(e.contains("tire_contact") && e.contains('2'), "{e}");
    }

    #[test]
    fn state_ending_just_before_a_grid_node_round_trips() {
        // A step that ends within the solver's tolerance before a grid node
        // commits the node and keeps the requested time as the current one,
        // a hair before the committed time.
        let mut model = running_model();
        let sim = model.engine.simulator_mut().unwrap();
        let step = sim.grid().step;
        let end = 400.0 * step - 0.4e-9 * step;
        sim.advance_to(end).unwrap();
        assert!(sim.time() < sim.committed_time());
        model.last_successful_time = end;
        let bytes = serialize(&model, &guid(Model::QuarterCar));
        let back = deserialize(&bytes, &guid(Model::QuarterCar), Model::QuarterCar).unwrap();
        assert_eq!(serialize(&back, &guid(Model::QuarterCar)), bytes);
    }

    #[test]
    fn envelope_errors() {
        let g = guid(Model::QuarterCar);
        let bytes = serialize(&running_model(), &g);
        let err = |b: &[u8]| deserialize(b, &g, Model::QuarterCar).unwrap_err().message;
        assert!(err(&[]).contains("magic"));
        assert!(err(b"TDVASSF").contains("magic"));
        assert!(err(b"something else entirely").contains("magic"));
        for cut in [8, 11, 12, 20, 60, 70, bytes.len() / 2, bytes.len() - 1] {
            let e = err(&bytes[..cut]);
            assert!(
                e.contains("truncated") || e.contains("payload"),
                "{cut}: {e}"
            );
        }
        for version in [1, 2, 3, 4, 5, 8] {
            let mut other = bytes.clone();
            other[8] = version;
            assert!(err(&other).contains(&format!("format version {version}")));
        }
        assert!(
            deserialize(
                &bytes,
                "{00000000-0000-0000-0000-000000000000}",
                Model::QuarterCar
            )
            .unwrap_err()
            .message
            .contains("GUID")
        );
        let mut long = bytes.clone();
        long.push(0);
        assert!(err(&long).contains("payload"));
        let mut bad_len = bytes.clone();
        bad_len[12] = 200;
        assert!(err(&bad_len).contains("GUID length"));
    }

    #[test]
    fn every_single_bit_flip_is_detected() {
        let g = guid(Model::QuarterCar);
        let bytes = serialize(&running_model(), &g);
        let mut flipped = bytes.clone();
        for i in 0..bytes.len() {
            for bit in 0..8 {
                flipped[i] ^= 1 << bit;
                assert!(
                    deserialize(&flipped, &g, Model::QuarterCar).is_err(),
                    "byte {i} bit {bit}"
                );
                flipped[i] ^= 1 << bit;
            }
        }
    }

    #[test]
    fn consistent_checksum_but_bad_content_is_refused() {
        let g = guid(Model::QuarterCar);
        let model = running_model();
        let mut payload = encode_payload(&model);
        // A negative mass (m_s is the second setting: phase byte, count, then vr/value pairs).
        let m_s_at = 1 + 4 + 12 + 4;
        payload[m_s_at..m_s_at + 8].copy_from_slice(&(-1.0f64).to_bits().to_le_bytes());
        let mut w = ByteWriter::default();
        w.raw(MAGIC);
        w.u32(FORMAT_VERSION);
        w.u32(g.len() as u32);
        w.raw(g.as_bytes());
        w.u64(payload.len() as u64);
        w.u32(crc32(&payload));
        w.raw(&payload);
        let e = deserialize(&w.bytes, &g, Model::QuarterCar)
            .unwrap_err()
            .message;
        assert!(e.contains("m_s") && e.contains("-1"), "{e}");
    }
}
