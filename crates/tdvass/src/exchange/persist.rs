//! The byte form of a Model Exchange instance's dynamic state (time,
//! continuous states, contact mode, counts, delay history), written with
//! the crate's one codec ([`crate::bytes`]). The configuration is not in
//! it: a state is restored into a model built from the same configuration
//! ([`ModelExchange::restore`]). A random road's generator and nodes are
//! in it. Version 2 adds the floor, the latest time set and the master's
//! completion habits; a state of version 1 still loads (its floor is the
//! latest of its accepted time and what its history and road still hold).
//! Version 3 adds a corner's body attachment (a tag, then its displacement
//! and velocity) at the end; version 4 writes there the count of the
//! inputs that prescribe coordinates ([`PRESCRIBED`]), then each one's tag
//! and values, so that a state saved before an input existed loads (the
//! input then takes its coordinates from the saved states).

use super::history::{DelayHistory, HistoryPoint};
use super::instance::{Delay, HYSTERESIS, ModelExchange};
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::model::dynamics::SWITCHES;
use crate::model::inputs::PRESCRIBED;
use crate::road::RoadState;
use crate::solver::CONTINUOUS_STATES;

/// Most road nodes a state may carry: as many as a model keeps (32 MiB).
const MAX_ROAD_NODES: u64 = crate::limits::MAX_WORK_PER_CALL as u64;

/// Version of the byte form; a saved state of a later version is refused.
/// Version 3 added the count of switching elements before their sides and
/// a corner's body attachment (its input) at the end; version 4 the count
/// of the inputs that prescribe coordinates before them.
pub const EXCHANGE_FORMAT_VERSION: u32 = 4;

/// The first version with a corner's body attachment.
const BODY_VERSION: u32 = 3;

/// The first version with the count of the inputs that prescribe
/// coordinates.
const PRESCRIBED_VERSION: u32 = 4;

/// The first version with the floor and the completion habits.
const FLOOR_VERSION: u32 = 2;

/// The byte form's first word.
const MAGIC: u32 = 0x4d45_5856; // "VXEM"

fn invalid(what: String) -> Error {
    Error::InvalidState(what)
}

