//! The film: per-pixel exact sums and sums of squares of sample radiance, weighted by the pixel
//! filter where it is splatted (`PixelFilter::splats`), the sums of the weights and of their
//! squares (for the mean and its variance), and the count of discarded non-finite samples (and
//! absurdly large ones). A pixel's estimate is its weighted sum over its weights' sum, the
//! plain mean where every sample weighs 1.

use crate::aov::Aovs;
use crate::costs::PixelCosts;
use glam::Vec3;
use pathwave_engine::filter::Splat;
use pathwave_engine::render_scene::PixelWindow;

/// Accumulated samples of an image.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// Per pixel (row-major, row 0 on top): the samples' exact sums.
    pub pixels: Vec<PixelSums>,
    /// The denoiser's guides over the same samples, when the integrator recorded them.
    pub guides: Option<Aovs>,
    /// What the pixels cost, when the integrator measured it: over the samples it rendered
    /// (a film resumed from a checkpoint has costs of the samples rendered since).
    pub costs: Option<PixelCosts>,
    /// Per pixel, the light tracer's exact sums over the same samples (in units of
    /// [`LIGHT_UNIT`]), in scenes where it takes part of the paths
    /// (`crate::light_tracer`); a pixel's estimate adds them over the sample count.
    pub light: Option<Vec<[i64; 3]>>,
}

/// Fixed-point scale of the light tracer's sums: 2^24 (a pixel's sum saturates at 2^39,
/// about 5.5e11; values below 6e-8 round to zero).
pub const LIGHT_UNIT: f64 = (1u64 << 24) as f64;

impl Film {
    /// An empty film. Its pixels are allocated zeroed (`bytemuck::zeroed_vec`: fresh pages
    /// from the kernel) and then written with zeros across the threads, so that each page's
    /// first touch is a write. Left to the render, a page's first touch was a tile's merge
    /// reading the sums (which maps the kernel's shared zero page) and then writing them: a
    /// copy-on-write fault that flushes every thread's TLB by an interprocessor interrupt, slow
    /// on a VM (5-9% of a 1024x1024 16-spp render of Bitterli's cornell-box).
    pub fn new(width: u32, height: u32) -> Self {
        use rayon::prelude::*;
        let mut pixels: Vec<PixelSums> = bytemuck::zeroed_vec(width as usize * height as usize);
        pixels.par_chunks_mut(4096).for_each(|c| c.fill(PixelSums::default()));
        Self { width, height, spp: 0, pixels, guides: None, costs: None, light: None }
    }

