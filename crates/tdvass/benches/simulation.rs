//! Cost of the simulation core: one internal TDVASS step against the
//! arithmetic floor of a step, and whole 15 s runs of the three variants on
//! the paper's roads. See BENCHMARKS.md for the figures and how to read them.
//! One bench binary on purpose: every ratio is against the floor measured
//! in the same run (hence its length).
//!
//! The floor ratio: `cargo bench --bench simulation -- 'floor ratio'`.
//! Both sides run 1000 internal steps per iteration; divide the reported
//! time by 1000 for the cost of one step.
//!
//! Criterion reports means, which move with the machine load. The published
//! floor-ratio figures are minima, from the min-of-N harness in this file
//! ([`min_of_n`]): the same loops, each timed over 200 batches of 10 000
//! steps, minimum ns per step, the whole repeated 3 times. The tdvass loop
//! uses AVX2 when the CPU has it unless `TDVASS_NO_AVX2` is set, and the
//! process decides once, so the two instruction sets take two runs:
//!
//! ```text
//! cargo bench --bench simulation -- --min-of-n                   # AVX2 tdvass loop
//! TDVASS_NO_AVX2=1 cargo bench --bench simulation -- --min-of-n  # baseline (SSE2) tdvass loop
//! ```
//!
//! Each run prints every loop's min and median-of-3 ns per step and the
//! ratio of the tdvass loop to the fastest floor of its instruction set.
//!
//! The cost of the extra metrics (`SimulationConfig::metrics`): the same
//! min-of-N harness on the default TDVASS case at the three levels, paper
//! (the baseline), road holding, and comfort (the ISO 2631-1 W_k filter),
//! interleaved in one process, and their ratios to the baseline:
//!
//! ```text
//! cargo bench --bench simulation -- --comfort-cost
//! ```
//!
//! (criterion's view of the same: `cargo bench --bench simulation -- 'comfort filter'`).
//!
//! The cost of the unilateral tire: whole 15 s runs (construction
//! included) with the bilateral and the unilateral tire, interleaved in one
//! process, min and median of 15 each, at the paper and the comfort
//! metrics level, on roads without lift-off and on class D, with the ratio
//! of unilateral to bilateral at the same level:
//!
//! ```text
//! cargo bench --bench simulation -- --tire-contact-cost
//! ```

use criterion::{Criterion, Throughput, criterion_group};
use nalgebra::{Matrix6, SMatrix, Vector2, Vector4, Vector6};
use std::hint::black_box;
use std::time::Instant;
use tdvass::model::{PAPER_G2, PAPER_TAU2, Params, Plant, Variant};
use tdvass::road::{RandomRoad, RoadSpec};
use tdvass::solver::expm::precise_exp;
use tdvass::solver::{Metrics, SimulationConfig, Simulator, simulate};

/// Steps per benchmark iteration of the floor-ratio group.
const STEPS: u64 = 1000;

/// The tdvass side of the floor ratio: the default TDVASS case (h = 1e-4,
/// m = 2, harmonic road), advanced `n` internal steps per call by one
/// `advance_to`, so each call does everything a step does.
fn tdvass_steps() -> impl FnMut(u64) {
    // The floor's case: h = 1e-4 s, m = 2 (the bound sets the step; the
    // loop per step is the same at any step the tolerance chooses).
    config_steps(SimulationConfig {
        tolerance: tdvass::solver::accuracy::MAX_TOLERANCE,
        max_internal_step: 1e-4,
        ..SimulationConfig::default()
    })
}

