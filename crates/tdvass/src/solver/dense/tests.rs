use super::*;
use crate::model::{Params, Plant, Variant, X_T};
use crate::solver::system::FilterCoupling;
use std::cell::Cell;

thread_local! {
    /// When set, partial steps take the full exponential of the
    /// quantized length (the method this module replaced), as the
    /// reference of the tests.
    pub(in crate::solver) static EXACT: Cell<bool> = const { Cell::new(false) };
}

/// `f` with partial steps by the full exponential.
pub(in crate::solver) fn exactly<T>(f: impl FnOnce() -> T) -> T {
    EXACT.set(true);
    let out = f();
    EXACT.set(false);
    out
}

/// A reproducible stream of numbers in [0, 1).
pub(in crate::solver) struct Lcg(pub(in crate::solver) u64);

impl Lcg {
    pub(in crate::solver) fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The plant matrices of the solver for a variant (with the delayed
/// input), and in flight (the road column moved into X_T's).
fn modes(variant: Variant, params: Params) -> Vec<(Matrix6<f64>, State, State, Plant)> {
    let plant = Plant::new(params, variant).unwrap();
    let mut flight = plant.a;
    for row in 0..6 {
        flight[(row, X_T)] += plant.e[row];
    }
    vec![
        (plant.a, plant.b, plant.e, plant.clone()),
        (flight, plant.b, plant.e, plant.clone()),
    ]
}

/// Largest |entry|, at least `floor`.
fn scale<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>, floor: f64) -> f64 {
    m.abs().max().max(floor)
}

#[test]
fn agrees_with_the_full_exponential_for_random_offsets() {
    let mut random = Lcg(7);
    let cases = [
        (Variant::Tdvass, Params::default(), 5.0, 1e-3),
        (
            Variant::Tdvass,
            Params::with_controller(40000.0, 0.03),
            60.0,
            3.3e-3,
        ),
        (Variant::Pvass, Params::default(), 0.0, 1e-2),
        (Variant::Cs, Params::default(), 20.0, 2e-4),
    ];
    let mut worst: [f64; 2] = [0.0; 2];
    for (variant, params, omega, h) in cases {
        for (a, b, e, plant) in modes(variant, params) {
            let coupling = FilterCoupling::new(&a, &b, &plant);
            let mut dense = DenseOutput::new(&a, &b, &e, omega, h);
            let m = augmented_matrix(&a, &b, &e, omega);
            let full = with_filter_matrix(&m, &coupling);
            for i in 0..400 {
                // Offsets over the whole step, near its ends, and tiny.
                let fraction = match i % 4 {
                    0 => random.next(),
                    1 => 1.0 - random.next() * 1e-6,
                    2 => random.next() * 1e-6,
                    _ => (random.next() * 64.0).floor() / 64.0,
                };
                let key = offset_key(fraction * h, h);
                let z = Augmented::<1>::from_fn(|_, _| 2.0 * random.next() - 1.0);
                let w = Filter::from_fn(|_, _| 2.0 * random.next() - 1.0);
                let sigma = key as f64 / (1u64 << OFFSET_BITS) as f64 * h;
                let exp = expm::precise_exp(&(m * sigma));
                let reference = exp.fixed_rows::<6>(0) * z;
                let got = dense.plant(key, &z);
                // Relative to the size of the terms summed.
                let size = scale(&(exp.fixed_rows::<6>(0).abs() * z.abs()), 1e-300);
                worst[0] = worst[0].max((got - reference).abs().max() / size);
                let mut big = SVector::<f64, WITH_FILTER>::zeros();
                big.fixed_rows_mut::<AUGMENTED>(0).copy_from(&z);
                big.fixed_rows_mut::<WK_STATES>(AUGMENTED).copy_from(&w);
                let exp = expm::precise_exp(&(full * sigma));
                let rows = exp.fixed_rows::<WK_STATES>(AUGMENTED);
                let reference = rows * big;
                let got = dense.filter(key, &z, &w, &coupling);
                let size = scale(&(rows.abs() * big.abs()), 1e-300);
                worst[1] = worst[1].max((got - reference).abs().max() / size);
            }
            eprintln!(
                "{variant:?} ω = {omega} h = {h}: plant n = {} K = {}, filter n = {} K = {}",
                dense.plant.bits,
                dense.plant.order,
                dense.filter.as_ref().unwrap().table.bits,
                dense.filter.as_ref().unwrap().table.order
            );
        }
    }
    eprintln!(
        "largest relative difference: plant {:e}, filter {:e}",
        worst[0], worst[1]
    );
    assert!(worst[0] < 1e-13, "plant: {worst:?}");
    assert!(worst[1] < 1e-13, "filter: {worst:?}");
}

/// Configurations in every delay regime (whole steps, inside the
/// step, folded; none), on a smooth road, a road with breakpoints
/// inside the steps and a sampled one, with the W_k filter, and with
/// the unilateral tire (lifting off on the harmonic road of 70 rad/s).
fn regimes() -> Vec<(&'static str, crate::solver::SimulationConfig)> {
    use crate::model::TireContact;
    use crate::road::{RandomRoad, RoadClass, RoadSpec};
    use crate::solver::{Metrics, SimulationConfig};
    let base = SimulationConfig {
        metrics: Metrics::Comfort,
        initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
        ..SimulationConfig::default()
    };
    let iso = RoadSpec::Iso8608(RandomRoad {
        class: RoadClass::D,
        ..RandomRoad::default()
    });
    let lifting = RoadSpec::Harmonic {
        amplitude: 0.01,
        angular_frequency: 70.0,
    };
    let with = |g: f64, tau: f64, bound: f64, road: &RoadSpec| SimulationConfig {
        params: Params::with_controller(g, tau),
        max_internal_step: bound,
        road: road.clone(),
        ..base.clone()
    };
    let harmonic = RoadSpec::paper_harmonic();
    let unilateral = |config: SimulationConfig| SimulationConfig {
        tire_contact: TireContact::Unilateral,
        ..config
    };
    vec![
        ("whole steps, harmonic", with(5386.0, 2e-4, 1e-4, &harmonic)),
        ("whole steps, ISO D", with(2528.0, 0.02, 0.0, &iso)),
        (
            "inside the step, harmonic",
            with(5386.0, 2e-4, 1e-3, &harmonic),
        ),
        ("inside the step, ISO D", with(2528.0, 1.28e-4, 0.0, &iso)),
        ("folded, harmonic", with(5386.0, 5e-8, 0.0, &harmonic)),
        (
            "CS, paper road",
            SimulationConfig {
                variant: Variant::Cs,
                road: RoadSpec::PaperCompatible {
                    road: RandomRoad::default(),
                    sample_interval: 0.1,
                },
                ..base.clone()
            },
        ),
        (
            "unilateral, inside the step",
            unilateral(with(5386.0, 2e-4, 1e-3, &lifting)),
        ),
        (
            "unilateral, whole steps",
            unilateral(with(20000.0, 0.02, 0.0, &lifting)),
        ),
        (
            "unilateral, folded, ISO D",
            unilateral(with(5386.0, 5e-8, 0.0, &iso)),
        ),
    ]
}

/// Strictly increasing times over `duration`, most of them inside
/// internal steps (random offsets), some a hair off a node.
fn times(random: &mut Lcg, duration: f64) -> Vec<f64> {
    let mut t = 0.0;
    let mut out = Vec::new();
    while t < duration {
        t += match out.len() % 3 {
            0 => random.next() * 7e-3,
            1 => random.next() * 1e-4,
            _ => random.next() * 2e-6,
        } + 1e-9;
        out.push(t);
    }
    out
}

#[test]
fn in_step_points_agree_with_the_full_exponential_in_every_regime() {
    use crate::solver::Simulator;
    let mut random = Lcg(21);
    for (label, config) in regimes() {
        let mut dense = Simulator::new(config.clone()).unwrap();
        let mut exact = exactly(|| Simulator::new(config.clone()).unwrap());
        let stops = times(&mut random, 0.4);
        let (mut states, mut outputs) = (Vec::new(), Vec::new());
        for &t in &stops {
            dense.advance_to(t).unwrap();
            let values = dense.outputs().core_values();
            let (x, reference) = exactly(|| {
                exact.advance_to(t).unwrap();
                (exact.state(), exact.outputs().core_values())
            });
            states.push((dense.state(), x));
            outputs.push((values, reference));
        }
        // Each component against the largest it reaches.
        let worst = |pairs: &[(Vec<f64>, Vec<f64>)]| {
            let n = pairs[0].0.len();
            (0..n)
                .map(|i| {
                    let size = pairs.iter().map(|(_, r)| r[i].abs()).fold(1e-300, f64::max);
                    pairs
                        .iter()
                        .map(|(a, r)| (a[i] - r[i]).abs() / size)
                        .fold(0.0, f64::max)
                })
                .fold(0.0, f64::max)
        };
        let states: Vec<_> = states
            .iter()
            .map(|(a, r)| (a.as_slice().to_vec(), r.as_slice().to_vec()))
            .collect();
        let outputs: Vec<_> = outputs
            .iter()
            .map(|(a, r)| (a.to_vec(), r.to_vec()))
            .collect();
        let (state_error, output_error) = (worst(&states), worst(&outputs));
        let lift_offs = dense.outputs().road_holding.map_or(0, |h| h.lift_off_count);
        eprintln!(
            "{label}: h = {:e}, {} points, lift-offs {lift_offs}: states {state_error:e}, outputs {output_error:e}",
            dense.grid().step,
            stops.len()
        );
        if label.starts_with("unilateral") && !label.contains("ISO") {
            assert!(lift_offs > 0, "{label}: no lift-off");
        }
        assert!(state_error < 1e-12, "{label}: states {state_error:e}");
        assert!(output_error < 1e-12, "{label}: outputs {output_error:e}");
    }
}

#[test]
fn in_step_points_leave_the_nodes_unchanged() {
    use crate::solver::Simulator;
    let mut random = Lcg(5);
    for (label, config) in regimes() {
        let end = 0.4 + 0.37 * random.next() * 1e-3;
        // Straight to the end, and through many points inside steps.
        let mut straight = Simulator::new(config.clone()).unwrap();
        straight.advance_to(end).unwrap();
        let mut stopping = Simulator::new(config.clone()).unwrap();
        for t in times(&mut random, end) {
            if t < end {
                stopping.advance_to(t).unwrap();
                stopping.outputs();
            }
        }
        stopping.advance_to(end).unwrap();
        let bits = |sim: &mut Simulator| {
            let mut v: Vec<f64> = sim.outputs().core_values().to_vec();
            v.extend(sim.trajectory.committed_state.iter());
            v.push(sim.trajectory.committed_time);
            v.push(sim.trajectory.grid_index as f64);
            v.extend(sim.state().iter());
            v.extend(sim.observers.rms.sums_of_squares);
            v.extend(sim.trajectory.committed_filter.iter());
            v.into_iter().map(f64::to_bits).collect::<Vec<_>>()
        };
        assert_eq!(bits(&mut straight), bits(&mut stopping), "{label}");
    }
}

#[test]
fn sin_cos_is_sin_and_cos_to_the_bit() {
    // The contact-loss test takes a road's value and slope from the
    // kept `sin_cos` instead of `sin` and `cos`: the same bits.
    let mut random = Lcg(3);
    for i in 0..100_000 {
        let angle = (random.next() - 0.5) * 10f64.powi(i % 12 - 3);
        let (sin, cos) = crate::math::sin_cos(angle);
        assert_eq!(sin.to_bits(), crate::math::sin(angle).to_bits(), "{angle}");
        assert_eq!(cos.to_bits(), crate::math::cos(angle).to_bits(), "{angle}");
    }
}

#[test]
fn the_order_meets_the_truncation_bound() {
    for theta in [1e-6, 1e-3, 1.0 / 64.0, 1.0 / 16.0, 0.5, 2.0] {
        let k = taylor_order(theta);
        let mut term = 1.0;
        for i in 1..=k + 1 {
            term *= theta / i as f64;
        }
        assert!(
            term / (1.0 - theta / (k + 2) as f64) <= TRUNCATION,
            "{theta}"
        );
        // And the order below does not.
        if k > 1 {
            let lower = term * (k + 1) as f64 / theta;
            assert!(
                lower / (1.0 - theta / (k + 1) as f64) > TRUNCATION,
                "{theta}"
            );
        }
    }
}

#[test]
fn balancing_bounds_the_norm_from_below_and_from_the_plain_norm() {
    let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
    let m = augmented_matrix(&plant.a, &plant.b, &plant.e, 5.0);
    let plain = m.abs().row_sum().max();
    let balanced = balanced_norm(&m);
    // ‖D⁻¹MD‖ is at least the spectral radius and at most the plain norm.
    let radius = m
        .complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max);
    eprintln!("plain {plain:e}, balanced {balanced:e}, spectral radius {radius:e}");
    assert!(balanced <= plain && balanced >= radius * (1.0 - 1e-12));
}

#[test]
fn an_entry_is_the_same_whatever_was_built_before() {
    let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
    let (a, b, e) = (plant.a, plant.b, plant.e);
    let mut first = DenseOutput::new(&a, &b, &e, 5.0, 1e-3);
    let mut second = first.clone();
    let z = Augmented::<1>::from_fn(|i, _| (i as f64 + 1.0).sqrt());
    let keys: Vec<u64> = (0..64)
        .map(|i| (i * 0x002f_5a1c_3b9d) % (1u64 << 40))
        .collect();
    let forward: Vec<_> = keys.iter().map(|&k| first.plant(k, &z)).collect();
    let backward: Vec<_> = keys.iter().rev().map(|&k| second.plant(k, &z)).collect();
    for (f, b) in forward.iter().zip(backward.iter().rev()) {
        assert_eq!(f.map(f64::to_bits), b.map(f64::to_bits));
    }
}
