//! Pixel reconstruction filters, sampled by filter importance sampling (pbrt-v4's
//! `FilterSampler`, `src/pbrt/filters.h`): each camera sample's offset from the pixel centre
//! is drawn with density proportional to the filter, so that its weight f / pdf is the
//! filter's integral, the same for every sample, and the pixel's estimate stays a plain mean
//! of its own samples. Its expectation is Mitsuba 3's weight-normalised splatted estimate,
//! the integral of f(x - centre) L(x) over the integral of f. Filters of a radius from half a
//! pixel to [`SPLAT_MAX_RADIUS`] are splatted instead ([`PixelFilter::splats`]), which reaches
//! that expectation with less noise a pixel. The filters are Mitsuba 3's
//! (mitsuba3 `src/rfilters/box.cpp`, `tent.cpp`, `gaussian.cpp`), separable in x and y.
//! Unlike pbrt's tabulated sampler, the Gaussian is sampled exactly (its CDF has a closed
//! form), so the weight is constant to rounding and no weight needs carrying.

/// A pixel filter ready to sample offsets.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[expect(
    clippy::large_enum_variant,
    reason = "held once in the render settings (which are Copy) and read in place, never moved per sample"
)]
pub enum PixelFilter {
    /// Radius 0.5: uniform over the pixel (the offset is the sample number itself).
    #[default]
    Box,
    /// f(x) = max(0, 1 - |x| / radius) per axis.
    Tent {
        /// In pixels.
        radius: f32,
    },
    /// f(x) = max(0, exp(-x^2 / (2 stddev^2)) - exp(-radius^2 / (2 stddev^2))) per axis,
    /// radius = 4 stddev.
    Gaussian(Gaussian),
}

impl PixelFilter {
    /// The 1D filter at `x` pixels from the centre (unnormalised, as Mitsuba's `eval`).
    pub fn eval(&self, x: f32) -> f32 {
        match self {
            PixelFilter::Box => (x.abs() <= 0.5) as u32 as f32,
            PixelFilter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            PixelFilter::Gaussian(g) => g.eval(x as f64) as f32,
        }
    }

    /// The filter as the scene file writes it.
    pub fn describe(&self) -> String {
        match self {
            PixelFilter::Box => "Box".into(),
            PixelFilter::Tent { radius } => format!("Tent(radius: {radius})"),
            PixelFilter::Gaussian(g) => format!("Gaussian(stddev: {})", g.stddev as f32),
        }
    }

    /// How far from the pixel centre samples reach, in pixels.
    pub fn radius(&self) -> f32 {
        match self {
            PixelFilter::Box => 0.5,
            PixelFilter::Tent { radius } => *radius,
            PixelFilter::Gaussian(g) => g.radius as f32,
        }
    }

    /// The 1D filter's integral over its support, in closed form (the Gaussian's from its CDF).
    pub fn integral(&self) -> f64 {
        match self {
            PixelFilter::Box => 1.0,
            PixelFilter::Tent { radius } => *radius as f64,
            PixelFilter::Gaussian(g) => g.total,
        }
    }

    /// The image position of a sample of pixel (x, y) drawn with the numbers `u` in [0, 1)^2:
    /// for the box, (x + u.x, y + u.y), as before filters existed (the same bits); for the
    /// others, the pixel centre plus an offset with density f(dx) f(dy) / (integral)^2.
    #[inline(always)]
    pub fn position(&self, pixel: (u32, u32), u: [f32; 2]) -> [f32; 2] {
        let (x, y) = (pixel.0 as f32, pixel.1 as f32);
        match self {
            PixelFilter::Box => [x + u[0], y + u[1]],
            PixelFilter::Tent { radius } => {
                [x + 0.5 + sample_tent(u[0], *radius), y + 0.5 + sample_tent(u[1], *radius)]
            }
            PixelFilter::Gaussian(g) => [x + 0.5 + g.sample(u[0]), y + 0.5 + g.sample(u[1])],
        }
    }

