//! Cost of the simulation core: one internal TDVASS step and whole 15 s
//! runs of the three variants on the paper's roads.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use tdvass::model::{PAPER_G2, PAPER_TAU2, Params, Variant};
use tdvass::road::{RandomRoad, RoadSpec};
use tdvass::solver::{SimulationConfig, Simulator, simulate};

fn internal_step(c: &mut Criterion) {
    let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
    let h = sim.grid().step;
    let mut k = 0u64;
    c.bench_function("tdvass internal step (harmonic road, tau1)", |b| {
        b.iter(|| {
            k += 1;
            sim.advance_to(black_box(k as f64 * h)).unwrap();
        })
    });
}

fn whole_runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("15 s run from rest");
    group.sample_size(20);
    for variant in Variant::ALL {
        let config = SimulationConfig {
            variant,
            ..SimulationConfig::default()
        };
        group.bench_function(format!("{} harmonic", variant.label()), |b| {
            b.iter(|| simulate(black_box(config.clone()), 15.0).unwrap())
        });
    }
    let paper_road = SimulationConfig {
        params: Params::with_controller(PAPER_G2, PAPER_TAU2),
        road: RoadSpec::PaperCompatible {
            road: RandomRoad::default(),
            sample_interval: 0.1,
        },
        ..SimulationConfig::default()
    };
    group.bench_function("TDVASS paper road (g2, tau2)", |b| {
        b.iter(|| simulate(black_box(paper_road.clone()), 15.0).unwrap())
    });
    let iso_road = SimulationConfig {
        road: RoadSpec::Iso8608(RandomRoad::default()),
        ..paper_road.clone()
    };
    group.bench_function("TDVASS ISO 8608 class C (g2, tau2)", |b| {
        b.iter(|| simulate(black_box(iso_road.clone()), 15.0).unwrap())
    });
    group.finish();
}

criterion_group!(benches, internal_step, whole_runs);
criterion_main!(benches);
