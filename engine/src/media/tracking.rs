//! Delta and ratio tracking through media whose density follows a grid (Novák et al., "Monte
//! Carlo methods for volumetric light transport simulation", Computer Graphics Forum 2018;
//! pbrt-v4 14.2): tentative collisions drawn against the majorant cells the ray crosses
//! ([`grid::MajorantGrid`]), each real with probability `sigma_t / majorant` (free flights) or
//! multiplying the transmittance by `1 - sigma_t / majorant` (ratio tracking), with numbers
//! from a generator seeded by a hash of the ray.

use super::{ChromaticFlight, Line, Media, MediumEvent, PlacedGrid, SEGMENTS, exp3, grid, sweep};
use glam::{Affine3A, Vec3, Vec3A};
use std::sync::Arc;

/// The most tentative collisions one free flight or transmittance estimate takes through
/// grids: a ray that would take more (a majorant far above the density it meets, over a long
/// stretch) is taken as absorbed, so that no input can stall a render. Delta tracking meets
/// about `majorant x length` of them, a million only past an optical depth of a million.
#[cfg(not(fuzzing))]
pub const MAX_TRACKING_STEPS: u32 = 1 << 20;
/// The most tentative collisions one free flight or transmittance estimate takes, in fuzzing
/// builds (`cargo fuzz` sets `cfg(fuzzing)`): 4096, so that the hostile grids the fuzzers make
/// (1e6 beside zeros) end in milliseconds and they reach their executions.
#[cfg(fuzzing)]
pub const MAX_TRACKING_STEPS: u32 = 1 << 12;

/// A grid as a volume looks it up: from world space.
#[derive(Clone, Debug)]
pub(super) struct WorldGrid {
    pub(super) grid: Arc<grid::VoxelGrid>,
    pub(super) grid_from_world: Affine3A,
}

impl WorldGrid {
    pub(super) fn new(g: &Option<PlacedGrid>, object_from_world: Affine3A) -> Option<Self> {
        g.as_ref()
            .map(|g| Self { grid: g.grid.clone(), grid_from_world: g.grid_from_object * object_from_world })
    }

    /// The `t` interval of `o + t d` inside the grid's cube (unclipped), or `None`.
    #[inline]
    pub(super) fn interval(&self, o: Vec3A, d: Vec3A) -> Option<(f32, f32)> {
        let (o, d) = (self.grid_from_world.transform_point3a(o), self.grid_from_world.transform_vector3a(d));
        let inv = d.recip();
        let (a, b) = (-o * inv, (Vec3A::ONE - o) * inv);
        // 0 * inf = NaN: a ray in a face's plane, inside the closed cube along that axis.
        let nan = a.cmpne(a) | b.cmpne(b);
        let lo = Vec3A::select(nan, Vec3A::NEG_INFINITY, a.min(b)).max_element();
        let hi = Vec3A::select(nan, Vec3A::INFINITY, a.max(b)).min_element();
        (lo < hi).then_some((lo, hi))
    }
}

/// A small generator for the numbers of delta and ratio tracking beyond the sampler's
/// (splitmix64: Steele et al., "Fast splittable pseudorandom number generators", OOPSLA 2014),
/// seeded by hashing the bits of a ray.
pub(super) struct Rng(u64);

impl Rng {
    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    pub(super) fn seeded(o: Vec3A, d: Vec3A, x: f32) -> Self {
        let words = [o.x, o.y, o.z, d.x, d.y, d.z, x].map(f32::to_bits);
        Self(words.iter().fold(0x243f_6a88_85a3_08d3, |h, &w| Self::mix(h ^ w as u64)))
    }

    /// A number in [0, 1).
    pub(super) fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        (Self::mix(self.0) >> 40) as f32 / (1u64 << 24) as f32
    }
}

impl Media {
    /// [`Self::transmittance`] in media with grids: Beer-Lambert through the homogeneous
    /// stretches times, per grid stretch, the product of `1 - sigma_t / majorant` over
    /// tentative collisions (ratio tracking), in every channel at once: the majorant bounds
    /// the largest channel, so that each factor lies in [0, 1].
    #[inline(never)]
    pub(super) fn tracked_transmittance(&self, line: &Line, tmax: f32) -> Vec3 {
        let len = line.d.length();
        let mut rng = Rng::seeded(line.o, line.d, tmax);
        let mut steps = 0u32;
        SEGMENTS.with_borrow_mut(|segs| {
            self.segments(line, tmax, segs);
            let mut depth = Vec3::ZERO;
            let mut tr = Vec3A::ONE;
            for s in segs.iter() {
                let i = s.vol as usize;
                if self.density[i].is_none() {
                    depth += self.volumes[i].medium.sigma_t * (s.t1 - s.t0);
                    continue;
                }
                let (o, d) = line.of(i);
                let mut t = s.t0;
                loop {
                    t -= crate::math::ln(1.0 - rng.next()) / (s.maj * len);
                    if !(t < s.t1) {
                        break;
                    }
                    tr *= Vec3A::ONE - Vec3A::from(self.extinction_at(i, o + t * d)) / s.maj;
                    steps += 1;
                    if steps > MAX_TRACKING_STEPS {
                        return Vec3::ZERO;
                    }
                    // Russian roulette once little gets through (pbrt-v4's ratio tracking): the
                    // steps end soon in dense media, and the estimate stays unbiased.
                    if tr.max_element() < 0.05 {
                        if rng.next() < 0.75 {
                            return Vec3::ZERO;
                        }
                        tr /= 0.25;
                    }
                }
            }
            // (One exponential where every channel is the same.)
            let through = match self.chromatic {
                true => exp3(-depth * len),
                false => Vec3::splat(crate::math::exp(-depth.x * len)),
            };
            Vec3::from(tr.max(Vec3A::ZERO)) * through
        })
    }