    /// Per-pixel estimate: the weighted mean (the plain mean where samples weigh 1, as the
    /// box's do: then the weight is the sample count and the bits are those of sum / spp).
    /// With the light tracer's sums, each pixel adds them over the sample count.
    pub fn mean(&self) -> Vec<Vec3> {
        let mut mean: Vec<Vec3> = self
            .pixels
            .iter()
            .map(|p| {
                let (s, w) = (p.sum(), p.weight());
                let k = if w > 0.0 { 1.0 / w } else { 0.0 };
                Vec3::new((s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32)
            })
            .collect();
        if let Some(light) = &self.light {
            let k = if self.spp > 0 { 1.0 / (LIGHT_UNIT * self.spp as f64) } else { 0.0 };
            for (m, l) in mean.iter_mut().zip(light) {
                *m += Vec3::new((l[0] as f64 * k) as f32, (l[1] as f64 * k) as f32, (l[2] as f64 * k) as f32);
            }
        }
        mean
    }

    /// Adds the samples of another film of the same size (other sample indices of the same
    /// pixels): the sums are exact, so the result has the same bits as rendering them all at
    /// once.
    pub fn merge(&mut self, o: &Film) {
        assert_eq!((self.width, self.height), (o.width, o.height), "films of different sizes");
        // Guides over all the samples: weighted means where both have them (or only one film
        // has samples), none where some samples have none.
        self.guides = match (self.guides.take(), &o.guides) {
            (Some(mut a), Some(b)) => {
                let (wa, wb) = (self.spp as f32, o.spp as f32);
                let mix = |x: &mut Vec<Vec3>, y: &Vec<Vec3>| {
                    x.iter_mut().zip(y).for_each(|(x, y)| *x = (*x * wa + *y * wb) / (wa + wb).max(1.0))
                };
                mix(&mut a.albedo, &b.albedo);
                mix(&mut a.normal, &b.normal);
                mix(&mut a.emission, &b.emission);
                Some(a)
            }
            (a, b) if self.spp == 0 => b.clone().or(a),
            (a, _) if o.spp == 0 => a,
            _ => None,
        };
        match (&mut self.costs, &o.costs) {
            (Some(a), Some(b)) => a.merge(b),
            (a @ None, Some(b)) => *a = Some(b.clone()),
            _ => {}
        }
        self.spp += o.spp;
        self.pixels.iter_mut().zip(&o.pixels).for_each(|(a, b)| a.merge(b));
        match (&mut self.light, &o.light) {
            (Some(a), Some(b)) => a.iter_mut().zip(b).for_each(|(a, b)| {
                for c in 0..3 {
                    a[c] = a[c].saturating_add(b[c]);
                }
            }),
            (a @ None, Some(b)) => *a = Some(b.clone()),
            _ => {}
        }
    }

    /// [`Self::merge`] of a film this one may keep: an empty film (no samples, guides or costs)
    /// takes `o` as it is, so the first pass of a render costs no second image's memory
    /// (zeroed pages faulted in, then a pass adding every pixel: 3-5 ms of a 256x256 render).
    pub fn absorb(&mut self, o: Film) {
        assert_eq!((self.width, self.height), (o.width, o.height), "films of different sizes");
        match self.spp == 0 && self.guides.is_none() && self.costs.is_none() && self.light.is_none() {
            true => *self = o,
            false => self.merge(&o),
        }
    }

    /// Samples whose value was NaN, infinite or above [`MAX_SAMPLE`]; they were counted as zero.
    pub fn non_finite(&self) -> u64 {
        self.pixels.iter().fold(0u64, |n, p| n.saturating_add(p.non_finite))
    }

    /// Pixels (row-major index) that discarded non-finite samples, with how many.
    pub fn non_finite_pixels(&self) -> Vec<(u32, u64)> {
        let bad = self.pixels.iter().enumerate().filter(|(_, p)| p.non_finite > 0);
        bad.map(|(i, p)| (i as u32, p.non_finite)).collect()
    }

    /// Per-pixel variance of the estimate: the samples' weighted variance over the effective
    /// sample count less one, n = (sum of weights)^2 / sum of squared weights (with weights 1,
    /// the sample variance over spp; infinite below two samples). A splatted pixel's noise is
    /// shared with its neighbours: the variance of a sum of pixels is larger than the sum of
    /// their variances, by `PixelFilter::splat_gain` for the whole image.
    pub fn variance_of_mean(&self) -> Vec<Vec3> {
        self.pixels
            .iter()
            .map(|p| {
                let (s, q, w) = (p.sum(), p.sum_sq(), p.weight());
                let n = w * w / p.weight_sq();
                if !(n >= 1.5) {
                    return Vec3::splat(f32::INFINITY);
                }
                let v = |c: usize| (((q[c] - s[c] * s[c] / w) / (n - 1.0)).max(0.0) / w) as f32;
                Vec3::new(v(0), v(1), v(2))
            })
            .collect()
    }
}

/// With `Some(max)`, scales a sample down so that its largest component is at most `max`
/// (trades bias for fewer fireflies; off by default). Non-finite samples pass unchanged, to be
/// counted by the accumulator.
#[inline]
pub fn clamp_sample(v: Vec3, max: Option<f32>) -> Vec3 {
    match max {
        Some(m) if v.max_element() > m => v * (m / v.max_element()),
        _ => v,
    }
}

/// Fixed-point scale of the exact sums: 2^50 (values below 1e-15 vanish). The film keeps them
/// in 96 bits ([`PixelSums`]): a pixel's sum saturates at 2^45, about 3.5e13.
const FIXED: f64 = (1u64 << 50) as f64;

/// Fixed-point scale of the exact sums of squares: 2^40 (squares below 1e-12 vanish; in 96
/// bits a pixel's sum saturates at 2^55, about 3.6e16, and its variance then reads infinite).
const FIXED_SQ: f64 = (1u64 << 40) as f64;

/// Fixed-point scale of the weights' sums: a sample of weight 1 adds 2^32 (and spp of them
/// sum to spp exactly).
const WEIGHT_FIXED: f64 = (1u64 << 32) as f64;

/// Whether a sample is summed: finite, and no component above [`MAX_SAMPLE`].
#[inline(always)]
fn usable(v: Vec3) -> bool {
    v.is_finite() && v.abs().max_element() <= MAX_SAMPLE
}

/// Samples with a component above this are treated like infinite ones (discarded and counted):
/// one sample's fixed-point value then fits its sum. A pixel's sum saturates at about 3.5e13
/// and its sum of squares at 3.6e16 (its variance then reads infinite): samples of 1e6
/// saturate the squares after 36,000 samples, the sum after 35 million.
pub const MAX_SAMPLE: f32 = 1e12;

/// `v as i128` (truncated, saturating), through one `i64` conversion instruction when `v`
/// fits (samples below 8192): the `i128` conversion is a library call.
#[inline(always)]
fn fixed(v: f64) -> i128 {
    if v.abs() < 9.2e18 { v as i64 as i128 } else { v as i128 }
}

/// Sums of one pixel's samples, with non-finite samples replaced by zero and counted.
///
/// The sums are exact fixed-point integers: adding samples in any order gives the same bits, so
/// an integrator may finish a pixel's samples in whatever order its scheduling produces and
/// still write the image that the sequential reference writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct PixelAccumulator {
    /// The samples' values times their weights.
    sum: [i128; 3],
    /// Their squared values times their weights.
    sum_sq: [i128; 3],
    /// Non-finite (or above [`MAX_SAMPLE`]) samples seen.
    pub non_finite: u64,
    /// The weights, in [`WEIGHT_FIXED`] units (discarded samples' included: they count as 0).
    weight: u64,
    /// The squared weights, in the same units.
    weight_sq: u64,
}