/// `n` internal steps per call of the simulator of `config` by one
/// `advance_to`.
fn config_steps(config: SimulationConfig) -> impl FnMut(u64) {
    let mut sim = Simulator::new(config).unwrap();
    let h = sim.grid().step;
    let mut k = 0u64;
    move |n| {
        k += n;
        sim.advance_to(black_box(k as f64 * h)).unwrap();
    }
}

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

    /// The operators as nalgebra matrices, for [`Floor::steps_nalgebra`].
    fn nalgebra_ops(&self) -> (Matrix6<f64>, SMatrix<f64, 6, 4>, SMatrix<f64, 6, 2>) {
        (
            Matrix6::from_fn(|i, j| self.transition[j][i]),
            SMatrix::<f64, 6, 4>::from_fn(|i, j| self.nodes[j][i]),
            SMatrix::<f64, 6, 2>::from_fn(|i, j| self.harmonic[j][i]),
        )
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
    let mut tdvass = tdvass_steps();
    group.bench_function("tdvass: 1000 internal steps in one advance_to", |b| {
        b.iter(|| tdvass(STEPS))
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
    let ops = floor.nalgebra_ops();
    group.bench_function("floor: 1000 bare steps, nalgebra products", |b| {
        b.iter(|| floor.steps_nalgebra(black_box(STEPS), &ops))
    });
    black_box(floor.x);
    group.finish();
}

/// The extra metrics' cost: 1000 internal steps of the default TDVASS
/// case at each [`Metrics`] level.
fn comfort_filter(c: &mut Criterion) {
    let mut group = c.benchmark_group("comfort filter");
    group.throughput(Throughput::Elements(STEPS));
    for metrics in Metrics::ALL {
        let mut steps = config_steps(SimulationConfig {
            metrics,
            ..SimulationConfig::default()
        });
        group.bench_function(format!("metrics {metrics:?}: 1000 internal steps"), |b| {
            b.iter(|| steps(STEPS))
        });
    }
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
                grid.delay_steps() + 1
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
    comfort_filter,
    internal_step,
    whole_runs,
    communication_steps,
    scaling
);

/// Instruction set a timed loop runs with.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Isa {
    /// The x86-64 baseline (SSE2): what the crate is compiled for.
    Baseline,
    /// Code compiled with `#[target_feature(enable = "avx2")]`.
    Avx2,
}

impl Isa {
    fn label(self) -> &'static str {
        match self {
            Isa::Baseline => "SSE2",
            Isa::Avx2 => "AVX2",
        }
    }
}

/// Batches timed per loop and repetition in the min-of-N harness.
const BATCHES: usize = 200;
/// Internal steps per timed batch.
const BATCH_STEPS: u64 = 10_000;
/// Untimed batches run before each loop's timed batches.
const WARM_UP_BATCHES: usize = 20;
/// Repetitions of the whole measurement.
const REPETITIONS: usize = 3;

/// One loop of the min-of-N harness: `run(n)` advances it `n` steps.
struct TimedLoop {
    name: &'static str,
    isa: Isa,
    run: Box<dyn FnMut(u64)>,
}

/// A floor loop as a [`TimedLoop`] body: `n` steps of `step`, with the
/// step count and the final state passed through `black_box`.
fn floor_loop(mut step: impl FnMut(&mut Floor, u64) + 'static) -> Box<dyn FnMut(u64)> {
    let mut floor = floor_data();
    Box::new(move |n| {
        step(&mut floor, black_box(n));
        black_box(floor.x);
    })
}

/// Which loop the solver runs in this process: the rule of
/// `wide_vectors()` in crates/tdvass/src/solver/kernel.rs (AVX2 when the CPU has it and
/// `TDVASS_NO_AVX2` is not set), which the solver does not export.
fn tdvass_isa() -> Isa {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("TDVASS_NO_AVX2").is_none() {
        return Isa::Avx2;
    }
    Isa::Baseline
}

