use super::*;
use std::collections::VecDeque;

#[test]
fn a_sampled_road_reports_its_last_sample_and_holds_it() {
    let spec = RoadSpec::Samples(Arc::new(vec![(0.0, 0.0), (1.0, 0.02), (2.5, -0.01)]));
    assert_eq!(spec.last_sample(), Some((2.5, -0.01)));
    let mut road = Road::new(&spec, 0.0).unwrap();
    assert_eq!(road.value(2.5), -0.01);
    assert_eq!(road.value(40.0), -0.01);
    assert_eq!(RoadSpec::paper_harmonic().last_sample(), None);
}

#[test]
fn road_type_codes_round_trip() {
    let specs = [
        RoadSpec::Input,
        RoadSpec::paper_harmonic(),
        RoadSpec::Iso8608(RandomRoad::default()),
        RoadSpec::PaperCompatible {
            road: RandomRoad::default(),
            sample_interval: 0.1,
        },
        RoadSpec::Samples(Arc::new(vec![(0.0, 0.0), (1.0, 0.0)])),
    ];
    for (code, spec) in specs.iter().enumerate() {
        let road_type = spec.road_type();
        assert_eq!(road_type.code(), code as i64, "{}", spec.kind());
        assert_eq!(RoadType::from_code(code as i64), Some(road_type));
    }
    assert_eq!(RoadType::from_code(5), None);
    assert_eq!(RoadType::from_code(-1), None);
}

#[test]
fn class_roughness_follows_iso8608() {
    assert_eq!(RoadClass::A.roughness(), 16e-6);
    assert_eq!(RoadClass::C.roughness(), 256e-6);
    assert_eq!(RoadClass::H.roughness(), 262144e-6);
    assert_eq!(RoadClass::from_code(3).unwrap(), RoadClass::C);
    assert!(RoadClass::from_code(9).is_err());
    assert_eq!("c".parse::<RoadClass>().unwrap(), RoadClass::C);
}

#[test]
fn same_seed_same_road_whatever_the_query_order() {
    let spec = RoadSpec::Iso8608(RandomRoad::default());
    let mut forward = Road::new(&spec, 0.0).unwrap();
    let mut jumping = Road::new(&spec, 0.0).unwrap();
    let times: Vec<f64> = (0..2000).map(|i| i as f64 * 0.00137).collect();
    let a: Vec<f64> = times.iter().map(|&t| forward.value(t)).collect();
    assert_eq!(jumping.value(2.5), forward.value(2.5));
    let b: Vec<f64> = times.iter().map(|&t| jumping.value(t)).collect();
    assert_eq!(a, b);
    assert_eq!(a[0], 0.0);
    let other = RoadSpec::Iso8608(RandomRoad {
        seed: 2,
        ..RandomRoad::default()
    });
    let mut other = Road::new(&other, 0.0).unwrap();
    assert_ne!(other.value(1.0), a[730]);
}

#[test]
fn released_nodes_do_not_change_later_values() {
    let spec = RoadSpec::PaperCompatible {
        road: RandomRoad::default(),
        sample_interval: 0.1,
    };
    let mut kept = Road::new(&spec, 0.0).unwrap();
    let mut pruned = Road::new(&spec, 0.0).unwrap();
    for i in 0..300 {
        let t = i as f64 * 0.05;
        assert_eq!(kept.value(t), pruned.value(t));
        pruned.release_before(t);
    }
}

#[test]
fn saved_state_continues_identically() {
    let spec = RoadSpec::Iso8608(RandomRoad::default());
    let mut road = Road::new(&spec, 0.0).unwrap();
    road.value(3.0);
    road.release_before(2.0);
    let saved = road.dynamic_state();
    let mut restored = Road::new(&spec, 0.0).unwrap();
    restored.restore_dynamic_state(&saved, 2.0, 3.0).unwrap();
    for i in 0..100 {
        let t = 2.0 + i as f64 * 0.037;
        assert_eq!(road.value(t), restored.value(t));
    }
}

#[test]
fn a_reserved_window_holds_the_nodes_of_its_span_without_growing() {
    let spec = RoadSpec::Iso8608(RandomRoad::default());
    let mut road = Road::new(&spec, 0.0).unwrap();
    road.value(3.0);
    road.release_before(2.9995);
    // A restored road comes with room for its few nodes only.
    let saved = road.dynamic_state();
    let mut restored = Road::new(&spec, 0.0).unwrap();
    restored.restore_dynamic_state(&saved, 2.9995, 3.0).unwrap();
    let RoadKind::Nodes(nodes) = &restored.kind else {
        panic!("an ISO 8608 road has nodes")
    };
    assert!(nodes.nodes.capacity() < 64, "{}", nodes.nodes.capacity());
    let span = 0.2; // 200 nodes of 1 ms
    restored.reserve_window(span);
    let RoadKind::Nodes(nodes) = &restored.kind else {
        unreachable!()
    };
    let room = nodes.nodes.capacity();
    assert!(room >= 208, "{room}");
    // Sliding a window of `span` along the road, releasing behind it,
    // never needs more room.
    for i in 0..2000 {
        let t = 3.0 + i as f64 * 1e-3;
        restored.release_before(t - 0.5 * span);
        restored.value(t + 0.5 * span);
        let RoadKind::Nodes(nodes) = &restored.kind else {
            unreachable!()
        };
        assert_eq!(nodes.nodes.capacity(), room, "at t = {t}");
    }
    // Degenerate spans reserve the default window.
    for span in [f64::NAN, -1.0, f64::INFINITY] {
        let mut fresh = Road::new(&spec, 0.0).unwrap();
        fresh.reserve_window(span);
        let RoadKind::Nodes(nodes) = &fresh.kind else {
            unreachable!()
        };
        assert!(nodes.nodes.capacity() >= NODE_WINDOW);
        assert!(nodes.nodes.capacity() <= MAX_RESERVED_NODES + NODE_MARGIN + 1);
    }
}

