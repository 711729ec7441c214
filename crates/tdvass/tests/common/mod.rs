//! Helpers shared by the integration tests: an independent reference
//! integrator for the delay equation, a small FFT, and road shorthands.
#![allow(dead_code)]

use tdvass::model::{Plant, State, V_T, X_T};
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};

/// The harmonic road `amplitude sin(angular_frequency t)`.
pub fn harmonic(amplitude: f64, angular_frequency: f64) -> RoadSpec {
    RoadSpec::Harmonic {
        amplitude,
        angular_frequency,
    }
}

/// An ISO 8608 road of `class` at `speed` (m/s), the other settings default.
pub fn iso(class: RoadClass, speed: f64) -> RoadSpec {
    RoadSpec::Iso8608(RandomRoad {
        class,
        speed,
        ..RandomRoad::default()
    })
}

/// The delay in steps of `step` (0 without a delay); the step must divide
/// tau.
fn delay_steps(tau: f64, step: f64) -> usize {
    let m = if tau > 0.0 {
        (tau / step).round() as usize
    } else {
        0
    };
    assert!(
        m == 0 || ((m as f64) * step - tau).abs() < 1e-12 * tau,
        "step must divide tau"
    );
    m
}

/// The cubic Hermite interpolant through `[x0, v0]` at 0 and `[x1, v1]`
/// at h, at offset s.
fn hermite_value([x0, v0, x1, v1]: [f64; 4], h: f64, s: f64) -> f64 {
    let slope = (x1 - x0) / h;
    let c2 = (3.0 * slope - 2.0 * v0 - v1) / h;
    let c3 = (v0 + v1 - 2.0 * slope) / (h * h);
    x0 + s * (v0 + s * (c2 + s * c3))
}

/// Classical RK4 with the method of steps for
/// `X' = A X + b x_t(t − tau) + e x_g(t)`, a constant history X0 for t < 0,
/// and a step that divides tau. Delayed values at half steps come from the
/// cubic Hermite interpolant of the stored (x_t, v_t) nodes (fourth order,
/// like RK4 itself). Returns X at `duration`.
pub fn rk4_method_of_steps(
    plant: &Plant,
    tau: f64,
    x0: State,
    road: impl Fn(f64) -> f64,
    step: f64,
    duration: f64,
) -> State {
    let m = delay_steps(tau, step);
    let n = (duration / step).round() as usize;
    assert!(
        (n as f64 * step - duration).abs() < 1e-9 * duration,
        "step must divide the duration"
    );
    let mut nodes: Vec<[f64; 2]> = Vec::with_capacity(n + 1);
    nodes.push([x0[X_T], x0[V_T]]);
    let delayed = |nodes: &Vec<[f64; 2]>, k: usize, frac: f64, x_now: &State| -> f64 {
        if m == 0 {
            return x_now[X_T];
        }
        if k < m {
            return x0[X_T];
        }
        let [xa, va] = nodes[k - m];
        if frac == 0.0 {
            return xa;
        }
        let [xb, vb] = nodes[k - m + 1];
        hermite_value([xa, va, xb, vb], step, frac * step)
    };
    let mut x = x0;
    for k in 0..n {
        let t = k as f64 * step;
        let f = |x: &State, frac: f64, nodes: &Vec<[f64; 2]>| {
            plant.derivative(x, delayed(nodes, k, frac, x), road(t + frac * step))
        };
        let k1 = f(&x, 0.0, &nodes);
        let k2 = f(&(x + k1 * (step / 2.0)), 0.5, &nodes);
        let k3 = f(&(x + k2 * (step / 2.0)), 0.5, &nodes);
        // The end of the step lies on the next history node.
        let x4 = x + k3 * step;
        let k4 = if m == 0 {
            plant.derivative(&x4, x4[X_T], road(t + step))
        } else {
            plant.derivative(&x4, delayed(&nodes, k + 1, 0.0, &x4), road(t + step))
        };
        x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (step / 6.0);
        nodes.push([x[X_T], x[V_T]]);
    }
    x
}

/// In-place radix-2 FFT of (re, im); the length must be a power of two.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(n.is_power_of_two() && im.len() == n);
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let angle = -2.0 * std::f64::consts::PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (angle * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let (tr, ti) = (re[b] * c - im[b] * s, re[b] * s + im[b] * c);
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
}

