//! The saved simulator's checks: every fault in the bytes is refused with
//! a message naming it.

use super::*;
use crate::model::{Body, State, TireContact};
use crate::road::{RandomRoad, RoadClass, RoadSpec};
use crate::solver::Metrics;

/// Offset of `grid_index` in [`Simulator::to_bytes`]: right after the
/// configuration. `committed_time` follows it, then the committed state
/// (6 values), then `current_time`.
fn grid_index_at(sim: &Simulator) -> usize {
    let mut w = ByteWriter::default();
    w.u64(STATE_FORMAT_VERSION);
    sim.config.write(&mut w);
    w.f64(sim.step_choice.step_bound);
    w.bytes.len()
}

fn committed_time_at(sim: &Simulator) -> usize {
    grid_index_at(sim) + 8
}

fn current_time_at(sim: &Simulator) -> usize {
    grid_index_at(sim) + 16 + 6 * 8
}

fn put(bytes: &mut [u8], at: usize, bits: u64) {
    bytes[at..at + 8].copy_from_slice(&bits.to_le_bytes());
}

/// Asserts that `bytes` are refused with [`Error::InvalidState`] whose
/// message names every one of `words`.
fn refused(bytes: &[u8], words: &[&str]) {
    match Simulator::from_bytes(bytes) {
        Err(Error::InvalidState(message)) => {
            for word in words {
                assert!(message.contains(word), "`{word}` not in: {message}");
            }
        }
        Err(other) => panic!("expected an invalid state naming {words:?}, got {other}"),
        Ok(_) => panic!("accepted a state that should name {words:?}"),
    }
}

/// A simulator at 0.0623 s on the harmonic road: grid node 623.
fn running() -> Simulator {
    let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
    sim.advance_to(0.0623).unwrap();
    assert_eq!(
        (sim.trajectory.grid_index, sim.trajectory.committed_time),
        (623, 0.0623)
    );
    sim
}

#[test]
fn grid_index_inconsistent_with_the_committed_time_is_refused() {
    let sim = running();
    let bytes = sim.to_bytes();
    Simulator::from_bytes(&bytes).unwrap();
    let k = sim.trajectory.grid_index;
    let at = grid_index_at(&sim);
    for forged in [
        0,
        k - 1,
        k + 1,
        k + 1_000_000,
        1 << 60,
        u64::MAX - 1,
        u64::MAX,
    ] {
        let mut bytes = bytes.clone();
        put(&mut bytes, at, forged);
        refused(&bytes, &["grid_index", &forged.to_string()]);
    }
}

#[test]
fn rms_accumulators_inconsistent_with_the_grid_index_are_refused() {
    let sim = running();
    let bytes = sim.to_bytes();
    // After the deferral byte and the history ring (its length, then 2
    // values per node) come the three sums of squares and the sample
    // count.
    let sums_at = current_time_at(&sim) + 8 + 6 * 8 + 1 + 8 + 16 * sim.inputs.history.len();
    let samples_at = sums_at + 3 * 8;
    assert_eq!(
        bytes[samples_at..samples_at + 8],
        sim.trajectory.grid_index.to_le_bytes()
    );
    for forged in [0, 622, 624, u64::MAX] {
        let mut bytes = bytes.clone();
        put(&mut bytes, samples_at, forged);
        refused(&bytes, &["rms samples", &forged.to_string()]);
    }
    for forged in [f64::NAN, f64::INFINITY, -1.0] {
        let mut bytes = bytes.clone();
        put(&mut bytes, sums_at + 8, forged.to_bits());
        refused(&bytes, &["SDD", &forged.to_string()]);
    }
}