/// Asserts that `piece` is finite and its `[start, end)` holds `t`.
fn holds(piece: RoadPiece, t: f64) {
    let RoadPiece::Linear {
        start,
        end,
        value,
        slope,
    } = piece
    else {
        panic!("{piece:?}")
    };
    assert!(start <= t && t < end, "{t} not in {piece:?}");
    assert!(value.is_finite() && slope.is_finite(), "{piece:?}");
}

#[test]
fn piece_lookup_is_bounded_at_huge_times() {
    // Node indices beyond u64::MAX (the estimate saturates) and beyond
    // MAX_NODE: the road holds the value of node MAX_NODE. The nodes
    // before it are skipped as in a restored road.
    let mut nodes = NodeSequence::new(0.0, 1e-3, 0.9, 0.1, 1);
    nodes.first = MAX_NODE - 1;
    nodes.nodes = VecDeque::from([0.1, 0.2]);
    for t in [1e17, 1e30, f64::MAX, f64::INFINITY] {
        let piece = nodes.piece(t);
        assert_eq!(piece.slope(t), 0.0, "{t}");
        assert_eq!(piece.value(nodes.node_time(MAX_NODE)), 0.2, "{t}");
        assert_eq!(piece.end(), f64::INFINITY);
        assert_eq!(nodes.index_at(t), MAX_NODE);
    }
    holds(nodes.piece(1e17), 1e17);
    holds(nodes.piece(1e13), 1e13);
    assert_eq!(nodes.index_at(f64::NAN), 0);
    assert_eq!(nodes.index_at(-1e300), 0);
}

#[test]
fn piece_lookup_is_bounded_where_nodes_share_one_time() {
    // From 1e15 s on, floats are 0.125 s apart: about 6e10 nodes
    // 1e-12 s apart have the time 1e15 (node_time(n) == node_time(n + 1)),
    // which a scan one node at a time would walk through.
    let mut nodes = NodeSequence::new(1e15, 1e-12, 0.9, 0.1, 1);
    let t = 1e15;
    let n = nodes.index_at(t);
    assert!(n > 50_000_000_000 && n < MAX_NODE, "{n}");
    assert!(nodes.node_time(n) <= t && nodes.node_time(n + 1) > t);
    assert_eq!(nodes.node_time(n - 1), nodes.node_time(n));
    for t in [t + 0.125, t + 0.25, t + 1e3] {
        let m = nodes.index_at(t);
        assert!(nodes.node_time(m) <= t && nodes.node_time(m + 1) > t, "{t}");
    }
    // The piece holding t, from a road restored at node n; from a road
    // restored after it, the first piece kept.
    nodes.first = n;
    nodes.nodes = VecDeque::from([0.1, 0.2]);
    holds(nodes.piece(t), t);
    nodes.first = 1 << 40;
    let RoadPiece::Linear { start, value, .. } = nodes.piece(t) else {
        unreachable!()
    };
    assert_eq!((start, value), (nodes.node_time(1 << 40), 0.1));
}

#[test]
fn samples_interpolate_linearly_and_hold_outside() {
    let spec = RoadSpec::Samples(Arc::new(vec![(0.0, 0.0), (1.0, 0.1), (2.0, -0.1)]));
    let mut road = Road::new(&spec, 0.0).unwrap();
    assert!((road.value(0.5) - 0.05).abs() < 1e-15);
    assert!((road.value(1.5) - 0.0).abs() < 1e-15);
    assert_eq!(road.value(5.0), -0.1);
    assert_eq!(road.value(-1.0), 0.0);
    assert_eq!(road.piece(0.5).end(), 1.0);
}

#[test]
fn bad_roads_are_refused_with_the_variable_name() {
    let bad = RoadSpec::Iso8608(RandomRoad {
        speed: -1.0,
        ..RandomRoad::default()
    });
    let err = Road::new(&bad, 0.0).unwrap_err();
    assert!(err.to_string().contains("vehicle_speed"), "{err}");
    let bad = RoadSpec::Samples(Arc::new(vec![(0.0, 0.0), (0.0, 1.0)]));
    assert!(Road::new(&bad, 0.0).is_err());
    let mut harmonic = Road::new(&RoadSpec::paper_harmonic(), 0.0).unwrap();
    assert!(harmonic.set_input(0.0, 1.0, 0.0).is_err());
}