/// Minimum wall time of one step over [`BATCHES`] batches of
/// [`BATCH_STEPS`] steps, in ns, after [`WARM_UP_BATCHES`] untimed batches.
fn min_ns_per_step(run: &mut dyn FnMut(u64)) -> f64 {
    for _ in 0..WARM_UP_BATCHES {
        run(BATCH_STEPS);
    }
    (0..BATCHES)
        .map(|_| {
            let start = Instant::now();
            run(BATCH_STEPS);
            start.elapsed().as_nanos() as f64 / BATCH_STEPS as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// The min-of-N measurement behind the published floor ratio: the loops of
/// the 'floor ratio' group (tdvass and each floor; the AVX2 floor only if
/// the CPU has AVX2), each timed by [`min_ns_per_step`], the whole repeated
/// [`REPETITIONS`] times. Prints, per loop, the minimum of the repetitions'
/// minima and their median, then the ratio of the tdvass loop to the
/// fastest floor of the instruction set the tdvass loop used.
fn min_of_n() {
    let tdvass_isa = tdvass_isa();
    let mut loops = vec![
        TimedLoop {
            name: "tdvass: advance_to",
            isa: tdvass_isa,
            run: Box::new(tdvass_steps()),
        },
        TimedLoop {
            name: "floor: sequential sums",
            isa: Isa::Baseline,
            run: floor_loop(Floor::steps_sequential),
        },
        TimedLoop {
            name: "floor: pairwise sums",
            isa: Isa::Baseline,
            run: floor_loop(Floor::steps_pairwise),
        },
        TimedLoop {
            name: "floor: nalgebra products",
            isa: Isa::Baseline,
            run: {
                let ops = floor_data().nalgebra_ops();
                floor_loop(move |floor, n| floor.steps_nalgebra(n, &ops))
            },
        },
    ];
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        loops.push(TimedLoop {
            name: "floor: pairwise sums, AVX2",
            isa: Isa::Avx2,
            // SAFETY: the CPU supports AVX2.
            run: floor_loop(|floor, n| unsafe { floor.steps_pairwise_avx2(n) }),
        });
    }

    // minima[loop][repetition], the loops interleaved within a repetition.
    let mut minima = vec![Vec::new(); loops.len()];
    for _ in 0..REPETITIONS {
        for (timed, mins) in loops.iter_mut().zip(&mut minima) {
            mins.push(min_ns_per_step(&mut timed.run));
        }
    }
    // (min, median) of each loop's repetition minima.
    let stats: Vec<(f64, f64)> = minima
        .into_iter()
        .map(|mut mins| {
            mins.sort_by(f64::total_cmp);
            (mins[0], mins[mins.len() / 2])
        })
        .collect();

    println!(
        "min of {REPETITIONS} x {BATCHES} batches of {BATCH_STEPS} steps \
         ({WARM_UP_BATCHES} warm-up batches), ns per internal step"
    );
    println!(
        "tdvass loop instruction set: {} (TDVASS_NO_AVX2 {})",
        tdvass_isa.label(),
        if std::env::var_os("TDVASS_NO_AVX2").is_some() {
            "set"
        } else {
            "unset"
        }
    );
    println!();
    println!(
        "{:<28} {:>4} {:>9} {:>12}",
        "loop", "isa", "min", "median of 3"
    );
    for (timed, (min, median)) in loops.iter().zip(&stats) {
        println!(
            "{:<28} {:>4} {min:>9.2} {median:>12.2}",
            timed.name,
            timed.isa.label()
        );
    }
    println!();
    // loops[0] is the tdvass loop, the others are floors. Fastest floor of
    // the tdvass loop's instruction set, by each statistic:
    let (tdvass_min, tdvass_median) = stats[0];
    let fastest = |stat: fn(&(f64, f64)) -> f64| {
        loops
            .iter()
            .zip(&stats)
            .skip(1)
            .filter(|(timed, _)| timed.isa == tdvass_isa)
            .map(|(timed, s)| (timed.name, stat(s)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("a floor for every instruction set")
    };
    let (min_floor, min_ns) = fastest(|s| s.0);
    let (median_floor, median_ns) = fastest(|s| s.1);
    println!(
        "ratio tdvass / fastest {} floor: {:.2} (min; {min_floor}), {:.2} (median of 3; {median_floor})",
        tdvass_isa.label(),
        tdvass_min / min_ns,
        tdvass_median / median_ns
    );
}

/// The extra metrics' cost per internal step: the default TDVASS case
/// (harmonic road, h = 1e-4 s, m = 2) at each [`Metrics`] level, each
/// timed by [`min_ns_per_step`] within every repetition, the whole
/// repeated [`REPETITIONS`] times; also on the ISO 8608 class C road with
/// (g2, tau2), whose steps are split by road breakpoints. Prints the min
/// and median-of-3 ns per step of each level and its ratio (of the minima)
/// to [`Metrics::Paper`] measured in the same run.
fn comfort_cost() {
    let iso = SimulationConfig {
        params: Params::with_controller(PAPER_G2, PAPER_TAU2),
        road: RoadSpec::Iso8608(RandomRoad::default()),
        ..SimulationConfig::default()
    };
    let cases = [
        ("TDVASS harmonic (g1, tau1)", SimulationConfig::default()),
        ("TDVASS ISO 8608 C (g2, tau2)", iso),
    ];
    println!(
        "min of {REPETITIONS} x {BATCHES} batches of {BATCH_STEPS} steps \
         ({WARM_UP_BATCHES} warm-up batches), ns per internal step, \
         tdvass loop instruction set {}",
        tdvass_isa().label()
    );
    println!();
    println!(
        "{:<30} {:<12} {:>9} {:>12} {:>18}",
        "case", "metrics", "min", "median of 3", "ratio to Paper"
    );
    for (name, config) in cases {
        let mut runs: Vec<Box<dyn FnMut(u64)>> = Metrics::ALL
            .iter()
            .map(|&metrics| {
                Box::new(config_steps(SimulationConfig {
                    metrics,
                    ..config.clone()
                })) as Box<dyn FnMut(u64)>
            })
            .collect();
        let mut minima = vec![Vec::new(); runs.len()];
        for _ in 0..REPETITIONS {
            for (run, mins) in runs.iter_mut().zip(&mut minima) {
                mins.push(min_ns_per_step(run));
            }
        }
        for mins in &mut minima {
            mins.sort_by(f64::total_cmp);
        }
        let median = REPETITIONS / 2;
        let baseline = minima[0][0];
        for (metrics, mins) in Metrics::ALL.iter().zip(&minima) {
            println!(
                "{name:<30} {:<12} {:>9.2} {:>12.2} {:>18.2}",
                format!("{metrics:?}"),
                mins[0],
                mins[median],
                mins[0] / baseline
            );
        }
    }
}

/// Runs of [`tire_contact_cost`] per configuration.
const WHOLE_RUNS: usize = 15;

/// Min and median wall time (ms) of whole 15 s runs of each configuration,
/// interleaved.
fn whole_run_times(configs: &[SimulationConfig]) -> Vec<(f64, f64)> {
    let mut times = vec![Vec::new(); configs.len()];
    for _ in 0..WHOLE_RUNS {
        for (config, samples) in configs.iter().zip(&mut times) {
            let start = Instant::now();
            let summary = simulate(config.clone(), 15.0).expect("the run succeeds");
            black_box(summary);
            samples.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    times
        .into_iter()
        .map(|mut samples| {
            samples.sort_by(f64::total_cmp);
            (samples[0], samples[samples.len() / 2])
        })
        .collect()
}

/// The `--tire-contact-cost` mode (see the module documentation).
fn tire_contact_cost() {
    use tdvass::TireContact;
    let road = |class| {
        RoadSpec::Iso8608(RandomRoad {
            class,
            ..RandomRoad::default()
        })
    };
    let cases = [
        ("TDVASS harmonic (default)", SimulationConfig::default()),
        (
            "PVASS ISO 8608 A",
            SimulationConfig {
                variant: Variant::Pvass,
                road: road(tdvass::road::RoadClass::A),
                ..SimulationConfig::default()
            },
        ),
        (
            "TDVASS ISO 8608 D (lifts off)",
            SimulationConfig {
                params: Params::with_controller(PAPER_G2, PAPER_TAU2),
                road: road(tdvass::road::RoadClass::D),
                ..SimulationConfig::default()
            },
        ),
    ];
    println!("whole 15 s runs, min and median of {WHOLE_RUNS} (ms)");
    println!();
    println!(
        "{:<30} {:<28} {:>8} {:>8} {:>10} {:>10}",
        "case", "tire, metrics", "min", "median", "lift-offs", "ratio"
    );
    for (name, config) in cases {
        let with = |tire_contact, metrics| SimulationConfig {
            tire_contact,
            metrics,
            ..config.clone()
        };
        // Bilateral and unilateral at the paper level (which the
        // unilateral tire raises to road holding: a PSO on J) and at the
        // comfort level (every metric: `simulate`, the FMUs).
        let configs = [
            with(TireContact::Bilateral, Metrics::Paper),
            with(TireContact::Unilateral, Metrics::Paper),
            with(TireContact::Bilateral, Metrics::Comfort),
            with(TireContact::Unilateral, Metrics::Comfort),
        ];
        let times = whole_run_times(&configs);
        for (i, (config, (min, median))) in configs.iter().zip(&times).enumerate() {
            // Counted below road holding too, where the summary has none.
            let lift_offs = simulate(
                SimulationConfig {
                    metrics: Metrics::Comfort,
                    ..config.clone()
                },
                15.0,
            )
            .expect("the run succeeds")
            .road_holding
            .map_or(0, |holding| holding.lift_off_count);
            let ratio = if i % 2 == 1 {
                format!("{:.2}", min / times[i - 1].0)
            } else {
                String::new()
            };
            println!(
                "{name:<30} {:<28} {min:>8.2} {median:>8.2} {lift_offs:>10} {ratio:>10}",
                format!("{:?}, {:?}", config.tire_contact, config.metrics),
            );
        }
    }
    println!();
    println!("ratio: unilateral min / bilateral min at the same metrics level");
}

/// `criterion_main!(benches)` plus the min-of-N modes: with `--min-of-n`
/// among the arguments, runs [`min_of_n`], with `--comfort-cost`
/// [`comfort_cost`], instead of criterion.
fn main() {
    if std::env::args().any(|arg| arg == "--min-of-n") {
        min_of_n();
        return;
    }
    if std::env::args().any(|arg| arg == "--comfort-cost") {
        comfort_cost();
        return;
    }
    if std::env::args().any(|arg| arg == "--tire-contact-cost") {
        tire_contact_cost();
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
