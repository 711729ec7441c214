//! Cost of the simulation core: one internal TDVASS step against the
//! arithmetic floor of a step, and whole 15 s runs of the three variants on
//! the paper's roads. See BENCHMARKS.md for the figures and how to read them.
//!
//! The floor ratio: `cargo bench --bench simulation -- 'floor ratio'`.
//! Both sides run 1000 internal steps per iteration; divide the reported
//! time by 1000 for the cost of one step.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::{Matrix6, SMatrix, Vector2, Vector4, Vector6};
use std::hint::black_box;
use tdvass::model::{PAPER_G2, PAPER_TAU2, Params, Plant, Variant};
use tdvass::road::{RandomRoad, RoadSpec};
use tdvass::solver::expm::precise_exp;
use tdvass::solver::{SimulationConfig, Simulator, simulate};

/// Steps per benchmark iteration of the floor-ratio group.
const STEPS: u64 = 1000;

/// The unavoidable arithmetic of one internal step of Eq. (23) on the same
/// data layout as the solver's whole-step loop (column arrays): the 6×6
/// transition times the state, plus the delayed input (6×4 times the two
/// history nodes read from a ring of m + 1 slots) and the harmonic road
/// (6×2 times a road phase read from a table), and the new node written
/// back to the ring. No road evaluation, RMS, divergence check or time
/// bookkeeping: that is the overhead the ratio measures.
struct Floor {
    transition: [[f64; 6]; 6],
    nodes: [[f64; 6]; 4],
    harmonic: [[f64; 6]; 2],
    ring: Vec<[f64; 2]>,
    phases: Vec<[f64; 2]>,
    slot: usize,
    x: [f64; 6],
}

/// Exact operators of the default TDVASS step (h = 1e-4, m = 2), from the
/// same augmented exponential as the solver, so the numbers are realistic.
fn floor_data() -> Floor {
    let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
    let h = 1e-4;
    let mut m = SMatrix::<f64, 14, 14>::zeros();
    m.fixed_view_mut::<6, 6>(0, 0).copy_from(&plant.a);
    m.fixed_view_mut::<6, 1>(0, 6).copy_from(&plant.b);
    for i in 0..3 {
        m[(6 + i, 7 + i)] = 1.0;
    }
    m.fixed_view_mut::<6, 1>(0, 12).copy_from(&plant.e);
    m[(12, 13)] = 5.0;
    m[(13, 12)] = -5.0;
    let e = precise_exp(&(m * h));
    let cols = |c0: usize, n: usize| -> Vec<[f64; 6]> {
        (c0..c0 + n)
            .map(|j| std::array::from_fn(|i| e[(i, j)]))
            .collect()
    };
    let phases = (0..1024)
        .map(|k| {
            let (s, c) = (5.0 * k as f64 * h).sin_cos();
            [0.05 * s, 0.05 * c]
        })
        .collect();
    Floor {
        transition: cols(0, 6).try_into().unwrap(),
        nodes: cols(6, 4).try_into().unwrap(),
        harmonic: cols(12, 2).try_into().unwrap(),
        ring: vec![[0.0; 2]; 3],
        phases,
        slot: 1,
        x: [0.0; 6],
    }
}

impl Floor {
    /// Sequential accumulation, column after column.
    #[inline(never)]
    fn steps_sequential(&mut self, n: u64) {
        let len = self.ring.len();
        let mut x = self.x;
        let mut slot = self.slot;
        for k in 0..n as usize {
            let next = if slot + 1 == len { 0 } else { slot + 1 };
            let [x0, v0] = self.ring[slot];
            let [x1, v1] = self.ring[next];
            let nodes = [x0, v0, x1, v1];
            let z = self.phases[k & 1023];
            let mut y = [0.0; 6];
            for (col, xj) in self.transition.iter().zip(x) {
                for i in 0..6 {
                    y[i] += col[i] * xj;
                }
            }
            for (col, p) in self.nodes.iter().zip(nodes) {
                for i in 0..6 {
                    y[i] += col[i] * p;
                }
            }
            for (col, p) in self.harmonic.iter().zip(z) {
                for i in 0..6 {
                    y[i] += col[i] * p;
                }
            }
            self.ring[slot] = [y[4], y[5]];
            x = y;
            slot = next;
        }
        self.x = x;
        self.slot = slot;
    }

    /// Pairwise (tree) summation, as the solver's loop does it.
    #[inline(never)]
    fn steps_pairwise(&mut self, n: u64) {
        self.pairwise(n)
    }