#[test]
fn times_moved_away_from_the_grid_index_are_refused() {
    // The times moved to 1e6 s with the grid index left at node 623:
    // accepting it would make the next step integrate ~1e10 steps, from
    // node 623 to 1e6 s.
    let sim = running();
    let bytes = sim.to_bytes();
    let mut forged = bytes.clone();
    put(&mut forged, committed_time_at(&sim), 1e6f64.to_bits());
    put(&mut forged, current_time_at(&sim), 1e6f64.to_bits());
    refused(&forged, &["committed_time", "1000000", "grid_index"]);

    let (h, k) = (sim.grid.step, sim.trajectory.grid_index);
    let next = sim.grid_time(k + 1);
    for (time, words) in [
        (
            sim.trajectory.committed_time - 0.5 * h,
            ["current_time", "committed_time"],
        ),
        (next + 0.5 * h, ["current_time", "grid_index"]),
        (sim.grid_time(k + 2), ["current_time", "grid_index"]),
        (f64::NAN, ["current_time", "NaN"]),
    ] {
        let mut forged = bytes.clone();
        put(&mut forged, current_time_at(&sim), time.to_bits());
        refused(&forged, &words);
    }
    // The committed time one step early, or on the next node, with both
    // times still ordered.
    for time in [sim.grid_time(k - 1), next] {
        let mut forged = bytes.clone();
        put(&mut forged, committed_time_at(&sim), time.to_bits());
        put(&mut forged, current_time_at(&sim), time.to_bits());
        refused(&forged, &["committed_time", "grid_index"]);
    }
}

#[test]
fn every_state_the_simulator_saves_is_accepted() {
    // On a node, inside a step, a hair before and after a node (within
    // the solver's tolerance, where the current time may lie just before
    // the committed node), and after an external input changes inside a
    // step or just before a node.
    for road in [
        RoadSpec::paper_harmonic(),
        RoadSpec::Iso8608(RandomRoad::default()),
        RoadSpec::PaperCompatible {
            road: RandomRoad::default(),
            sample_interval: 0.1,
        },
        RoadSpec::Input,
    ] {
        let mut sim = Simulator::new(SimulationConfig {
            road: road.clone(),
            ..SimulationConfig::default()
        })
        .unwrap();
        let h = sim.grid.step;
        let node = |sim: &Simulator, k: u64| sim.grid_time(k);
        let stops = [
            node(&sim, 100),
            node(&sim, 250) + 0.3 * h,
            node(&sim, 400) - 0.4e-9 * h,
            node(&sim, 500) + 0.4e-9 * h,
            node(&sim, 5000) + 0.7 * h,
            node(&sim, 9000) - 0.4e-9 * h,
        ];
        for t in stops {
            sim.advance_to(t).unwrap();
            if sim.inputs.road.is_input() {
                sim.set_road_input(0.01 * t, 0.1).unwrap();
            }
            let bytes = sim.to_bytes();
            let mut restored =
                Simulator::from_bytes(&bytes).unwrap_or_else(|e| panic!("{road:?} at {t}: {e}"));
            assert_eq!(restored.to_bytes(), bytes);
            let mut ahead = sim.clone();
            ahead.advance_to(t + 0.01).unwrap();
            restored.advance_to(t + 0.01).unwrap();
            assert_eq!(restored.to_bytes(), ahead.to_bytes(), "{road:?} at {t}");
        }
    }
}