impl ModelExchange {
    /// Encodes the dynamic state (module documentation).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = ByteWriter::default();
        w.u32(MAGIC);
        w.u32(EXCHANGE_FORMAT_VERSION);
        w.f64(self.time);
        w.f64(self.accepted);
        w.f64(self.floor);
        w.f64(self.latest);
        w.u8(u8::from(self.completes));
        let (completes_steps, completed_once) = match &self.delay {
            Delay::History(h) => h.habits(),
            _ => (false, false),
        };
        w.u8(u8::from(completes_steps) | (u8::from(completed_once) << 1));
        w.f64s(&self.states);
        let d = &self.discrete;
        // How many elements, then each element's side (1 on its first)
        // and hysteresis, in bit order (before version 3: the tire's alone,
        // without the count).
        w.u8(SWITCHES.len() as u8);
        for (i, switch) in SWITCHES.into_iter().enumerate() {
            w.u8(u8::from(!d.sides.is(switch)));
            w.f64(d.hysteresis[i]);
        }
        w.u64(d.lift_off_count);
        w.f64(d.max_suspension_deflection);
        match d.first_contact_loss {
            Some((time, load)) => {
                w.u8(1);
                w.f64(time);
                w.f64(load);
            }
            None => w.u8(0),
        }
        match &self.delay {
            Delay::History(h) => {
                w.u64(h.points().len() as u64);
                for p in h.points() {
                    w.f64(p.time);
                    w.f64(p.position);
                    w.f64(p.velocity);
                    w.u8(u8::from(p.accepted) | (u8::from(p.anchor) << 1));
                    w.f64(p.superseded_by);
                }
            }
            _ => w.u64(0),
        }
        // A random road's generator and nodes: a restored model goes on
        // from them instead of generating the road again from its start.
        match self.road.node_state() {
            Some(road) => {
                w.u8(1);
                road.write_nodes(&mut w);
            }
            None => w.u8(0),
        }
        w.u8(PRESCRIBED.len() as u8);
        for value in &self.prescribed {
            match value {
                Some([position, velocity]) => {
                    w.u8(1);
                    w.f64(*position);
                    w.f64(*velocity);
                }
                None => w.u8(0),
            }
        }
        w.bytes
    }

    /// Restores a state of [`Self::to_bytes`] into this model (built from
    /// the same configuration). Checked: version, layout, finite values,
    /// times not before the start, a history consistent with the delay.
    /// On error the model is unchanged.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<()> {
        let mut r = ByteReader::new(bytes);
        if r.u32()? != MAGIC {
            return Err(invalid("not a Model Exchange state".into()));
        }
        let version = r.u32()?;
        if !(1..=EXCHANGE_FORMAT_VERSION).contains(&version) {
            return Err(invalid(format!(
                "Model Exchange state format version {version}, this FMU reads 1 to {EXCHANGE_FORMAT_VERSION}"
            )));
        }
        let start = self.config.start_time;
        let time = r.f64()?;
        let accepted = r.f64()?;
        let (floor, latest, completes, habit_bits) = if version >= FLOOR_VERSION {
            (r.f64()?, r.f64()?, r.u8()? != 0, r.u8()?)
        } else {
            (accepted, time, false, 0)
        };
        if habit_bits > 3 {
            return Err(invalid(format!("completion habits {habit_bits}")));
        }
        let habits = (habit_bits & 1 != 0, habit_bits & 2 != 0);
        if !([time, accepted, floor, latest]
            .iter()
            .all(|t| t.is_finite())
            && start <= accepted
            && accepted <= floor
            && floor <= time
            && time <= latest
            && time.abs() <= self.max_time)
        {
            return Err(invalid(format!(
                "times {accepted} s (accepted), {floor} s (floor), {time} s (now) and {latest} s (latest) are not ordered after the start time {start} s within ±{:e} s",
                self.max_time
            )));
        }
        let states = r.f64s(CONTINUOUS_STATES as u64)?;
        if states.len() != CONTINUOUS_STATES || states.iter().any(|v| !v.is_finite()) {
            return Err(invalid(format!(
                "{} continuous states, not {CONTINUOUS_STATES} finite values",
                states.len()
            )));
        }
        let mut discrete = self.discrete;
        let elements = if version >= BODY_VERSION {
            usize::from(r.u8()?)
        } else {
            1
        };
        if elements > SWITCHES.len() {
            return Err(invalid(format!(
                "{elements} switching elements: this model has {}",
                SWITCHES.len()
            )));
        }
        for (i, switch) in SWITCHES.into_iter().enumerate() {
            if i < elements {
                discrete.sides = discrete.sides.with(switch, r.u8()? == 0);
                discrete.hysteresis[i] = r.f64()?;
            } else {
                // An element the saved state did not have: its first law.
                discrete.sides = discrete.sides.with(switch, false);
                discrete.hysteresis[i] = HYSTERESIS * self.switching.scale(switch);
            }
        }
        discrete.lift_off_count = r.u64()?;
        discrete.max_suspension_deflection = r.f64()?;
        discrete.first_contact_loss = match r.u8()? {
            0 => None,
            _ => Some((r.f64()?, r.f64()?)),
        };
        if !(discrete
            .hysteresis
            .iter()
            .all(|h| h.is_finite() && *h > 0.0)
            && discrete.max_suspension_deflection.is_finite()
            && discrete
                .first_contact_loss
                .is_none_or(|(t, load)| t.is_finite() && load.is_finite()))
        {
            return Err(invalid("the discrete state is not finite".into()));
        }
        let count = r.u64()?;
        if count > super::MAX_HISTORY_POINTS as u64 {
            return Err(invalid(format!("a delay history of {count} points")));
        }
        let mut points = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let (time, position, velocity) = (r.f64()?, r.f64()?, r.f64()?);
            let flags = r.u8()?;
            let superseded_by = if version >= FLOOR_VERSION {
                r.f64()?
            } else {
                f64::INFINITY
            };
            if flags > 3 || (version < FLOOR_VERSION && flags > 1) {
                return Err(invalid(format!("delay history point flags {flags}")));
            }
            points.push(HistoryPoint {
                time,
                position,
                velocity,
                accepted: flags & 1 != 0,
                anchor: flags & 2 != 0,
                superseded_by,
            });
        }
        let road = match r.u8()? {
            0 => None,
            _ => Some(RoadState::read_nodes(&mut r)?),
        };
        if let Some(kept) = road.as_ref().map(|road| road.nodes.len() as u64)
            && kept > MAX_ROAD_NODES
        {
            return Err(invalid(format!(
                "{kept} road nodes: a model keeps at most {MAX_ROAD_NODES}"
            )));
        }
        let saved = read_prescribed(&mut r, version)?;
        for (i, (saved, value)) in saved.iter().zip(&self.prescribed).enumerate() {
            if saved.is_some_and(|s| s.is_some() != value.is_some()) {
                return Err(invalid(format!(
                    "{} for a model without it, or none for one with it",
                    PRESCRIBED[i].what
                )));
            }
            if saved
                .flatten()
                .is_some_and(|v| v.iter().any(|v| !v.is_finite()))
            {
                return Err(invalid(format!("{} is not finite", PRESCRIBED[i].what)));
            }
        }
        if !r.is_empty() {
            return Err(invalid(
                "trailing bytes after the Model Exchange state".into(),
            ));
        }
        let mut restored_road = self.road.clone();
        match (&road, self.road.node_state()) {
            (Some(state), _) => restored_road.restore_nodes(state)?,
            (None, None) => {}
            (None, Some(_)) => return Err(invalid("a random road without its nodes".into())),
        }
        let delay = match &self.delay {
            Delay::History(h) => Delay::History(
                DelayHistory::from_points(start, h.initial_position(), h.tau(), points, habits)
                    .map_err(invalid)?,
            ),
            other if count == 0 => other.clone(),
            _ => return Err(invalid("a delay history for a model without delay".into())),
        };
        let held_from = match &delay {
            Delay::History(h) => h.earliest_time(),
            _ => f64::NEG_INFINITY,
        }
        .max(restored_road.earliest_time());
        let floor = if version >= FLOOR_VERSION {
            if held_from > floor {
                return Err(invalid(format!(
                    "the floor {floor} s is before {held_from} s, where the saved delay history and road nodes begin"
                )));
            }
            floor
        } else {
            floor.max(held_from)
        };
        if floor > time {
            return Err(invalid(format!(
                "the saved delay history and road nodes begin at {floor} s, after the time {time} s"
            )));
        }
        self.time = time;
        self.accepted = accepted;
        self.floor = floor;
        self.latest = latest;
        self.completes = completes;
        self.states.copy_from_slice(&states);
        for ((p, saved), value) in PRESCRIBED.iter().zip(saved).zip(&mut self.prescribed) {
            if value.is_some() {
                // An input the state was saved without (before version 3,
                // never a corner's, or before the input existed) takes its
                // coordinates from the saved states.
                *value = saved.flatten().or(Some(p.coordinates.map(|c| states[c])));
            }
        }
        self.discrete = discrete;
        self.delay = delay;
        self.road = restored_road;
        self.reserve();
        Ok(())
    }
}

/// The saved values of the inputs that prescribe coordinates, by index
/// into [`PRESCRIBED`]: `None` for one the state was saved without (before
/// version 3 or before the input existed), `Some(None)` for one saved as
/// absent. Version 3 saved the body attachment alone, without the count.
fn read_prescribed(
    r: &mut ByteReader,
    version: u32,
) -> Result<[Option<Option<[f64; 2]>>; PRESCRIBED.len()]> {
    let count = match version {
        v if v >= PRESCRIBED_VERSION => usize::from(r.u8()?),
        v if v >= BODY_VERSION => 1,
        _ => 0,
    };
    if count > PRESCRIBED.len() {
        return Err(invalid(format!(
            "{count} inputs that prescribe coordinates: this FMU knows {}",
            PRESCRIBED.len()
        )));
    }
    let mut saved = [None; PRESCRIBED.len()];
    for value in saved.iter_mut().take(count) {
        *value = Some(match r.u8()? {
            0 => None,
            _ => Some([r.f64()?, r.f64()?]),
        });
    }
    Ok(saved)
}