    /// [`Self::sample`] where grids are: delta tracking.
    pub(super) fn tracked_flight(&self, line: &Line, tmax: f32, u: f32) -> Option<MediumEvent> {
        let (o, d) = (line.o, line.d);
        let len = d.length();
        // Optical depth to travel, in units of t.
        let mut left = -crate::math::ln(1.0 - u) / len;
        let (mut t, mut first, mut nulls) = (0.0f32, 0, 0u32);
        let mut rng = None;
        SEGMENTS.with_borrow_mut(|segs| {
            self.segments(line, tmax, segs);
            // Sweep the piecewise-constant majorant: at `t`, the summed majorant of the
            // stretches covering [t, next) and the next stretch end or start.
            loop {
                let (mut sigma, mut tracked) = (0.0f32, false);
                let next = sweep(segs, &mut first, t, tmax, |s| {
                    sigma += s.maj;
                    tracked |= self.density[s.vol as usize].is_some();
                });
                if sigma > 0.0 && sigma * (next - t) > left {
                    let ts = t + left / sigma;
                    let c = self.coefficients_at(segs, line, ts);
                    if tracked {
                        // A tentative collision: real with probability sigma_t / majorant.
                        let rng = rng.get_or_insert_with(|| Rng::seeded(o, d, u));
                        if !(rng.next() * sigma < c.sigma_t.x) {
                            nulls += 1;
                            if nulls > MAX_TRACKING_STEPS {
                                // Absorbed (see MAX_TRACKING_STEPS).
                                let (albedo, emitted) = (Vec3::ZERO, Vec3::ZERO);
                                return Some(MediumEvent { t: ts, albedo, g: c.g, emitted });
                            }
                            t = ts;
                            left = -crate::math::ln(1.0 - rng.next()) / len;
                            continue;
                        }
                    }
                    return Some(c.event(ts));
                }
                left -= sigma * (next - t);
                if !(next > t) || next >= tmax {
                    return None;
                }
                t = next;
            }
        })
    }

    /// [`Self::sample_chromatic`] where grids are: delta tracking against the majorant of the
    /// largest channel, `sigma_maj` (one for every channel, so that the majorant's
    /// transmittance is the same in each and cancels from the ratios). A tentative collision
    /// is real with probability `sigma_t,h / sigma_maj` in the hero channel `h`, else null.
    /// Had channel `c` been the hero, the same collision's density would have been
    /// `sigma_t,c` (real) or `sigma_maj - sigma_t,c` (null) times the majorant's part; so a
    /// null multiplies weight and ratio by `(sigma_maj - sigma_t) / (sigma_maj - sigma_t,h)`,
    /// and the real collision ends the flight with weight `sigma_s / sigma_t,h` and ratio
    /// `sigma_t / sigma_t,h` (pbrt-v4's `VolPathIntegrator`, 4th ed. 14.2.2, whose
    /// majorants are per channel).
    pub(super) fn tracked_chromatic_flight(
        &self,
        line: &Line,
        tmax: f32,
        u: f32,
        h: usize,
    ) -> ChromaticFlight {
        let len = line.d.length();
        // Optical depth of the majorant to travel, in units of t.
        let mut left = -crate::math::ln(1.0 - u) / len;
        let (mut t, mut first, mut nulls) = (0.0f32, 0, 0u32);
        // The nulls' product, weight and ratio alike.
        let mut w = Vec3::ONE;
        let mut rng = Rng::seeded(line.o, line.d, u);
        SEGMENTS.with_borrow_mut(|segs| {
            self.segments(line, tmax, segs);
            loop {
                let mut sigma = 0.0f32;
                let next = sweep(segs, &mut first, t, tmax, |s| sigma += s.maj);
                if sigma > 0.0 && sigma * (next - t) > left {
                    let ts = t + left / sigma;
                    let c = self.coefficients_at(segs, line, ts);
                    if rng.next() * sigma < c.sigma_t[h] {
                        return c.flight(ts, w / c.sigma_t[h]);
                    }
                    let null = (Vec3::splat(sigma) - c.sigma_t).max(Vec3::ZERO);
                    w *= null / null[h];
                    nulls += 1;
                    if nulls > MAX_TRACKING_STEPS || !w.is_finite() {
                        // Absorbed (see MAX_TRACKING_STEPS).
                        return ChromaticFlight::through(Vec3::ZERO);
                    }
                    t = ts;
                    left = -crate::math::ln(1.0 - rng.next()) / len;
                    continue;
                }
                left -= sigma * (next - t);
                if !(next > t) || next >= tmax {
                    return ChromaticFlight::through(w);
                }
                t = next;
            }
        })
    }
}