/// A small deterministic generator for random step lengths in tests.
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// What [`rk4_unilateral`] measures over a run from t = 0.
#[derive(Debug, Clone, Copy)]
pub struct SwitchedRun {
    /// Time averages `sqrt(∫ y² / T)` of BA, SDD, TDD.
    pub rms: [f64; 3],
    /// The time with the wheel off the road (s).
    pub flight_time: f64,
    /// The number of lift-offs.
    pub lift_offs: u64,
}

/// Classical RK4 at a fixed fine step for the switched delay equation of
/// a unilateral tire: `X' = A X + b x_t(t − tau) + e x_g(t)` with the tire
/// force `k_t (x_g − x_t)` replaced by `max(−W, k_t (x_g − x_t))`, written
/// pointwise in the right-hand side (it is continuous, so RK4 stays
/// accurate to O(h³) per step across a switch, which it does not locate).
/// History as in [`rk4_method_of_steps`], from rest. The RMS integrals
/// are trapezoids over the nodes; the flight time and the lift-offs come
/// from the margin `W/k_t − (x_t − x_g)` at the nodes, its zeros placed
/// by linear interpolation (O(h²)).
pub fn rk4_unilateral(
    plant: &Plant,
    tau: f64,
    weight: f64,
    road: impl Fn(f64) -> f64,
    step: f64,
    duration: f64,
) -> SwitchedRun {
    let k_t = plant.params.k_t;
    let m_t = plant.params.m_t;
    let m = delay_steps(tau, step);
    let n = (duration / step).round() as usize;
    let derivative = |x: &State, delayed: f64, xg: f64| {
        let mut dx = plant.derivative(x, delayed, xg);
        let load = k_t * (xg - x[X_T]);
        dx[V_T] += (load.max(-weight) - load) / m_t;
        dx
    };
    let mut nodes: Vec<[f64; 2]> = Vec::with_capacity(n + 1);
    nodes.push([0.0, 0.0]);
    let delayed = |nodes: &Vec<[f64; 2]>, k: usize, frac: f64, x_now: &State| -> f64 {
        if m == 0 {
            return x_now[X_T];
        }
        if k < m {
            return 0.0;
        }
        let [xa, va] = nodes[k - m];
        if frac == 0.0 {
            return xa;
        }
        let [xb, vb] = nodes[k - m + 1];
        hermite_value([xa, va, xb, vb], step, frac * step)
    };
    let outputs = |x: &State, t: f64| {
        [
            plant.body_acceleration(x),
            x[tdvass::model::X_S] - x[X_T],
            x[X_T] - road(t),
        ]
    };
    let margin = |x: &State, t: f64| weight / k_t - (x[X_T] - road(t));
    let mut x = State::zeros();
    let mut sums = [0.0; 3];
    let mut before = outputs(&x, 0.0);
    let mut margin_before = margin(&x, 0.0);
    let (mut flight_time, mut lift_offs) = (0.0, 0);
    for k in 0..n {
        let t = k as f64 * step;
        let f = |x: &State, frac: f64, nodes: &Vec<[f64; 2]>| {
            derivative(x, delayed(nodes, k, frac, x), road(t + frac * step))
        };
        let k1 = f(&x, 0.0, &nodes);
        let k2 = f(&(x + k1 * (step / 2.0)), 0.5, &nodes);
        let k3 = f(&(x + k2 * (step / 2.0)), 0.5, &nodes);
        let x4 = x + k3 * step;
        let k4 = if m == 0 {
            derivative(&x4, x4[X_T], road(t + step))
        } else {
            derivative(&x4, delayed(&nodes, k + 1, 0.0, &x4), road(t + step))
        };
        x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (step / 6.0);
        nodes.push([x[X_T], x[V_T]]);
        let after = outputs(&x, t + step);
        for i in 0..3 {
            sums[i] += 0.5 * step * (before[i] * before[i] + after[i] * after[i]);
        }
        before = after;
        let margin_after = margin(&x, t + step);
        match (margin_before >= 0.0, margin_after >= 0.0) {
            (true, true) => {}
            (false, false) => flight_time += step,
            (true, false) => {
                lift_offs += 1;
                flight_time += step * margin_after / (margin_after - margin_before);
            }
            (false, true) => {
                flight_time += step * margin_before / (margin_before - margin_after);
            }
        }
        margin_before = margin_after;
    }
    SwitchedRun {
        rms: sums.map(|s| (s / duration).sqrt()),
        flight_time,
        lift_offs,
    }
}