    /// [`Floor::steps_pairwise`] compiled for AVX2, as the solver's loop is
    /// where the CPU has it.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn steps_pairwise_avx2(&mut self, n: u64) {
        self.pairwise(n)
    }

    #[inline(always)]
    fn pairwise(&mut self, n: u64) {
        let len = self.ring.len();
        let mut x = self.x;
        let mut slot = self.slot;
        for k in 0..n as usize {
            let next = if slot + 1 == len { 0 } else { slot + 1 };
            let [x0, v0] = self.ring[slot];
            let [x1, v1] = self.ring[next];
            let z = self.phases[k & 1023];
            let (t, u, h) = (&self.transition, &self.nodes, &self.harmonic);
            let y: [f64; 6] = std::array::from_fn(|i| {
                let fx = ((t[0][i] * x[0] + t[1][i] * x[1]) + (t[2][i] * x[2] + t[3][i] * x[3]))
                    + (t[4][i] * x[4] + t[5][i] * x[5]);
                let inputs = ((u[0][i] * x0 + u[1][i] * v0) + (u[2][i] * x1 + u[3][i] * v1))
                    + (h[0][i] * z[0] + h[1][i] * z[1]);
                fx + inputs
            });
            self.ring[slot] = [y[4], y[5]];
            x = y;
            slot = next;
        }
        self.x = x;
        self.slot = slot;
    }

    /// The same arithmetic written with nalgebra's fixed-size products.
    #[inline(never)]
    fn steps_nalgebra(
        &mut self,
        n: u64,
        ops: &(Matrix6<f64>, SMatrix<f64, 6, 4>, SMatrix<f64, 6, 2>),
    ) {
        let len = self.ring.len();
        let mut x = Vector6::from(self.x);
        let mut slot = self.slot;
        for k in 0..n as usize {
            let next = if slot + 1 == len { 0 } else { slot + 1 };
            let [x0, v0] = self.ring[slot];
            let [x1, v1] = self.ring[next];
            let z = self.phases[k & 1023];
            let y = ops.0 * x + ops.1 * Vector4::new(x0, v0, x1, v1) + ops.2 * Vector2::from(z);
            self.ring[slot] = [y[4], y[5]];
            x = y;
            slot = next;
        }
        self.x = x.into();
        self.slot = slot;
    }
}

fn floor_ratio(c: &mut Criterion) {
    let mut group = c.benchmark_group("floor ratio");
    group.throughput(Throughput::Elements(STEPS));
    let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
    let h = sim.grid().step;
    let mut k = 0u64;
    group.bench_function("tdvass: 1000 internal steps in one advance_to", |b| {
        b.iter(|| {
            k += STEPS;
            sim.advance_to(black_box(k as f64 * h)).unwrap();
        })
    });
    let mut floor = floor_data();
    group.bench_function("floor: 1000 bare steps, sequential sums", |b| {
        b.iter(|| floor.steps_sequential(black_box(STEPS)))
    });
    black_box(floor.x);
    let mut floor = floor_data();
    group.bench_function("floor: 1000 bare steps, pairwise sums", |b| {
        b.iter(|| floor.steps_pairwise(black_box(STEPS)))
    });
    black_box(floor.x);
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        let mut floor = floor_data();
        group.bench_function("floor: 1000 bare steps, pairwise sums, AVX2", |b| {
            // SAFETY: the CPU supports AVX2.
            b.iter(|| unsafe { floor.steps_pairwise_avx2(black_box(STEPS)) })
        });
        black_box(floor.x);
    }
    let mut floor = floor_data();
    let ops = (
        Matrix6::from_fn(|i, j| floor.transition[j][i]),
        SMatrix::<f64, 6, 4>::from_fn(|i, j| floor.nodes[j][i]),
        SMatrix::<f64, 6, 2>::from_fn(|i, j| floor.harmonic[j][i]),
    );
    group.bench_function("floor: 1000 bare steps, nalgebra products", |b| {
        b.iter(|| floor.steps_nalgebra(black_box(STEPS), &ops))
    });
    black_box(floor.x);
    group.finish();
}

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

/// 15 s in 1 ms communication steps with every output read at each point:
/// the library side of the FMU route (benches/fmu_overhead.py).
fn communication_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("15 s in 1 ms communication steps");
    group.sample_size(20);
    group.bench_function("advance_to + outputs every 1 ms", |b| {
        b.iter(|| {
            let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
            let mut sum = 0.0;
            for i in 1..=15000 {
                sim.advance_to(i as f64 * 1e-3).unwrap();
                sum += sim.outputs().objective;
            }
            black_box(sum)
        })
    });
    group.finish();
}

/// Cost against simulated duration, delay and number of parallel runs.
fn scaling(c: &mut Criterion) {
    let mut group = c.benchmark_group("scaling: duration");
    group.sample_size(10);
    for duration in [1.0, 4.0, 16.0, 64.0] {
        group.bench_function(format!("TDVASS harmonic {duration} s"), |b| {
            b.iter(|| simulate(SimulationConfig::default(), black_box(duration)).unwrap())
        });
    }
    group.finish();
    // g = 1000 N/m is stable whatever the delay (below the delay-independent
    // bound), so every tau runs the full 15 s.
    let mut group = c.benchmark_group("scaling: tau");
    group.sample_size(10);
    for tau in [1e-5, 5e-5, 1e-4, 2e-4, 2e-3, 2e-2, 0.2, 0.5] {
        let config = SimulationConfig {
            params: Params::with_controller(1000.0, tau),
            ..SimulationConfig::default()
        };
        let grid = Simulator::new(config.clone()).unwrap().grid();
        group.bench_function(
            format!(
                "15 s, tau {tau:e} (h {:e}, {} history nodes)",
                grid.step,
                grid.delay_steps + 1
            ),
            |b| b.iter(|| simulate(black_box(config.clone()), 15.0).unwrap()),
        );
    }
    group.finish();
    let mut group = c.benchmark_group("scaling: 16 runs of 15 s");
    group.sample_size(10);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_function(format!("{threads} thread(s)"), |b| {
            b.iter(|| {
                pool.install(|| {
                    use rayon::prelude::*;
                    (0..16)
                        .into_par_iter()
                        .map(|i| {
                            let config = SimulationConfig {
                                params: Params::with_controller(5000.0 + i as f64, 2e-4),
                                ..SimulationConfig::default()
                            };
                            simulate(config, 15.0).unwrap().objective
                        })
                        .sum::<f64>()
                })
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    floor_ratio,
    internal_step,
    whole_runs,
    communication_steps,
    scaling
);
criterion_main!(benches);
