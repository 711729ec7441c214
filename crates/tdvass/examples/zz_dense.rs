use std::time::Instant;
use tdvass::model::Params;
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::{Metrics, SimulationConfig, Simulator};
fn main() {
    let iso = |class, speed| {
        RoadSpec::Iso8608(RandomRoad {
            class,
            speed,
            ..RandomRoad::default()
        })
    };
    let paper = RoadSpec::PaperCompatible {
        road: RandomRoad::default(),
        sample_interval: 0.1,
    };
    let h = |a: f64, w: f64| RoadSpec::Harmonic {
        amplitude: a,
        angular_frequency: w,
    };
    for (name, road, g, tau) in [
        ("h5", h(0.05, 5.0), 5386.0, 2e-4),
        ("h60", h(0.005, 60.0), 5386.0, 2e-4),
        ("h60 t.05", h(0.005, 60.0), 2000.0, 0.05),
        ("h g<0", h(0.05, 5.0), -3000.0, 0.01),
        ("h tau0", h(0.05, 5.0), 5386.0, 0.0),
        ("isoB", iso(RoadClass::B, 10.0), 5386.0, 2e-4),
        ("isoD", iso(RoadClass::D, 30.0), 2528.0, 1.28e-4),
        ("isoE t.02", iso(RoadClass::E, 20.0), 4000.0, 0.02),
        ("isoC .0123", iso(RoadClass::C, 20.0), -2000.0, 0.0123),
        ("paper", paper.clone(), 2528.0, 1.28e-4),
        ("paper .05", paper, 3000.0, 0.05),
    ] {
        let cfg = SimulationConfig {
            metrics: Metrics::Comfort,
            tolerance: 1e-8,
            road,
            params: Params {
                g,
                tau,
                ..Params::default()
            },
            ..SimulationConfig::default()
        };
        let mut sim = Simulator::new(cfg).unwrap();
        let n = 20000;
        let t = Instant::now();
        for i in 1..=n {
            sim.advance_to(2.0 * i as f64 / n as f64).unwrap();
            let _ = sim.outputs();
        }
        println!(
            "{name} h {} : {:.2} us per call",
            sim.grid().step,
            t.elapsed().as_secs_f64() / n as f64 * 1e6
        );
    }
}