    /// Whether the film splats this filter's samples: each sample, drawn uniformly over its
    /// pixel as the box's are, is added to every pixel the filter reaches from it, weighed by
    /// the filter there, and a pixel's estimate is its weighted sum over the sum of its weights
    /// (Mitsuba 3's `ImageBlock::put`). Its expectation is the same as sampling the filter's
    /// offsets ([`Self::position`], pbrt-v4's way), but a pixel averages the samples of its
    /// neighbours too: [`Self::splat_gain`] times as many (2.25 for the tent of radius 1,
    /// about 3.1 for the Gaussian of stddev 0.5), at the cost of noise that neighbours share.
    /// Not the box (one pixel, weight 1), nor filters narrower than a pixel (their weights
    /// would leave parts of a pixel out) or wider than [`SPLAT_MAX_RADIUS`] (a sample would
    /// touch too many pixels); those sample their offsets.
    pub fn splats(&self) -> bool {
        let r = self.radius();
        !matches!(self, PixelFilter::Box) && (0.5..=SPLAT_MAX_RADIUS).contains(&r)
    }

    /// Whether camera samples take their offsets from the filter (filter importance sampling):
    /// every filter but the box and those the film splats.
    pub fn samples_offsets(&self) -> bool {
        !matches!(self, PixelFilter::Box) && !self.splats()
    }

    /// How many pixels beyond its own a splatted sample reaches on each side:
    /// ceil(radius - 1/2) (0 where the filter is not splatted).
    pub fn margin(&self) -> u32 {
        match self.splats() {
            true => (self.radius() - 0.5).ceil() as u32,
            false => 0,
        }
    }

    /// The filter ready to splat, where the film splats it.
    pub fn splat(&self) -> Option<Splat> {
        self.splats().then(|| Splat {
            filter: *self,
            margin: self.margin() as i32,
            radius: self.radius(),
            inv_radius: 1.0 / self.radius(),
        })
    }

    /// How many times as many samples a splatted pixel averages as a pixel of its own samples
    /// only: (integral of f)^2 / integral of f^2 over the filter's support, squared for the
    /// two axes (the effective sample count of weights f; 1 where the film does not splat).
    /// It is also how much larger the variance of the image's mean is than the sum of the
    /// pixels' variances, their noise shared with their neighbours.
    pub fn splat_gain(&self) -> f64 {
        if !self.splats() {
            return 1.0;
        }
        let r = self.radius() as f64;
        let n = 100_000;
        let (mut f1, mut f2) = (0.0, 0.0);
        for k in 0..n {
            let f = self.eval((-r + 2.0 * r * (k as f64 + 0.5) / n as f64) as f32) as f64;
            (f1, f2) = (f1 + f, f2 + f * f);
        }
        let g = f1 * f1 / f2 * 2.0 * r / n as f64;
        g * g
    }

    /// The offset from the pixel centre that the numbers `u` give (1D, for tests).
    pub fn sample_1d(&self, u: f32) -> f32 {
        match self {
            PixelFilter::Box => u - 0.5,
            PixelFilter::Tent { radius } => sample_tent(u, *radius),
            PixelFilter::Gaussian(g) => g.sample(u),
        }
    }
}

impl From<crate::scene::FilterDesc> for PixelFilter {
    fn from(d: crate::scene::FilterDesc) -> Self {
        use crate::scene::FilterDesc;
        match d {
            FilterDesc::Box => PixelFilter::Box,
            FilterDesc::Tent { radius } => PixelFilter::Tent { radius },
            FilterDesc::Gaussian { stddev } => PixelFilter::Gaussian(Gaussian::new(stddev)),
        }
    }
}

/// The widest filter the film splats, in pixels: a sample reaches at most
/// (2 ceil(radius - 1/2) + 1)^2 pixels, 81 at this radius; wider filters sample their offsets.
pub const SPLAT_MAX_RADIUS: f32 = 4.0;

/// The most pixels a splatted sample reaches along one axis.
pub const SPLAT_REACH: usize = 9;