#[test]
fn comfort_and_holding_accumulators_inconsistent_with_the_run_are_refused() {
    use crate::solver::Metrics;
    let config = |metrics| SimulationConfig {
        road: RoadSpec::Iso8608(RandomRoad {
            class: RoadClass::H,
            speed: 30.0,
            ..RandomRoad::default()
        }),
        metrics,
        ..SimulationConfig::default()
    };
    let mut sim = Simulator::new(config(Metrics::Comfort)).unwrap();
    sim.advance_to(0.5).unwrap();
    let holding = sim.observers.holding;
    assert!(holding.lost_steps > 0 && holding.first_loss.is_some());
    let bytes = sim.to_bytes();
    Simulator::from_bytes(&bytes).unwrap();
    // Offsets from the end: the road state (input tag, the nodes with
    // their count, first_node, word position), then the flight in
    // progress (tag 0), the mode, the lift-offs, the first loss (tag and
    // time), the lost time, the lost steps, the max deflection, the 8
    // filter states and the 2 a_w sums.
    let road = sim.inputs.road.dynamic_state();
    let road_len = 16 + 8 + 8 + 8 * road.nodes.len() + 8;
    let flight_at = bytes.len() - road_len - 8;
    let mode_at = flight_at - 8;
    let lift_offs_at = mode_at - 8;
    let first_loss_at = lift_offs_at - 16;
    assert_eq!(
        bytes[lift_offs_at..lift_offs_at + 8],
        holding.lift_offs.to_le_bytes()
    );
    let lost_time_at = first_loss_at - 8;
    let lost_steps_at = lost_time_at - 8;
    let max_at = lost_steps_at - 8;
    let filter_at = max_at - 8 * 8;
    let sums_at = filter_at - 16;
    assert_eq!(
        bytes[lost_steps_at..lost_steps_at + 8],
        holding.lost_steps.to_le_bytes()
    );
    for (at, value, words) in [
        (sums_at, (-1.0f64).to_bits(), ["comfort", "negative"]),
        (filter_at, f64::NAN.to_bits(), ["comfort", "NaN"]),
        (
            max_at,
            0.0f64.to_bits(),
            ["max suspension deflection", "below"],
        ),
        (
            lost_steps_at,
            sim.trajectory.grid_index + 1,
            ["contact loss time", "whole steps"],
        ),
        (lost_time_at, 1e3f64.to_bits(), ["contact loss time", "run"]),
        (
            first_loss_at + 8,
            1e3f64.to_bits(),
            ["first contact loss", "outside"],
        ),
    ] {
        let mut forged = bytes.clone();
        put(&mut forged, at, value);
        refused(&forged, &words);
    }
    // No first loss recorded (tag 0, without its time).
    let mut forged = bytes[..first_loss_at].to_vec();
    forged.extend(0u64.to_le_bytes());
    forged.extend(&bytes[first_loss_at + 16..]);
    refused(&forged, &["contact loss time", "without a first"]);
    // A flight in progress with the bilateral tire.
    let mut forged = bytes[..flight_at].to_vec();
    forged.extend(1u64.to_le_bytes());
    forged.extend(0.25f64.to_le_bytes());
    forged.extend(&bytes[flight_at + 8..]);
    put(&mut forged, mode_at, 1);
    refused(&forged, &["flight in progress", "bilateral"]);
    // A mode that is not one, and one the flight in progress contradicts.
    let mut forged = bytes.clone();
    put(&mut forged, mode_at, 2);
    refused(&forged, &["mode 2", "2 modes"]);
    let mut forged = bytes.clone();
    put(&mut forged, mode_at, 1);
    refused(&forged, &["mode 1", "in flight", "in contact"]);
    // A foreign version.
    let mut forged = bytes.clone();
    put(&mut forged, 0, 1);
    refused(&forged, &["format version 1"]);
    // Filter state or holding accumulators where they are not kept.
    let mut paper = Simulator::new(config(Metrics::Paper)).unwrap();
    paper.advance_to(0.5).unwrap();
    paper.trajectory.committed_filter[3] = 1e-3;
    refused(&paper.to_bytes(), &["comfort", "off"]);
    paper.trajectory.committed_filter[3] = 0.0;
    Simulator::from_bytes(&paper.to_bytes()).unwrap();
    paper.observers.holding.lost_steps = 1;
    refused(&paper.to_bytes(), &["road holding is off"]);
}