impl PixelAccumulator {
    /// Adds one sample value of weight 1.
    #[inline]
    pub fn add(&mut self, v: Vec3) {
        const ONE: u64 = 1 << 32;
        (self.weight, self.weight_sq) = (self.weight.saturating_add(ONE), self.weight_sq.saturating_add(ONE));
        if !usable(v) {
            self.non_finite += 1;
            return;
        }
        for c in 0..3 {
            let x = v[c] as f64;
            // Saturating (`as` saturates too): for the non-negative values of radiance the
            // result is the same in any order.
            self.sum[c] = self.sum[c].saturating_add(fixed(x * FIXED));
            self.sum_sq[c] = self.sum_sq[c].saturating_add(fixed(x * x * FIXED_SQ));
        }
    }

    /// Adds a usable sample (its [`Parts`]) with the weight `w` (in [0, 1]).
    #[inline(always)]
    fn add_weighted(&mut self, parts: &Parts, w: f32) {
        let w = w as f64;
        // Through i64 (w is at most 1): one conversion instruction where `as u64` is several.
        self.weight = self.weight.saturating_add((w * WEIGHT_FIXED) as i64 as u64);
        self.weight_sq = self.weight_sq.saturating_add((w * w * WEIGHT_FIXED) as i64 as u64);
        for c in 0..3 {
            self.sum[c] = self.sum[c].saturating_add(fixed(w * parts.x[c]));
            self.sum_sq[c] = self.sum_sq[c].saturating_add(fixed(w * parts.x[3 + c]));
        }
    }

    /// Adds another accumulator's samples.
    #[inline]
    pub fn merge(&mut self, o: &PixelAccumulator) {
        for c in 0..3 {
            self.sum[c] = self.sum[c].saturating_add(o.sum[c]);
            self.sum_sq[c] = self.sum_sq[c].saturating_add(o.sum_sq[c]);
        }
        self.non_finite = self.non_finite.saturating_add(o.non_finite);
        self.weight = self.weight.saturating_add(o.weight);
        self.weight_sq = self.weight_sq.saturating_add(o.weight_sq);
    }