/// A filter the film splats ([`PixelFilter::splat`]), with what each sample's weights need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    filter: PixelFilter,
    /// [`PixelFilter::margin`].
    margin: i32,
    /// The filter's radius in pixels.
    radius: f32,
    /// 1 / radius (the tent's slope).
    inv_radius: f32,
}

impl Splat {
    /// The 1D weights of a sample at `u` in [0, 1) across its pixel: the filter at the centres
    /// of the pixels `first..first + n` (offsets from the sample's own pixel), those strictly
    /// within its radius (the tent's slope as a product, not a division). The range comes from
    /// `u` by floor and ceiling, not by testing each weight: those tests, as random as `u`,
    /// were mispredicted half the time.
    #[inline(always)]
    pub fn weights(&self, u: f32) -> SplatWeights {
        let (m, r) = (self.margin, self.radius);
        let first = ((u - 0.5 - r).floor() as i32 + 1).max(-m);
        let last = ((u - 0.5 + r).ceil() as i32 - 1).min(m);
        let mut s = SplatWeights { first, n: (last - first + 1).max(0) as usize, w: [0.0; SPLAT_REACH] };
        for (i, w) in s.w.iter_mut().enumerate().take(s.n) {
            let x = (first + i as i32) as f32 + 0.5 - u;
            *w = match &self.filter {
                PixelFilter::Tent { .. } => (1.0 - x.abs() * self.inv_radius).max(0.0),
                PixelFilter::Gaussian(g) => g.eval_splat(x),
                PixelFilter::Box => (x.abs() <= 0.5) as u32 as f32,
            };
        }
        s
    }
}

/// A splatted sample's weights along one axis ([`Splat::weights`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatWeights {
    /// The offset of the first pixel reached from the sample's own (0 or below).
    pub first: i32,
    /// Pixels reached.
    pub n: usize,
    /// Their weights (the first `n`).
    pub w: [f32; SPLAT_REACH],
}

/// The tent's inverse CDF: density (1 - |x| / r) / r on [-r, r] (pbrt-v4's `SampleTent`).
#[inline(always)]
fn sample_tent(u: f32, r: f32) -> f32 {
    if u < 0.5 { r * ((2.0 * u).sqrt() - 1.0) } else { r * (1.0 - (2.0 - 2.0 * u).max(0.0).sqrt()) }
}

/// Knots of the Gaussian's inverse CDF table (the first guess of [`Gaussian::sample`]).
const KNOTS: usize = 64;

/// Mitsuba 3's windowed Gaussian, with its inverse CDF at `KNOTS + 1` evenly spaced
/// probabilities: sampling interpolates there and refines by Newton steps on the exact CDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    /// Standard deviation in pixels.
    pub stddev: f64,
    /// 4 stddev.
    pub radius: f64,
    /// exp(-radius^2 / (2 stddev^2)), subtracted so that the filter reaches 0 at the radius.
    bias: f64,
    /// The CDF's value at the radius (the filter's integral).
    total: f64,
    /// erf(radius / (stddev sqrt 2)), the CDF's constant term.
    erf_radius: f64,
    /// x where the CDF is k / KNOTS.
    inverse: [f32; KNOTS + 1],
    /// The filter at |x| = radius k / PROFILE, for splatting ([`Self::eval_splat`]).
    profile: [f32; PROFILE + 2],
    /// PROFILE / radius: profile intervals a pixel.
    per_pixel: f32,
}

/// Intervals of the Gaussian's tabulated profile over its radius: linear interpolation is
/// within 1e-5 of the filter's peak (the second derivative is at most 1 / stddev^2, the
/// interval radius / PROFILE = stddev / 128).
const PROFILE: usize = 512;