/// The bytes of format 4, which had no mode word, still load: a
/// unilateral run saved in flight and in contact restores to the same
/// simulator as its bytes of the current format.
#[test]
fn states_of_format_4_still_load() {
    let config = SimulationConfig {
        road: RoadSpec::Iso8608(RandomRoad {
            class: RoadClass::E,
            speed: 30.0,
            ..RandomRoad::default()
        }),
        tire_contact: TireContact::Unilateral,
        ..SimulationConfig::default()
    };
    let mut sim = Simulator::new(config).unwrap();
    let (mut saw_flight, mut saw_contact) = (false, false);
    for step in 1..=400 {
        sim.advance_to(step as f64 * 2.5e-3).unwrap();
        let in_flight = sim.in_flight();
        if (in_flight && saw_flight) || (!in_flight && saw_contact) {
            continue;
        }
        (saw_flight, saw_contact) = (saw_flight || in_flight, saw_contact || !in_flight);
        let bytes = settled(&sim).to_bytes();
        let road_len = 16 + 8 + 8 + 8 * sim.inputs.road.dynamic_state().nodes.len() + 8;
        let flight_len = if in_flight { 16 } else { 8 };
        let mode_at = bytes.len() - road_len - flight_len - 8;
        let mut old = bytes[..mode_at].to_vec();
        old.extend(&bytes[mode_at + 8..]);
        let old = as_format(&sim, &old, 4);
        let restored = Simulator::from_bytes(&old).unwrap();
        assert_eq!(restored.in_flight(), in_flight);
        assert_eq!(restored.to_bytes(), bytes, "in flight: {in_flight}");
    }
    assert!(saw_flight && saw_contact, "the run should lift off");
}

/// The bytes of `sim` with its random road state replaced.
fn with_road(sim: &Simulator, first_node: u64, nodes: &[f64]) -> Vec<u8> {
    let bytes = sim.to_bytes();
    let saved = sim.inputs.road.dynamic_state();
    // first_node, the node count, the nodes, the input tag.
    let first_at = bytes.len() - 8 * (3 + saved.nodes.len());
    let mut w = ByteWriter {
        bytes: bytes[..first_at].to_vec(),
    };
    w.u64(first_node);
    w.f64s(nodes);
    w.u64(0);
    w.bytes
}

#[test]
fn road_nodes_inconsistent_with_the_committed_time_are_refused() {
    for road in [
        RoadSpec::Iso8608(RandomRoad::default()),
        RoadSpec::PaperCompatible {
            road: RandomRoad::default(),
            sample_interval: 0.01,
        },
    ] {
        let mut sim = Simulator::new(SimulationConfig {
            road,
            ..SimulationConfig::default()
        })
        .unwrap();
        sim.advance_to(0.5).unwrap();
        let saved = sim.inputs.road.dynamic_state();
        let (first, nodes) = (saved.first_node, saved.nodes);
        assert!(first > 0);
        assert_eq!(with_road(&sim, first, &nodes), sim.to_bytes());
        Simulator::from_bytes(&with_road(&sim, first, &nodes)).unwrap();
        // The node holding the committed time released.
        refused(&with_road(&sim, first + 1, &nodes), &["first_node"]);
        // From node 0, without the nodes up to the committed time: the
        // next step would generate them all again.
        refused(&with_road(&sim, 0, &nodes), &["first_node 0"]);
        refused(&with_road(&sim, 0, &[0.0]), &["first_node 0", "1 nodes"]);
        // Far too many nodes, and node indices that would overflow.
        let mut many = nodes.clone();
        many.resize(nodes.len() + 10_000, 0.0);
        refused(
            &with_road(&sim, first, &many),
            &["first_node", "extends past"],
        );
        refused(&with_road(&sim, u64::MAX - 1, &nodes), &["first_node"]);
        refused(&with_road(&sim, first, &[]), &["without nodes"]);
    }
}

#[test]
fn road_input_after_the_committed_time_is_refused() {
    let mut sim = Simulator::new(SimulationConfig {
        road: RoadSpec::Input,
        ..SimulationConfig::default()
    })
    .unwrap();
    sim.advance_to(0.05).unwrap();
    sim.set_road_input(0.01, 0.2).unwrap();
    sim.advance_to(0.0712).unwrap();
    let bytes = sim.to_bytes();
    Simulator::from_bytes(&bytes).unwrap();
    // The input's start time, value and slope are the last 24 bytes.
    let start_at = bytes.len() - 24;
    for (at, value) in [
        (start_at, 0.08),
        (start_at, f64::NAN),
        (start_at + 8, f64::INFINITY),
        (start_at + 16, f64::NAN),
    ] {
        let mut forged = bytes.clone();
        put(&mut forged, at, value.to_bits());
        refused(&forged, &["road input", "committed_time"]);
    }
}