    /// Adds the 64-bit sums `part` and sets them to zero.
    #[inline]
    fn absorb(&mut self, part: &mut Partial) {
        for c in 0..3 {
            self.sum[c] = self.sum[c].saturating_add(part.0[c] as i128);
            self.sum_sq[c] = self.sum_sq[c].saturating_add(part.0[3 + c] as i128);
        }
        // The weights' parts are non-negative.
        self.weight = self.weight.saturating_add(part.0[6] as u64);
        self.weight_sq = self.weight_sq.saturating_add(part.0[7] as u64);
        *part = Partial::default();
    }

    /// Sum of the values (for tests; the film reads [`PixelSums`]).
    pub fn sum(&self) -> [f64; 3] {
        PixelSums::from(self).sum()
    }
}

/// The largest magnitude of a 96-bit sum.
const I96_MAX: i128 = (1 << 95) - 1;

/// A 96-bit integer, as three 32-bit words, low first.
type I96 = [u32; 3];

/// `v` in 96 bits, saturated.
#[inline(always)]
fn narrow(v: i128) -> I96 {
    let v = v.clamp(-I96_MAX, I96_MAX) as u128;
    [v as u32, (v >> 32) as u32, (v >> 64) as u32]
}

/// A 96-bit integer's value.
#[inline(always)]
fn widen(w: &I96) -> i128 {
    let v = w[0] as u128 | (w[1] as u128) << 32 | (w[2] as u128) << 64;
    ((v << 32) as i128) >> 32
}

/// One pixel's sums as the film keeps them: a [`PixelAccumulator`]'s, each fixed-point sum in
/// 96 bits (saturated; a saturated sum of squares reads infinite) and aligned to 8 bytes: 96 bytes a pixel
/// where the accumulator takes 128 (a 1024 x 1024 film: 100 MB, not 134). Tiles accumulate in
/// the wide form and hand their sums over once, so the narrowing costs nothing per sample; the
/// sums are integers, saturating at the same ends in any order, so the film's bits do not
/// depend on the order tiles, passes or shares come in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct PixelSums {
    /// The values' sums (2^50 units), then their squares' (2^40 units).
    sums: [I96; 6],
    /// Non-finite (or above [`MAX_SAMPLE`]) samples seen.
    pub non_finite: u64,
    /// The weights' sum (2^32 units).
    weight: u64,
    /// The squared weights' sum (2^32 units).
    weight_sq: u64,
}

impl From<&PixelAccumulator> for PixelSums {
    fn from(a: &PixelAccumulator) -> Self {
        let mut p = PixelSums::default();
        p.add(a);
        p
    }
}

impl PixelSums {
    /// Adds a tile's (or another film's, widened) sums of this pixel.
    #[inline]
    pub fn add(&mut self, a: &PixelAccumulator) {
        for c in 0..3 {
            self.sums[c] = narrow(widen(&self.sums[c]).saturating_add(a.sum[c]));
            self.sums[3 + c] = narrow(widen(&self.sums[3 + c]).saturating_add(a.sum_sq[c]));
        }
        self.non_finite = self.non_finite.saturating_add(a.non_finite);
        self.weight = self.weight.saturating_add(a.weight);
        self.weight_sq = self.weight_sq.saturating_add(a.weight_sq);
    }

    /// Adds another film's sums of this pixel.
    #[inline]
    pub fn merge(&mut self, o: &PixelSums) {
        self.add(&o.wide());
    }

    /// The sums in the accumulator's form.
    fn wide(&self) -> PixelAccumulator {
        PixelAccumulator {
            sum: [0, 1, 2].map(|c| widen(&self.sums[c])),
            sum_sq: [3, 4, 5].map(|c| widen(&self.sums[c])),
            non_finite: self.non_finite,
            weight: self.weight,
            weight_sq: self.weight_sq,
        }
    }

