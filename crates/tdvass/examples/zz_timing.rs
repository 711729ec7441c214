use std::time::Instant;
use tdvass::solver::{SimulationConfig, Simulator};
fn main() {
    let cfg = SimulationConfig::default();
    let n = 200;
    let t = Instant::now();
    let mut choice = None;
    for _ in 0..n {
        choice = Some(Simulator::choose_step(&cfg).unwrap());
    }
    println!(
        "choose_step {:?} us {:?}",
        t.elapsed().as_secs_f64() / n as f64 * 1e6,
        choice
    );
    let c = choice.unwrap();
    let t = Instant::now();
    for _ in 0..n {
        let _ = Simulator::with_choice(cfg.clone(), c).unwrap();
    }
    println!(
        "with_choice {:?} us",
        t.elapsed().as_secs_f64() / n as f64 * 1e6
    );
    let t = Instant::now();
    for _ in 0..n {
        let mut s = Simulator::with_choice(cfg.clone(), c).unwrap();
        s.advance_to(15.0).unwrap();
    }
    println!(
        "run 15 s {:?} us",
        t.elapsed().as_secs_f64() / n as f64 * 1e6
    );
}