#[test]
fn last_node_until_finds_the_last_node_reached() {
    // Ends on a node, a few ulps either side of it, at the edge of the
    // snap tolerance and inside steps, one to three steps ahead: the
    // node found is the last one a scan finds.
    let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
    sim.advance_to(0.25).unwrap();
    let k = sim.trajectory.grid_index;
    for ahead in 1..=3 {
        let node = sim.grid_time(k + ahead);
        let tolerance = sim.snap_tolerance(node);
        let h = sim.grid.step;
        for t_end in [
            node,
            node.next_up(),
            node.next_down(),
            node.next_down().next_down(),
            node - 0.9 * tolerance,
            node - 1.1 * tolerance,
            node + 1.1 * tolerance,
            node - 0.5 * h,
            node + 0.5 * h,
        ] {
            let scan = (k..k + 8)
                .take_while(|&j| {
                    let t = sim.grid_time(j);
                    t < t_end || sim.snaps(t_end, t)
                })
                .last()
                .unwrap();
            assert_eq!(
                sim.last_node_until(t_end),
                scan,
                "{ahead} ahead, t_end {t_end}"
            );
        }
    }
}

#[test]
fn last_node_until_is_bounded_where_node_times_do_not_resolve_steps() {
    // States no simulator reaches (`Simulator::new` refuses such start
    // times), built field by field: the search for the last node reached
    // returns without scanning the nodes that share one floating-point
    // time, and without overflowing the node index.
    let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
    let k = u64::MAX - 10;
    sim.trajectory.grid_index = k;
    sim.trajectory.committed_time = sim.grid_time(k);
    sim.trajectory.current_time = sim.trajectory.committed_time;
    for t_end in [
        sim.trajectory.committed_time,
        sim.trajectory.committed_time * 1.5,
        f64::MAX,
    ] {
        let j = sim.last_node_until(t_end);
        assert!(j >= k && j < u64::MAX, "{j}");
    }
    let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
    sim.config.start_time = 1e22;
    sim.inputs.move_start_for_tests(1e22);
    sim.trajectory.committed_time = 1e22;
    sim.trajectory.current_time = 1e22;
    let reached = |sim: &Simulator, j: u64| {
        let t = sim.grid_time(j);
        t <= 1e22 || sim.coincide(t, 1e22)
    };
    let j = sim.last_node_until(1e22);
    // About 1.8e11 nodes coincide with 1e22 s.
    assert!(j > 1 << 36, "{j}");
    assert!(reached(&sim, j) && !reached(&sim, j + 1));
}

/// `sim` with its current state computed, as the formats before 7 saved
/// it.
fn settled(sim: &Simulator) -> Simulator {
    let mut settled = sim.clone();
    settled.settle();
    settled
}

/// `bytes` (of `sim`, its state computed) as format `version` (4 to 6)
/// wrote them: without the deferral byte after the points (format 7), and
/// before 6 without the configuration's body and road shift (its last
/// three words).
fn as_format(sim: &Simulator, bytes: &[u8], version: u64) -> Vec<u8> {
    let deferral_at = current_time_at(sim) + 8 + 6 * 8;
    assert_eq!(bytes[deferral_at], 0, "a computed state");
    let mut old = bytes[..deferral_at].to_vec();
    old.extend(&bytes[deferral_at + 1..]);
    if version < 6 {
        let mut config = ByteWriter::default();
        sim.config.write(&mut config);
        let body_at = 8 + config.bytes.len() - 24;
        old.drain(body_at..body_at + 24);
    }
    put(&mut old, 0, version);
    old
}