    /// The exact state, for checkpoints: the fixed-point sums of the values (2^50 units) and of
    /// their squares (2^40 units), each within 96 bits, the count of discarded samples, and the
    /// sums of the weights and of their squares (2^32 units).
    pub fn raw(&self) -> ([i128; 6], u64, [u64; 2]) {
        (self.sums.map(|s| widen(&s)), self.non_finite, [self.weight, self.weight_sq])
    }

    /// Sums from [`Self::raw`]'s parts (saturated to 96 bits).
    pub fn from_raw(sums: [i128; 6], non_finite: u64, [weight, weight_sq]: [u64; 2]) -> Self {
        Self { sums: sums.map(narrow), non_finite, weight, weight_sq }
    }

    /// The raw weights of `n` samples of weight 1 (what [`Self::raw`] holds of a pixel that
    /// `n` calls of [`PixelAccumulator::add`] made).
    pub fn unit_weights(n: u32) -> [u64; 2] {
        [(n as u64) << 32; 2]
    }

    /// Sum of the weights (the sample count where each weighs 1).
    pub fn weight(&self) -> f64 {
        self.weight as f64 / WEIGHT_FIXED
    }

    /// Sum of the squared weights.
    pub fn weight_sq(&self) -> f64 {
        self.weight_sq as f64 / WEIGHT_FIXED
    }

    /// Sum of the values (where it saturated, its largest value: a pixel's estimate stays
    /// finite).
    pub fn sum(&self) -> [f64; 3] {
        [0, 1, 2].map(|c| widen(&self.sums[c]) as f64 / FIXED)
    }

    /// Sum of the squared values (infinite where it saturated: the variance is unknown).
    pub fn sum_sq(&self) -> [f64; 3] {
        [3, 4, 5].map(|c| match widen(&self.sums[c]) {
            s if s.abs() >= I96_MAX => f64::INFINITY.copysign(s as f64),
            s => s as f64 / FIXED_SQ,
        })
    }
}

/// A tile's sums: a [`PixelAccumulator`] a pixel, and beside it 64-bit sums of the pixel's
/// samples whose parts are small ([`Partial`]), added to the accumulator every
/// [`PARTIAL_SAMPLES`] samples and by [`Self::into_pixels`].
#[derive(Clone, Debug)]
pub struct TileSums {
    /// The wide sums, but for [`Self::partial`]'s.
    pixels: Vec<PixelAccumulator>,
    /// The 64-bit sums.
    partial: Vec<Partial>,
    /// Samples added since the 64-bit sums were last emptied.
    samples: u32,
}

/// A pixel's sums in 64-bit integers, the same fixed-point units as a [`PixelAccumulator`]'s
/// (the values' three, their squares' three, the weights' and the squared weights'), of its
/// samples whose parts are all below [`SMALL`]: plain 64-bit adds of integers converted
/// without a branch ([`small_fixed`]), where the wide sums take a conversion with its range
/// check and a saturating 128-bit add each (a tent-filtered render's splats took 97 ns a
/// sample with those; see `benches/results/camera-and-film.md`). The sums are exact integers
/// either way, and no wide sum comes near saturating (a sample's part is below 2^91), so a
/// pixel's total is the same bits whichever sums took which samples. Aligned to its 64 bytes:
/// one cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
struct Partial([i64; 8]);

/// The bound (exclusive) on the magnitude of a sample's parts for the 64-bit sums: a value
/// below 2 and a square below 2^11 (in their fixed-point units), where [`small_fixed`] is exact.
const SMALL: f64 = (1u64 << 51) as f64;

/// How many samples the 64-bit sums take before they are added to the wide ones: 2^12 parts
/// below 2^51 sum below 2^63.
const PARTIAL_SAMPLES: u32 = 1 << 12;

/// `x as i64` (truncated) for |x| < 2^51, without the conversion's range checks, in operations
/// that vectorise: the truncated value plus 1.5 * 2^52 is exact, and its bits less the
/// constant's are the integer.
#[inline(always)]
fn small_fixed(x: f64) -> i64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    ((x.trunc() + MAGIC).to_bits() as i64).wrapping_sub(MAGIC.to_bits() as i64)
}

