//! A piece of road over which `x_g` has a closed form (a sine or a straight
//! line), and the piece of sampled profile at a time.

/// A piece of road over which `x_g` has a closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RoadPiece {
    /// `x_g(t) = amplitude sin(angular_frequency t + phase)` for every t
    /// ([`harmonic_angle`]).
    Harmonic {
        amplitude: f64,
        angular_frequency: f64,
        phase: f64,
    },
    /// `x_g(t) = value + slope (t − start)` on `[start, end)`.
    Linear {
        start: f64,
        end: f64,
        value: f64,
        slope: f64,
    },
}

impl RoadPiece {
    /// `x_g(t)` (m).
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
                phase,
            } => amplitude * crate::math::sin(harmonic_angle(angular_frequency, phase, t)),
            RoadPiece::Linear {
                start,
                value,
                slope,
                ..
            } => value + slope * (t - start),
        }
    }

    /// `dx_g/dt` (m/s).
    #[inline]
    pub fn slope(&self, t: f64) -> f64 {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
                phase,
            } => {
                let angle = harmonic_angle(angular_frequency, phase, t);
                amplitude * angular_frequency * crate::math::cos(angle)
            }
            RoadPiece::Linear { slope, .. } => slope,
        }
    }

    /// `[x_g, x_g', x_g'', x_g''']` at t (m, m/s, m/s², m/s³): of the
    /// harmonic piece `A sin(ω t + φ)` (its sine and cosine from one
    /// [`crate::math::sin_cos`]), of a linear piece its value and slope.
    #[inline]
    pub fn derivatives(&self, t: f64) -> [f64; 4] {
        match *self {
            RoadPiece::Harmonic {
                amplitude: a,
                angular_frequency: w,
                phase,
            } => {
                let (sin, cos) = crate::math::sin_cos(harmonic_angle(w, phase, t));
                [a * sin, a * w * cos, -a * w * w * sin, -a * w * w * w * cos]
            }
            RoadPiece::Linear { .. } => [self.value(t), self.slope(t), 0.0, 0.0],
        }
    }

    /// Bounds of `|x_g|, |x_g'|, |x_g''|, |x_g'''|` over the piece from t
    /// on (the harmonic piece's `|A| |ω|^j`; a linear piece's value at t
    /// and its slope).
    #[inline]
    pub fn derivative_bounds(&self, t: f64) -> [f64; 4] {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
                ..
            } => {
                let (a, w) = (amplitude.abs(), angular_frequency.abs());
                [a, a * w, a * w * w, a * w * w * w]
            }
            RoadPiece::Linear { .. } => [self.value(t).abs(), self.slope(t).abs(), 0.0, 0.0],
        }
    }

    /// End of the piece's validity (`+inf` for the harmonic road).
    #[inline]
    pub fn end(&self) -> f64 {
        match *self {
            RoadPiece::Harmonic { .. } => f64::INFINITY,
            RoadPiece::Linear { end, .. } => end,
        }
    }
}

/// The harmonic road's angle at t (rad): `ω t + φ`; `ω t` itself with no
/// phase (the same bits as a road without one).
#[inline(always)]
pub fn harmonic_angle(angular_frequency: f64, phase: f64, t: f64) -> f64 {
    let angle = angular_frequency * t;
    if phase == 0.0 { angle } else { angle + phase }
}

/// The piece of the sampled profile `samples` whose interval holds `t`
/// (the first sample's value held before it, the last one's after it).
pub(super) fn sample_piece(samples: &[(f64, f64)], t: f64) -> RoadPiece {
    let after = samples.partition_point(|&(ts, _)| ts <= t);
    if after == 0 {
        let (t0, x0) = samples[0];
        return RoadPiece::Linear {
            start: t0,
            end: t0,
            value: x0,
            slope: 0.0,
        };
    }
    let (t0, x0) = samples[after - 1];
    match samples.get(after) {
        Some(&(t1, x1)) => RoadPiece::Linear {
            start: t0,
            end: t1,
            value: x0,
            slope: (x1 - x0) / (t1 - t0),
        },
        None => RoadPiece::Linear {
            start: t0,
            end: f64::INFINITY,
            value: x0,
            slope: 0.0,
        },
    }
}