#[test]
fn states_of_format_5_still_load_with_the_sprung_mass() {
    let mut sim = Simulator::new(SimulationConfig {
        metrics: Metrics::Comfort,
        ..SimulationConfig::default()
    })
    .unwrap();
    sim.advance_to(0.1234).unwrap();
    let bytes = settled(&sim).to_bytes();
    let restored = Simulator::from_bytes(&as_format(&sim, &bytes, 5)).unwrap();
    assert_eq!(restored.config().body, Body::Mass);
    assert_eq!(restored.to_bytes(), bytes);
}

/// The bytes of format 6, which saved every current state computed, still
/// load: a corner inside a step, on the delayed random road.
#[test]
fn states_of_format_6_still_load() {
    let mut sim = Simulator::new(SimulationConfig {
        body: Body::Attached,
        road: RoadSpec::Iso8608(RandomRoad::default()),
        road_shift: crate::road::RoadShift {
            delay: 0.01,
            phase: 0.0,
        },
        ..SimulationConfig::default()
    })
    .unwrap();
    sim.advance_to(0.03).unwrap();
    sim.set_body_input(0.002, -0.03).unwrap();
    sim.advance_to(0.08765).unwrap();
    let bytes = settled(&sim).to_bytes();
    let mut restored = Simulator::from_bytes(&as_format(&sim, &bytes, 6)).unwrap();
    assert!(restored.computed_state().is_some());
    assert_eq!(restored.to_bytes(), bytes);
    sim.advance_to(0.2).unwrap();
    restored.advance_to(0.2).unwrap();
    assert_eq!(restored.to_bytes(), sim.to_bytes());
}

/// A state saved while still to be found is saved as it stands and found
/// after the restore; a deferral byte out of range, or a deferred state
/// not written as the committed one, is refused by name.
#[test]
fn a_deferred_state_is_saved_as_it_stands() {
    let mut sim = running();
    sim.advance_to(0.06234).unwrap();
    assert!(sim.computed_state().is_none(), "inside a step: deferred");
    let bytes = sim.to_bytes();
    let deferral_at = current_time_at(&sim) + 8 + 6 * 8;
    assert_eq!(bytes[deferral_at], 2);
    let mut restored = Simulator::from_bytes(&bytes).unwrap();
    assert!(restored.computed_state().is_none());
    assert_eq!(restored.to_bytes(), bytes);
    let bits = |x: State| x.map(f64::to_bits);
    assert_eq!(bits(restored.state()), bits(sim.state()));
    sim.advance_to(0.1).unwrap();
    restored.advance_to(0.1).unwrap();
    assert_eq!(restored.to_bytes(), sim.to_bytes());
    let mut wrong = bytes.clone();
    wrong[deferral_at] = 3;
    refused(&wrong, &["deferral 3"]);
    let mut wrong = bytes.clone();
    put(&mut wrong, current_time_at(&sim) + 8, 1e-3f64.to_bits());
    refused(&wrong, &["deferred", "committed"]);
}

#[test]
fn a_corner_s_state_keeps_its_body_and_its_attachment() {
    let mut sim = Simulator::new(SimulationConfig {
        body: Body::Attached,
        ..SimulationConfig::default()
    })
    .unwrap();
    sim.advance_to(0.05).unwrap();
    sim.set_body_input(0.002, -0.03).unwrap();
    sim.advance_to(0.0875).unwrap();
    let bytes = sim.to_bytes();
    let mut restored = Simulator::from_bytes(&bytes).unwrap();
    assert_eq!(restored.config().body, Body::Attached);
    sim.advance_to(0.2).unwrap();
    restored.advance_to(0.2).unwrap();
    assert_eq!(restored.to_bytes(), sim.to_bytes());
    // A body code out of range is refused by name.
    let mut config = ByteWriter::default();
    sim.config.write(&mut config);
    let mut wrong = bytes.clone();
    put(&mut wrong, config.bytes.len() - 16, 7);
    let e = Simulator::from_bytes(&wrong).unwrap_err().to_string();
    assert!(e.contains("body"), "{e}");
}