/// A usable sample's parts in fixed-point units before its weight: its value's three, its
/// square's three, and the weights' unit twice.
#[derive(Clone, Copy, Debug)]
struct Parts {
    /// The parts.
    x: [f64; 8],
    /// Whether each is below [`SMALL`] (then so is each weighted part: weights are at most 1).
    small: bool,
}

impl Parts {
    /// The parts of the value `v` (zero for a discarded sample: its weights alone).
    #[inline(always)]
    fn new(v: glam::DVec3) -> Self {
        // FIXED and FIXED_SQ are powers of two: the scaling rounds nothing.
        let (a, b) = (v * FIXED, v * v * FIXED_SQ);
        let x = [a.x, a.y, a.z, b.x, b.y, b.z, WEIGHT_FIXED, WEIGHT_FIXED];
        Self { x, small: a.abs().max(b.abs()).max_element() < SMALL }
    }
}

impl TileSums {
    /// `n` pixels without samples.
    pub fn new(n: usize) -> Self {
        Self {
            pixels: vec![PixelAccumulator::default(); n],
            partial: vec![Partial::default(); n],
            samples: 0,
        }
    }

    /// Adds one sample value of weight 1 to pixel `k` ([`PixelAccumulator::add`]).
    #[inline]
    pub fn add(&mut self, k: usize, v: Vec3) {
        if !usable(v) {
            self.pixels[k].add(v);
            return;
        }
        self.count();
        self.add_parts(k, &Parts::new(v.as_dvec3()), 1.0);
    }

    /// Counts a sample about to be added (to one pixel or, splatted, to several), first
    /// emptying the 64-bit sums into the wide ones where they have taken
    /// [`PARTIAL_SAMPLES`].
    #[inline(always)]
    fn count(&mut self) {
        if self.samples == PARTIAL_SAMPLES {
            self.empty_partial();
        }
        self.samples += 1;
    }

    /// Adds the 64-bit sums to the wide ones.
    fn empty_partial(&mut self) {
        for (p, part) in self.pixels.iter_mut().zip(&mut self.partial) {
            p.absorb(part);
        }
        self.samples = 0;
    }

    /// Adds a sample's `parts` with the weight `w` (in [0, 1]) to pixel `k`.
    #[inline(always)]
    fn add_parts(&mut self, k: usize, parts: &Parts, w: f32) {
        if !parts.small {
            self.pixels[k].add_weighted(parts, w);
            return;
        }
        // The weighted parts as `add_weighted` computes them (the squared weight is exact in
        // f64, and times a power of two).
        let w = w as f64;
        let part = &mut self.partial[k].0;
        for (i, (sum, x)) in part.iter_mut().zip(parts.x).enumerate() {
            let m = if i == 7 { w * w } else { w };
            *sum = sum.wrapping_add(small_fixed(m * x));
        }
    }

    /// The pixels' sums.
    pub fn into_pixels(mut self) -> Vec<PixelAccumulator> {
        self.empty_partial();
        self.pixels
    }
}

/// A tile's splatted samples (`PixelFilter::splats`): the sums of `rect`, the pixels of the
/// window that the tile's samples reach (the tile's own and a margin around them), row-major.
#[derive(Clone, Debug)]
pub struct SplatFilm {
    /// The filter.
    filter: Splat,
    /// The pixels held, in image coordinates.
    pub rect: PixelWindow,
    /// Their sums.
    sums: TileSums,
}

impl SplatFilm {
    /// No samples of `filter` over `rect`.
    pub fn new(filter: Splat, rect: PixelWindow) -> Self {
        Self { filter, rect, sums: TileSums::new(rect.len()) }
    }

    /// The pixels' sums (row-major over [`Self::rect`]).
    pub fn into_pixels(self) -> Vec<PixelAccumulator> {
        self.sums.into_pixels()
    }