#[test]
fn csv_file_is_read() {
    let dir = std::env::temp_dir().join(format!("tdvass-road-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("road.csv");
    std::fs::write(&path, "t,x_g\n0,0\n0.5,0.01\n1.0,0\n").unwrap();
    let spec = RoadSpec::from_csv_file(path.to_str().unwrap()).unwrap();
    let mut road = Road::new(&spec, 0.0).unwrap();
    assert!((road.value(0.25) - 0.005).abs() < 1e-15);
    std::fs::write(&path, "t,x_g\n0,0\nzero,1\n").unwrap();
    let err = RoadSpec::from_csv_file(path.to_str().unwrap()).unwrap_err();
    assert!(err.to_string().contains("line 3"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The roads a shift applies to: ISO 8608 class C at 20 m/s, the
/// paper-compatible road and a sampled profile.
fn shifted_roads() -> Vec<RoadSpec> {
    let random = RandomRoad {
        class: RoadClass::C,
        speed: 20.0,
        ..RandomRoad::default()
    };
    vec![
        RoadSpec::Iso8608(random),
        RoadSpec::PaperCompatible {
            road: random,
            sample_interval: 0.01,
        },
        RoadSpec::Samples(Arc::new(vec![
            (0.0, 0.0),
            (0.3, 0.02),
            (0.7, -0.01),
            (1.5, 0.005),
        ])),
    ]
}

#[test]
fn a_delayed_road_is_the_road_later_and_a_random_one_zero_before() {
    let (start, delay) = (0.25, 0.13);
    for spec in shifted_roads() {
        let mut road = Road::new(&spec, start).unwrap();
        let shift = RoadShift { delay, phase: 0.0 };
        let mut delayed = Road::with_shift(&spec, start, shift).unwrap();
        for i in 0..4000 {
            let t = start + i as f64 * 4.37e-4;
            let (now, later) = (road.value(t), delayed.value(t + delay));
            assert!(
                (now - later).abs() <= 1e-12 * (1.0 + now.abs()),
                "{spec:?} {t}: {now} {later}"
            );
        }
        if !matches!(spec, RoadSpec::Samples(_)) {
            let mut fresh = Road::with_shift(&spec, start, shift).unwrap();
            for i in 0..130 {
                let t = start + i as f64 * 1e-3;
                assert_eq!(fresh.value(t), 0.0, "{spec:?} at {t}");
                assert_eq!(fresh.piece(t).slope(t), 0.0);
            }
            assert_eq!(fresh.earliest_time(), f64::NEG_INFINITY);
        }
    }
}

#[test]
fn the_shifted_harmonic_road_is_delayed_and_phased_and_unshifted_the_same_bits() {
    let spec = RoadSpec::paper_harmonic();
    let mut plain = Road::new(&spec, 0.0).unwrap();
    let mut unshifted = Road::with_shift(&spec, 0.0, RoadShift::NONE).unwrap();
    let (delay, phase) = (0.13, 0.9);
    let mut shifted = Road::with_shift(&spec, 0.0, RoadShift { delay, phase }).unwrap();
    for i in 0..1000 {
        let t = i as f64 * 3.1e-3;
        assert_eq!(plain.value(t).to_bits(), unshifted.value(t).to_bits());
        let expected = 0.05 * (5.0 * (t - delay) + phase).sin();
        let value = shifted.value(t);
        assert!((value - expected).abs() < 1e-15, "{t}: {value} {expected}");
        let rate = shifted.piece(t).slope(t);
        let expected_rate = 0.25 * (5.0 * (t - delay) + phase).cos();
        assert!(
            (rate - expected_rate).abs() < 1e-14,
            "{t}: {rate} {expected_rate}"
        );
    }
}

#[test]
fn a_shift_that_does_not_apply_is_refused_by_name() {
    let harmonic = RoadSpec::paper_harmonic();
    let iso = shifted_roads().remove(0);
    for (spec, shift, name) in [
        (
            &harmonic,
            RoadShift {
                delay: -0.1,
                phase: 0.0,
            },
            "road_delay",
        ),
        (
            &harmonic,
            RoadShift {
                delay: f64::NAN,
                phase: 0.0,
            },
            "road_delay",
        ),
        (
            &harmonic,
            RoadShift {
                delay: 0.0,
                phase: f64::INFINITY,
            },
            "road_phase",
        ),
        (
            &iso,
            RoadShift {
                delay: 0.1,
                phase: 0.5,
            },
            "road_phase",
        ),
        (
            &RoadSpec::Input,
            RoadShift {
                delay: 0.1,
                phase: 0.0,
            },
            "road_delay",
        ),
    ] {
        let e = Road::with_shift(spec, 0.0, shift).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}