impl Gaussian {
    /// The filter of standard deviation `stddev` pixels (positive and finite).
    pub fn new(stddev: f32) -> Self {
        let stddev = stddev as f64;
        let radius = 4.0 * stddev;
        let bias = (-radius * radius / (2.0 * stddev * stddev)).exp();
        let erf_radius = erf(radius / (stddev * std::f64::consts::SQRT_2));
        let mut g = Gaussian {
            stddev,
            radius,
            bias,
            total: 1.0,
            erf_radius,
            inverse: [0.0; KNOTS + 1],
            profile: [0.0; PROFILE + 2],
            per_pixel: (PROFILE as f64 / radius) as f32,
        };
        for k in 0..=PROFILE {
            g.profile[k] = g.eval(radius * k as f64 / PROFILE as f64) as f32;
        }
        g.total = g.cdf(radius);
        for k in 0..=KNOTS {
            // Bisection on the monotone CDF.
            let target = k as f64 / KNOTS as f64;
            let (mut lo, mut hi) = (-radius, radius);
            for _ in 0..64 {
                let mid = 0.5 * (lo + hi);
                if g.cdf(mid) / g.total < target { lo = mid } else { hi = mid }
            }
            g.inverse[k] = (0.5 * (lo + hi)) as f32;
        }
        (g.inverse[0], g.inverse[KNOTS]) = (-radius as f32, radius as f32);
        g
    }

    /// The filter at `x`.
    pub fn eval(&self, x: f64) -> f64 {
        ((-x * x / (2.0 * self.stddev * self.stddev)).exp() - self.bias).max(0.0)
    }

    /// The filter at `x` by linear interpolation in its tabulated profile: what a splatted
    /// sample weighs (ten exponentials a sample were a third of its cost).
    #[inline(always)]
    pub fn eval_splat(&self, x: f32) -> f32 {
        let t = (x.abs() * self.per_pixel).min(PROFILE as f32);
        let k = t as usize;
        let f = t - k as f32;
        // profile[PROFILE + 1] is zero: the interval past the radius.
        self.profile[k] + (self.profile[k + 1] - self.profile[k]) * f
    }

    /// The integral of the filter from -radius to `x` (in [-radius, radius]):
    /// stddev sqrt(pi / 2) (erf(x / (stddev sqrt 2)) + erf(radius / (stddev sqrt 2))) - bias (x + radius).
    pub fn cdf(&self, x: f64) -> f64 {
        let s = self.stddev * std::f64::consts::SQRT_2;
        let c = self.stddev * (std::f64::consts::PI / 2.0).sqrt();
        c * (erf(x / s) + self.erf_radius) - self.bias * (x + self.radius)
    }

    /// The offset with density eval / total that `u` in [0, 1) gives: the table's guess, then
    /// safeguarded Newton steps on the exact CDF (a step that leaves the bracket of the root,
    /// which starts as the knots around it and shrinks with every evaluation, bisects instead).
    #[inline]
    pub fn sample(&self, u: f32) -> f32 {
        let t = (u.clamp(0.0, 1.0) * KNOTS as f32).min(KNOTS as f32 - 1e-3);
        let k = t as usize;
        let (mut lo, mut hi) = (self.inverse[k] as f64, self.inverse[k + 1] as f64);
        let mut x = lo + (hi - lo) * (t - k as f32) as f64;
        let target = u as f64 * self.total;
        for _ in 0..48 {
            let err = self.cdf(x) - target;
            if err < 0.0 {
                lo = x
            } else {
                hi = x
            }
            let newton = x - err / self.eval(x);
            let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            // Well below an f32's resolution of the offset.
            let done = (next - x).abs() <= 1e-6 * self.radius;
            x = next;
            if done {
                break;
            }
        }
        x as f32
    }
}

/// The error function for |z| <= 4 / sqrt 2 (the Gaussian's reach, in its units), by its
/// Taylor series in f64: 2 / sqrt(pi) sum (-1)^n z^(2n+1) / (n! (2n+1)) (Abramowitz and
/// Stegun 7.1.5); at that reach the largest term is about 1.2e3 and the error about 1e-12.
fn erf(z: f64) -> f64 {
    let z2 = z * z;
    let (mut term, mut sum) = (z, z);
    for n in 1..64 {
        term *= -z2 / n as f64;
        let add = term / (2 * n + 1) as f64;
        sum += add;
        if add.abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    sum * std::f64::consts::FRAC_2_SQRT_PI
}

#[cfg(test)]
mod tests;