    /// Adds a sample of value `v` of the pixel `pixel`, at `u` in [0, 1)^2 across it, to every
    /// pixel of [`Self::rect`] that the filter reaches from there, weighed by the filter at its
    /// centre. A non-finite sample (or one above [`MAX_SAMPLE`]) adds its weights as zero and
    /// is counted in its own pixel.
    #[inline]
    pub fn splat(&mut self, pixel: (u32, u32), u: [f32; 2], v: Vec3) {
        let r = self.rect;
        let ok = usable(v);
        if !ok && r.contains(pixel.0, pixel.1) {
            let own = r.index(pixel.0, pixel.1);
            self.sums.pixels[own].non_finite += 1;
        }
        let parts = Parts::new(if ok { v.as_dvec3() } else { glam::DVec3::ZERO });
        self.sums.count();
        let (wx, wy) = (self.filter.weights(u[0]), self.filter.weights(u[1]));
        for j in 0..wy.n {
            let y = (pixel.1 as i64 + (wy.first + j as i32) as i64) as u32;
            for i in 0..wx.n {
                let x = (pixel.0 as i64 + (wx.first + i as i32) as i64) as u32;
                // Pixels off the image (negative coordinates wrap to huge ones) or outside the
                // window are not held.
                if r.contains(x, y) {
                    self.sums.add_parts(r.index(x, y), &parts, wx.w[i] * wy.w[j]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_do_not_depend_on_order() {
        let values: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::splat((i as f32 * 0.7368).sin().abs() * 10f32.powi(i % 13 - 6)))
            .collect();
        let mut a = PixelAccumulator::default();
        let mut b = PixelAccumulator::default();
        values.iter().for_each(|v| a.add(*v));
        values.iter().rev().for_each(|v| b.add(*v));
        assert_eq!(a, b);
        let exact: f64 = values.iter().map(|v| v.x as f64).sum();
        assert!((a.sum()[0] - exact).abs() < 1e-9 * exact);
    }

    #[test]
    fn tile_sums_equal_the_wide_sums_at_every_magnitude() {
        // Values from 1e-7 to 1e6 (past [`SMALL`], and the 64-bit sums emptied several times),
        // non-finite ones among them, at weights in [0, 1].
        let mut h = 1u32;
        let mut next = || {
            h = h.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            h
        };
        let (mut tile, mut wide) = (TileSums::new(2), [PixelAccumulator::default(); 2]);
        for i in 0..20_000 {
            let m = 10f32.powf((next() % 1400) as f32 / 100.0 - 7.0);
            let v = match i % 97 {
                0 => Vec3::new(f32::NAN, 1.0, 1.0),
                1 => Vec3::ZERO,
                _ => Vec3::new(m, m * 0.5, m * 0.25),
            };
            let w = (next() % 1001) as f32 / 1000.0;
            tile.add(0, v);
            wide[0].add(v);
            if usable(v) {
                let parts = Parts::new(v.as_dvec3());
                tile.count();
                tile.add_parts(1, &parts, w);
                wide[1].add_weighted(&parts, w);
            }
        }
        assert_eq!(tile.partial.iter().filter(|p| p.0 != [0; 8]).count(), 2, "the 64-bit sums took samples");
        assert_eq!(tile.into_pixels(), wide);
        // The largest small parts, for longer than 64-bit sums of them would hold.
        let (mut tile, mut wide) = (TileSums::new(1), PixelAccumulator::default());
        let v = Vec3::splat(1.999);
        (0..3 * PARTIAL_SAMPLES).for_each(|_| (tile.add(0, v), wide.add(v)).1);
        assert_eq!(tile.into_pixels(), vec![wide]);
        for x in [0.0, 0.75, 1.0, 2.5, 1e6, (1u64 << 51) as f64 - 1.0] {
            for x in [x, -x] {
                assert_eq!(small_fixed(x), x as i64, "{x}");
            }
        }
    }

    #[test]
    fn a_new_film_holds_no_samples() {
        let film = Film::new(3, 2);
        assert_eq!(film.pixels, vec![PixelSums::default(); 6]);
        assert_eq!((film.spp, film.non_finite()), (0, 0));
    }

    #[test]
    fn absorbing_a_film_equals_merging_it() {
        let film = |spp: u32, v: f32| {
            let mut f = Film::new(2, 1);
            f.spp = spp;
            let mut a = PixelAccumulator::default();
            (0..spp).for_each(|_| a.add(Vec3::splat(v)));
            f.pixels.iter_mut().for_each(|p| p.add(&a));
            f
        };
        for (a, b) in
            [(film(0, 0.0), film(3, 0.5)), (film(2, 0.25), film(3, 0.5)), (film(2, 0.25), film(0, 0.0))]
        {
            let (mut merged, mut absorbed) = (a.clone(), a);
            merged.merge(&b);
            absorbed.absorb(b);
            assert_eq!(merged, absorbed);
        }
    }

    #[test]
    fn clamping_scales_bright_samples_only() {
        assert_eq!(clamp_sample(Vec3::new(8.0, 4.0, 2.0), Some(2.0)), Vec3::new(2.0, 1.0, 0.5));
        assert_eq!(clamp_sample(Vec3::new(1.0, 0.5, 0.0), Some(2.0)), Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(clamp_sample(Vec3::splat(100.0), None), Vec3::splat(100.0));
        assert!(clamp_sample(Vec3::splat(f32::NAN), Some(1.0)).is_nan());
    }

    #[test]
    fn non_finite_samples_are_counted_not_summed() {
        let mut a = PixelAccumulator::default();
        a.add(Vec3::new(f32::NAN, 1.0, 1.0));
        a.add(Vec3::splat(f32::INFINITY));
        a.add(Vec3::ONE);
        assert_eq!(a.non_finite, 2);
        assert_eq!(a.sum(), [1.0; 3]);
    }

    #[test]
    fn huge_samples_neither_overflow_nor_depend_on_order() {
        // Found by the fuzzer: an emitter of 6.7e28 overflowed the fixed-point sums.
        let mut a = PixelAccumulator::default();
        a.add(Vec3::splat(2e12));
        assert_eq!((a.non_finite, a.sum()), (1, [0.0; 3]));
        let values = [Vec3::splat(9e11), Vec3::splat(1.0), Vec3::splat(9e11), Vec3::splat(0.25)];
        let (mut a, mut b) = (PixelAccumulator::default(), PixelAccumulator::default());
        values.iter().for_each(|v| a.add(*v));
        values.iter().rev().for_each(|v| b.add(*v));
        assert_eq!(a, b);
        assert_eq!(a.sum()[0], 2.0 * 9e11f32 as f64 + 1.25);
        let film = PixelSums::from(&a);
        assert_eq!(film.sum()[0], a.sum()[0]);
        assert_eq!(film.sum_sq()[0], f64::INFINITY, "the squares saturate: the variance is unknown");
    }

    /// The film's 96-bit sums hold what fits, saturate what does not (the sum at its largest
    /// value, the squares' reading infinite), sign included, and saturate the same in any
    /// order for non-negative sums.
    #[test]
    fn film_sums_keep_96_bits_and_saturate() {
        for v in [0, 1, -1, 12345 << 70, -(12345 << 70), I96_MAX, -I96_MAX] {
            assert_eq!(widen(&narrow(v)), v, "{v}");
        }
        assert_eq!(widen(&narrow(i128::MAX)), I96_MAX);
        assert_eq!(widen(&narrow(i128::MIN + 1)), -I96_MAX);
        // Three pixels' worth of 1e11 samples (2^50 units: 2^86.5 each) pass 2^95 in the sum's
        // third part: saturated whichever part comes first.
        let part = |v: f32, n: usize| {
            let mut a = PixelAccumulator::default();
            (0..n).for_each(|_| a.add(Vec3::splat(v)));
            a
        };
        let parts = [part(1e11, 200), part(1.0, 3), part(1e11, 200)];
        let (mut ab, mut ba) = (PixelSums::default(), PixelSums::default());
        parts.iter().for_each(|p| ab.add(p));
        parts.iter().rev().for_each(|p| ba.add(p));
        assert_eq!(ab, ba);
        assert_eq!((ab.sum()[0], ab.sum_sq()[0]), (I96_MAX as f64 / FIXED, f64::INFINITY));
        assert_eq!(PixelSums::from(&parts[1]).sum()[0], 3.0);
    }
}
