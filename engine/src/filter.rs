//! Pixel reconstruction filters, sampled by filter importance sampling (pbrt-v4's
//! `FilterSampler`, `src/pbrt/filters.h`): each camera sample's offset from the pixel centre
//! is drawn with density proportional to the filter, so that its weight f / pdf is the
//! filter's integral, the same for every sample, and the pixel's estimate stays a plain mean
//! of its own samples. Its expectation is Mitsuba 3's weight-normalised splatted estimate,
//! the integral of f(x - centre) L(x) over the integral of f. The filters are Mitsuba 3's
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
}

impl Gaussian {
    /// The filter of standard deviation `stddev` pixels (positive and finite).
    pub fn new(stddev: f32) -> Self {
        let stddev = stddev as f64;
        let radius = 4.0 * stddev;
        let bias = (-radius * radius / (2.0 * stddev * stddev)).exp();
        let erf_radius = erf(radius / (stddev * std::f64::consts::SQRT_2));
        let mut g = Gaussian { stddev, radius, bias, total: 1.0, erf_radius, inverse: [0.0; KNOTS + 1] };
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
