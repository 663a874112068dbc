//! A lat-long (equirectangular) HDR environment light, importance-sampled by luminance.
//!
//! # Mapping
//!
//! A world direction d looks up the image at
//! u = atan2(d.x, -d.z) / (2 pi), wrapped to [0, 1), and v = acos(d.y) / pi: v = 0 is +y and
//! the top row of the image, -z is u = 0 (the left edge), +x is u = 0.25, +z is u = 0.5 and -x
//! is u = 0.75 (the mapping of Mitsuba 3's `envmap` emitter). Texel (i, j) (column i, row j
//! from the top) lies at u = (i + 0.5) / W (texel-centred columns) and v = j / (H - 1) (the
//! top row at the pole +y, the bottom row at -y), as Mitsuba 3.9 places them; lookups
//! interpolate bilinearly between those points, wrapping in u and clamping in v.
//!
//! Rotation: `rotate_degrees` turns the map about +y by a right-handed rotation (positive =
//! counter-clockwise seen from above, looking down -y): what the unrotated map shows in the
//! direction d appears in the direction R_y(rotate) d. For instance, rotating by +90 degrees
//! moves what was at +x to -z, and what was at -z to -x. Since a rotation about +y only shifts
//! the azimuth, it is applied as u_map = u(d) + rotate / 360 (mod 1).
//!
//! # Sampling
//!
//! The map is sampled with a piecewise-constant 2D distribution over its texel grid: a
//! marginal density over rows and one conditional density per row ([`crate::lighting::distribution`]:
//! pbrt-v4's `PiecewiseConstant1D` and `PiecewiseConstant2D`, appendix A.4 and A.5 of
//! "Physically Based Rendering", 4th edition). A point (u, v) of the unit square maps to the direction above, with
//! d omega = 2 pi^2 sin(theta) du dv, so the solid-angle density is
//! p(omega) = p(u, v) / (2 pi^2 sin theta) (pbrt-v3's `InfiniteAreaLight`, section 14.2.4 of
//! the 3rd edition); directions with sin theta = 0 (the poles) are never returned and have
//! density 0.
//!
//! The weight of a cell must be positive wherever the bilinear radiance can be: a lookup inside
//! cell (i, j) reads texels i - 1 ..= i + 1 (wrapping) of rows j - 1 ..= j + 1 (clamped), so the
//! weight is the largest Rec. 709 luminance among those nine texels (a bound of the interpolated
//! luminance, which is a convex combination of theirs), times sin theta at the cell centre. The
//! bound is conservative: a small sun's density spreads over the ring of cells around it.
//!
//! # MIS compensation
//!
//! A map has two densities ([`EnvPdf`]). The complete one is the one above, positive wherever
//! there is radiance. The compensated one (Karlik, Šik, Vévoda, Skřivan and Křivánek 2019, "MIS
//! Compensation: Optimizing Sampling Techniques in Multiple Importance Sampling", ACM TOG
//! 38(6); pbrt-v4's `ImageInfiniteLight::compensatedDistribution`) is built from the cells'
//! weights less their mean, max(0, w - mean): where light sampling is combined by MIS with
//! BSDF or phase sampling, which covers every direction, the light technique need not cover the
//! directions dimmer than the mean (BSDF sampling takes them with MIS weight 1) and spends its
//! samples on the bright ones. pbrt's map is equal-area, so its mean is one over solid angle;
//! a lat-long grid's cells are not, and the mean here is the solid-angle one too (each row's
//! weights counted by sin theta at its centre), the level that a BSDF technique spread evenly
//! over the sphere would cover. A map whose compensated weights are all 0 (every cell's weight
//! the same) falls back to the complete density, as pbrt's does.

use crate::lighting::distribution::{Distribution2D, clean};
use crate::texture::{TextureError, TextureImage};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::{PI, TAU};
use std::path::Path;

use crate::math::luminance;

/// The (u, v) of the unit square that a direction looks up in an unrotated map (see the module
/// documentation), and sin theta, the sine of its angle to +y. `dir` need not be unit length.
/// `None` for a zero or non-finite direction.
#[inline]
pub fn direction_to_uv(dir: Vec3A) -> Option<(Vec2, f32)> {
    let d = dir.normalize_or_zero();
    if d == Vec3A::ZERO {
        return None;
    }
    // atan2 of the two components is accurate near the poles, unlike acos(d.y).
    let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
    let u = wrap01(crate::math::atan2(d.x, -d.z) / TAU);
    let v = (crate::math::atan2(sin_theta, d.y) / PI).clamp(0.0, 1.0);
    Some((Vec2::new(u, v), sin_theta.min(1.0)))
}

/// The unit direction at (u, v) of an unrotated map: theta = pi v from +y, and the azimuth
/// 2 pi u measured from -z towards +x. The inverse of [`direction_to_uv`].
#[inline]
pub fn uv_to_direction(uv: Vec2) -> Vec3A {
    uv_to_direction_sin(uv).0
}

/// [`uv_to_direction`] and sin theta there.
#[inline]
fn uv_to_direction_sin(uv: Vec2) -> (Vec3A, f32) {
    // Half a turn for theta, a turn (wrapped) for phi: polynomials, not the C library's.
    let (cos_theta, sin_theta) = crate::math::cos_sin_turn(wrap01(0.5 * uv.y));
    let (cos_phi, sin_phi) = crate::math::cos_sin_turn(wrap01(uv.x));
    (Vec3A::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi), sin_theta)
}

/// `x` wrapped to [0, 1) (1 - tiny rounds to 1 after `x - floor(x)`: that is 0 again).
#[inline]
fn wrap01(x: f32) -> f32 {
    let f = x - x.floor();
    if f < 1.0 { f } else { 0.0 }
}

/// The shift of u that rotates a map by `rotate_degrees` about +y (see the module
/// documentation); 0 for a non-finite angle.
fn u_offset(rotate_degrees: f32) -> f32 {
    if rotate_degrees.is_finite() { wrap01(rotate_degrees / 360.0) } else { 0.0 }
}

/// sin theta at the centre of row `j` of `h` (the area a cell of that row covers on the sphere,
/// up to a constant): in f64, rounded, as a C library's last bits reach the f32 only at a
/// rounding tie.
fn row_sin_theta(j: usize, h: usize) -> f32 {
    (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin() as f32
}

/// Samples directions over the sphere in proportion to a lat-long grid of weights (with the
/// mapping of the module documentation), and gives their density in solid angle.
///
/// [`EnvironmentMap`] uses one built from its texels; a caller with an analytic background (a
/// sky model) builds one from a grid of its luminance (for instance 1 x 64 cells, one per band
/// of latitude) and evaluates the radiance itself. The weight of a cell must be positive
/// wherever the background's radiance can be: cells of weight 0 are never sampled.
#[derive(Clone, Debug, PartialEq)]
pub struct LatLongSampler {
    dist: Distribution2D,
    u_offset: f32,
}

impl LatLongSampler {
    /// Builds the sampler of a `width` x `height` grid of `weights` (row-major, row 0 at the top:
    /// v = 0, +y). A weight is the luminance of its cell, or a bound of it; the sampler multiplies
    /// it by sin theta at the cell centre (the area the cell covers on the sphere), so the density
    /// in solid angle is proportional to the weight, up to sin(theta centre) / sin(theta) within a
    /// cell. `rotate_degrees` rotates the grid about +y as the module documentation says. `None`
    /// when every weight is 0 (nothing to sample).
    ///
    /// # Panics
    /// If `weights.len() != width * height`.
    pub fn new(width: u32, height: u32, weights: &[f32], rotate_degrees: f32) -> Option<Self> {
        let (w, h) = (width as usize, height as usize);
        assert_eq!(weights.len(), w * h, "LatLongSampler: {width} x {height} cells need as many weights");
        let mut area_weighted = Vec::with_capacity(weights.len());
        for (j, row) in weights.chunks_exact(w.max(1)).enumerate() {
            let sin_theta = row_sin_theta(j, h);
            area_weighted.extend(row.iter().map(|&x| clean(x) * sin_theta));
        }
        let dist = Distribution2D::new(w, h, &area_weighted)?;
        Some(Self { dist, u_offset: u_offset(rotate_degrees) })
    }

    /// The MIS-compensated sampler of the same grid (see the module documentation): [`Self::new`]
    /// of the weights less their mean over solid angle, max(0, w - mean), so that cells no
    /// brighter than the mean are never sampled. Only for estimators that also sample the BSDF
    /// or phase function and weigh both by MIS with this density. `None` when no weight
    /// exceeds the mean (all equal, or all 0).
    ///
    /// # Panics
    /// If `weights.len() != width * height`.
    pub fn compensated(width: u32, height: u32, weights: &[f32], rotate_degrees: f32) -> Option<Self> {
        let (w, h) = (width as usize, height as usize);
        assert_eq!(weights.len(), w * h, "LatLongSampler: {width} x {height} cells need as many weights");
        // The mean over solid angle: each row's weights counted by the area of its cells.
        let (mut sum, mut area) = (0f64, 0f64);
        for (j, row) in weights.chunks_exact(w.max(1)).enumerate() {
            let sin_theta = row_sin_theta(j, h) as f64;
            sum += sin_theta * row.iter().map(|&x| clean(x) as f64).sum::<f64>();
            area += sin_theta * w as f64;
        }
        if !(area > 0.0) {
            return None;
        }
        let mean = (sum / area) as f32;
        let excess: Vec<f32> = weights.iter().map(|&x| (clean(x) - mean).max(0.0)).collect();
        Self::new(width, height, &excess, rotate_degrees)
    }

    /// The (u, v) of the grid that `dir` looks up (rotation included), and sin theta.
    #[inline]
    fn grid_uv(&self, dir: Vec3A) -> Option<(Vec2, f32)> {
        map_uv(dir, self.u_offset)
    }

    /// Samples a unit direction for `u` in [0, 1)^2; returns it with its density in solid angle,
    /// taken from the sampled (u, v) as pbrt-v4's `ImageInfiniteLight` does: [`Self::pdf`] of
    /// the direction up to round-off (the direction's (u, v) found again can land an ulp into
    /// the next cell). Sampling from the direction found again (its (u, v) by two `atan2`s, the
    /// density looked up again) cost materials-env 11% of its time. `None` in the rare case
    /// where the density there is 0 (a direction at a pole).
    pub fn sample(&self, u: Vec2) -> Option<(Vec3A, f32)> {
        self.sample_at(u).map(|(dir, _, pdf)| (dir, pdf))
    }

    /// [`Self::sample`] with the grid's (u, v) of the direction.
    #[inline]
    fn sample_at(&self, u: Vec2) -> Option<(Vec3A, Vec2, f32)> {
        let (p, grid_pdf) = self.dist.sample_continuous(u);
        let (dir, sin_theta) = uv_to_direction_sin(Vec2::new(p.x - self.u_offset, p.y));
        let pdf = if sin_theta > 0.0 { grid_pdf / (2.0 * PI * PI * sin_theta) } else { 0.0 };
        (pdf > 0.0).then_some((dir, p, pdf))
    }

    /// The density in solid angle of sampling `dir` (any non-zero length): the grid density
    /// p(u, v) / (2 pi^2 sin theta); 0 at the poles, where sin theta = 0.
    pub fn pdf(&self, dir: Vec3A) -> f32 {
        self.grid_uv(dir).map_or(0.0, |at| self.pdf_at(at))
    }

    /// [`Self::pdf`] at the grid's (u, v) and sin theta of a direction.
    #[inline]
    fn pdf_at(&self, (uv, sin_theta): (Vec2, f32)) -> f32 {
        if sin_theta > 0.0 { self.dist.pdf(uv) / (2.0 * PI * PI * sin_theta) } else { 0.0 }
    }
}

/// The (u, v) of a map shifted by `u_offset` that `dir` looks up, and sin theta: shared by the
/// radiance lookup and the sampler's density, so that both see the same cell.
#[inline]
fn map_uv(dir: Vec3A, u_offset: f32) -> Option<(Vec2, f32)> {
    let (uv, sin_theta) = direction_to_uv(dir)?;
    Some((Vec2::new(wrap01(uv.x + u_offset), uv.y), sin_theta))
}

/// Which of an [`EnvironmentMap`]'s two densities a caller samples and weighs with (pbrt-v4's
/// `allowIncompletePDF`; see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvPdf {
    /// In proportion to the cells' luminance bounds: positive wherever there is radiance. For
    /// estimators that sample the map alone.
    Complete,
    /// MIS compensation: 0 for the directions whose cells are no brighter than the mean. Only
    /// for estimators that also sample the BSDF or phase function (reaching every direction the
    /// map is sampled for) and weigh the two by MIS with this density: alone it misses the dim
    /// directions' light.
    Compensated,
}

/// A direction sampled from an [`EnvironmentMap`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    /// Unit direction towards the environment.
    pub dir: Vec3A,
    /// The radiance arriving from `dir` ([`EnvironmentMap::radiance`]).
    pub radiance: Vec3,
    /// The density in solid angle of having sampled `dir`, equal to [`EnvironmentMap::pdf`]
    /// (of the same [`EnvPdf`]).
    pub pdf: f32,
}

/// The brightest texel component of an [`EnvironmentMap`], after scaling: brighter ones are
/// clamped to it, so that luminances and their sums over the largest maps stay finite (a
/// texel of 3e38, finite in the file, has an infinite luminance).
pub const MAX_RADIANCE: f32 = 1e30;

/// An infinitely distant lat-long HDR environment (see the module documentation for the
/// mapping and the rotation), importance-sampled by luminance.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Row-major from the top row, already multiplied by the scale; every component in
    /// [0, [`MAX_RADIANCE`]].
    texels: Vec<Vec3>,
    u_offset: f32,
    /// `None` when the map is black.
    sampler: Option<LatLongSampler>,
    /// The MIS-compensated sampler ([`EnvPdf::Compensated`]); `None` where `sampler` serves
    /// instead (no cell brighter than the mean, or a black map).
    compensated: Option<LatLongSampler>,
    power: f32,
}

impl EnvironmentMap {
    /// A map of `width` x `height` linear RGB `texels` (row-major, the top row first), its
    /// radiance multiplied by `scale`, rotated by `rotate_degrees` about +y (positive =
    /// counter-clockwise seen from above; see the module documentation). Components that are
    /// negative or not finite after scaling count as 0, those above [`MAX_RADIANCE`] as it.
    ///
    /// # Panics
    /// If the size is 0 or `texels.len() != width * height`.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>, scale: f32, rotate_degrees: f32) -> Self {
        assert!(width > 0 && height > 0, "an environment map needs at least one texel");
        assert_eq!(texels.len(), width as usize * height as usize, "{width} x {height} texels expected");
        let (w, h) = (width as usize, height as usize);
        let texels: Vec<Vec3> = texels
            .into_iter()
            .map(|t| {
                let t = t * scale;
                Vec3::new(clean(t.x), clean(t.y), clean(t.z)).min(Vec3::splat(MAX_RADIANCE))
            })
            .collect();
        let lum: Vec<f32> = texels.iter().map(|&t| luminance(t)).collect();

        // Each cell's bound: the largest luminance of the 3 x 3 texels its lookups read, as a
        // separable max (columns wrap, rows clamp).
        let mut across = vec![0f32; w * h];
        for j in 0..h {
            for i in 0..w {
                let row = &lum[j * w..(j + 1) * w];
                across[j * w + i] = row[(i + w - 1) % w].max(row[i]).max(row[(i + 1) % w]);
            }
        }
        let mut bound = vec![0f32; w * h];
        for j in 0..h {
            let (up, down) = (j.saturating_sub(1), (j + 1).min(h - 1));
            for i in 0..w {
                bound[j * w + i] = across[up * w + i].max(across[j * w + i]).max(across[down * w + i]);
            }
        }

        // The luminance integral: each texel's luminance times its cell's solid angle,
        // (2 pi / W) (cos theta_j - cos theta_{j+1}).
        let mut power = 0f64;
        for j in 0..h {
            let cos0 = (std::f64::consts::PI * j as f64 / h as f64).cos();
            let cos1 = (std::f64::consts::PI * (j + 1) as f64 / h as f64).cos();
            let row: f64 = lum[j * w..(j + 1) * w].iter().map(|&l| l as f64).sum();
            power += row * std::f64::consts::TAU / w as f64 * (cos0 - cos1);
        }

        let sampler = LatLongSampler::new(width, height, &bound, rotate_degrees);
        let compensated = LatLongSampler::compensated(width, height, &bound, rotate_degrees);
        Self {
            width,
            height,
            texels,
            u_offset: u_offset(rotate_degrees),
            sampler,
            compensated,
            power: power as f32,
        }
    }

    /// Reads a lat-long map (EXR or HDR, linear float; 8-bit images are decoded from sRGB) with
    /// [`TextureImage::load`] and its bounds on reads and decoding.
    pub fn load(path: &Path, scale: f32, rotate_degrees: f32) -> Result<Self, TextureError> {
        let image = TextureImage::load(path)?;
        Ok(Self::new(image.width, image.height, image.texels(), scale, rotate_degrees))
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The sampler of the map's directions for `pdf`; `None` when the map is black.
    #[inline]
    pub fn sampler(&self, pdf: EnvPdf) -> Option<&LatLongSampler> {
        match pdf {
            EnvPdf::Complete => self.sampler.as_ref(),
            EnvPdf::Compensated => self.compensated.as_ref().or(self.sampler.as_ref()),
        }
    }

    /// The radiance arriving from direction `dir` (any non-zero length; it is normalised
    /// here), scaled, interpolated bilinearly between texels (see the module documentation). Black for a zero or
    /// non-finite direction. Never negative or NaN.
    pub fn radiance(&self, dir: Vec3A) -> Vec3 {
        map_uv(dir, self.u_offset).map_or(Vec3::ZERO, |(uv, _)| self.radiance_at(uv))
    }

    /// [`Self::radiance`] and [`Self::pdf`] of one direction, its (u, v) found once (the
    /// sampler's grid and the map share the rotation).
    #[inline]
    pub fn radiance_pdf(&self, dir: Vec3A, pdf: EnvPdf) -> (Vec3, f32) {
        match map_uv(dir, self.u_offset) {
            Some(at) => (self.radiance_at(at.0), self.sampler(pdf).map_or(0.0, |s| s.pdf_at(at))),
            None => (Vec3::ZERO, 0.0),
        }
    }

    /// The bilinear lookup at the map's (u, v).
    #[inline]
    fn radiance_at(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        // The same product u * W as the sampler's cell lookup (`distribution::cell_of`), so
        // that a lookup in cell i reads only columns i - 1 ..= i + 1, which that cell's bound
        // covers.
        // Columns are texel-centred (periodic in u); rows are corner-aligned, row 0 at v = 0
        // (+y) and row H - 1 at v = 1 (-y), as Mitsuba 3's `envmap` (its `eval_spectrum`):
        // the rows a lookup in the sampler's row j reads stay within j - 1 ..= j + 1.
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * (self.height - 1) as f32;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i0, j0) = (x0 as i64, y0 as i64);
        // Columns wrap: u in [0, 1) gives i0 in -1 ..= W - 1 (others wrap as rem_euclid
        // would, without its division).
        let wrap = |i: i64| if (0..w).contains(&i) { i } else { i.rem_euclid(w) };
        let (i0, i1) = (wrap(i0), wrap(i0 + 1));
        let (j0, j1) = (j0.clamp(0, h - 1), (j0 + 1).clamp(0, h - 1));
        let t = |i: i64, j: i64| self.texels[(j * w + i) as usize];
        let top = t(i0, j0).lerp(t(i1, j0), fx);
        let bottom = t(i0, j1).lerp(t(i1, j1), fx);
        top.lerp(bottom, fy)
    }

    /// Samples a direction for `u` in [0, 1)^2 from the density `pdf`: in proportion (roughly)
    /// to the map's luminance, or to its excess over the mean. `None` when the map is black, or,
    /// rarely, when the sampled direction has density 0.
    pub fn sample(&self, u: Vec2, pdf: EnvPdf) -> Option<EnvSample> {
        // The radiance at the sampled (u, v): `radiance` of the direction up to round-off.
        let (dir, at, density) = self.sampler(pdf)?.sample_at(u)?;
        Some(EnvSample { dir, radiance: self.radiance_at(at), pdf: density })
    }

    /// The density in solid angle with which [`Self::sample`] of the same `pdf` returns `dir`
    /// (any non-zero length); 0 for a black map. [`EnvPdf::Complete`]'s is positive wherever
    /// [`Self::radiance`] is not black (unless the map's luminances span more than about 1e38
    /// to 1); [`EnvPdf::Compensated`]'s only where the cell's bound exceeds the mean.
    pub fn pdf(&self, dir: Vec3A, pdf: EnvPdf) -> f32 {
        self.sampler(pdf).map_or(0.0, |s| s.pdf(dir))
    }

    /// The integral over the sphere of the luminance of the (scaled) radiance, in radiance
    /// times steradians: the sum over texels of luminance times the solid angle of the texel's
    /// cell. 4 pi for a map of radiance 1 everywhere. The power the environment sends into a
    /// scene bounded by a sphere of radius r is about pi r^2 times this (pbrt-v4's
    /// `ImageInfiniteLight::Phi`); to choose between the environment and other lights in
    /// proportion to power, compare that.
    pub fn power_estimate(&self) -> f32 {
        self.power
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::chi2::{chi2, chi2_critical};
    use crate::math::uniform_sphere;
    use crate::testing::uniform;
    use EnvPdf::Complete as C;
    use glam::Quat;

    /// The direction of the texel centre (i, j) of a `w` x `h` unrotated map.
    fn centre(i: u32, j: u32, w: u32, h: u32) -> Vec3A {
        uv_to_direction(Vec2::new((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32))
    }

    fn sun_dir() -> Vec3A {
        Vec3A::new(-0.5, 0.8, -0.6).normalize()
    }

    /// 64 x 32 texels: a smooth sky (brighter upwards) and a sun of 7 degrees radius (about
    /// eight texels) at 500 times the sky, around `sun_dir`.
    fn sun_texels() -> Vec<Vec3> {
        let (w, h) = (64, 32);
        let mut t = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let d = centre(i, j, w, h);
                let sky = Vec3::new(0.4, 0.6, 1.0) * (0.5 + 0.5 * d.y.max(0.0));
                let sun = d.dot(sun_dir()) > 7f32.to_radians().cos();
                t.push(if sun { Vec3::new(500.0, 450.0, 400.0) } else { sky });
            }
        }
        t
    }

    fn sun_map(rotate: f32) -> EnvironmentMap {
        EnvironmentMap::new(64, 32, sun_texels(), 1.0, rotate)
    }

    /// 48 x 24 texels varying smoothly in both directions.
    fn smooth_map() -> EnvironmentMap {
        let (w, h) = (48, 24);
        let mut t = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let d = centre(i, j, w, h);
                let a = 1.0 + 0.8 * (3.0 * d.x).sin() * d.z + 0.5 * d.y;
                t.push(Vec3::new(a, 0.8 * a, 1.2 - 0.3 * d.y));
            }
        }
        EnvironmentMap::new(w, h, t, 1.0, 0.0)
    }

    /// 16 x 8 black texels but a few isolated ones (a corner, the seam, the bottom row, the
    /// middle).
    fn sparse_map(rotate: f32) -> EnvironmentMap {
        let (w, h) = (16, 8);
        let mut t = vec![Vec3::ZERO; w * h];
        t[0] = Vec3::new(1.0, 0.0, 0.0);
        t[3 * w + 15] = Vec3::new(0.0, 0.0, 2.0);
        t[7 * w + 7] = Vec3::new(0.0, 5.0, 0.0);
        t[4 * w + 5] = Vec3::splat(3.0);
        EnvironmentMap::new(w as u32, h as u32, t, 1.0, rotate)
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol * b.abs().max_element().max(1.0)
    }

    #[test]
    fn axes_map_to_the_documented_uv() {
        let uv = |d: Vec3A| direction_to_uv(d).unwrap().0;
        assert_eq!(uv(Vec3A::NEG_Z), Vec2::new(0.0, 0.5)); // left edge
        assert!((uv(Vec3A::X) - Vec2::new(0.25, 0.5)).abs().max_element() < 1e-6);
        assert!((uv(Vec3A::Z) - Vec2::new(0.5, 0.5)).abs().max_element() < 1e-6);
        assert!((uv(Vec3A::NEG_X) - Vec2::new(0.75, 0.5)).abs().max_element() < 1e-6);
        assert_eq!(uv(Vec3A::Y).y, 0.0); // top row
        assert_eq!(uv(Vec3A::NEG_Y).y, 1.0);
        // Length does not matter; zero and NaN directions have no uv.
        assert_eq!(uv(Vec3A::new(0.0, 0.0, -7.0)), Vec2::new(0.0, 0.5));
        assert!(direction_to_uv(Vec3A::ZERO).is_none());
        assert!(direction_to_uv(Vec3A::new(f32::NAN, 0.0, 1.0)).is_none());
        // uv_to_direction inverts it.
        let mut r = uniform(3);
        for _ in 0..1000 {
            let p = Vec2::new(r(), 0.001 + 0.998 * r());
            let d = uv_to_direction(p);
            assert!((d.length() - 1.0).abs() < 1e-6);
            let q = direction_to_uv(d).unwrap().0;
            let du = (q.x - p.x).abs();
            assert!(du.min(1.0 - du) < 1e-5 && (q.y - p.y).abs() < 1e-5, "{p} {q}");
        }
    }

    #[test]
    fn a_bright_texel_is_brightest_in_its_direction_and_rotates_counter_clockwise_from_above() {
        // 6 x 3 texels: column 1's centre is u = 0.25 (+x), row 1's is the equator.
        let mut t = vec![Vec3::splat(0.1); 18];
        t[6 + 1] = Vec3::new(100.0, 50.0, 20.0);
        let plain = EnvironmentMap::new(6, 3, t.clone(), 1.0, 0.0);
        let turned = EnvironmentMap::new(6, 3, t, 1.0, 90.0);
        assert!(close(plain.radiance(Vec3A::X), Vec3::new(100.0, 50.0, 20.0), 1e-4));
        // +90 degrees, right-handed about +y: +x goes to -z.
        assert!(close(turned.radiance(Vec3A::NEG_Z), Vec3::new(100.0, 50.0, 20.0), 1e-4));
        assert!(close(turned.radiance(Vec3A::X), Vec3::splat(0.1), 1e-4));
        // The brightest of many directions is next to +x (resp. -z).
        let mut r = uniform(5);
        let (mut best, mut best_turned) = ((0.0, Vec3A::ZERO), (0.0, Vec3A::ZERO));
        for _ in 0..20000 {
            let d = uniform_sphere(Vec2::new(r(), r()));
            let keep = |b: &mut (f32, Vec3A), x: f32| {
                if x > b.0 {
                    *b = (x, d)
                }
            };
            keep(&mut best, luminance(plain.radiance(d)));
            keep(&mut best_turned, luminance(turned.radiance(d)));
        }
        assert!(best.1.dot(Vec3A::X) > 0.99, "{:?}", best);
        assert!(best_turned.1.dot(Vec3A::NEG_Z) > 0.99, "{:?}", best_turned);
        // The density moves with the light: at the equator it is highest there.
        assert_eq!(plain.pdf(Vec3A::X, C), turned.pdf(Vec3A::NEG_Z, C));
        assert!(plain.pdf(Vec3A::X, C) > 50.0 * plain.pdf(Vec3A::NEG_X, C));
        assert!(turned.pdf(Vec3A::NEG_Z, C) > 50.0 * turned.pdf(Vec3A::Z, C));

        // Any angle: the turned map shows in R_y(a) d what the plain one shows in d (glam's
        // rotation is right-handed), and its density moves with it.
        let texels = sun_texels();
        let plain = EnvironmentMap::new(64, 32, texels.clone(), 1.0, 0.0);
        for a in [37.0f32, -120.0, 450.0] {
            let turned = EnvironmentMap::new(64, 32, texels.clone(), 1.0, a);
            let rot = Quat::from_rotation_y(a.to_radians());
            let mut differ = 0;
            for _ in 0..2000 {
                let d = uniform_sphere(Vec2::new(r(), r()));
                let e = rot * d;
                assert!(close(turned.radiance(e), plain.radiance(d), 1e-3), "{a} {d}");
                let (p, q) = (turned.pdf(e, C), plain.pdf(d, C));
                // Equal but where a cell boundary falls between the two roundings.
                differ += ((p - q).abs() > 1e-3 * q) as usize;
            }
            assert!(differ < 10, "{a}: {differ} densities differ");
        }

        // The top row is +y, the bottom row -y.
        let mut t = vec![Vec3::ONE; 8 * 4];
        t[..8].fill(Vec3::splat(10.0));
        let m = EnvironmentMap::new(8, 4, t, 1.0, 0.0);
        assert_eq!(m.radiance(Vec3A::Y), Vec3::splat(10.0));
        assert_eq!(m.radiance(Vec3A::NEG_Y), Vec3::ONE);
    }

    #[test]
    fn bilinear_hits_texels_and_means_halfway_across_the_seam() {
        let (w, h) = (8u32, 4u32);
        let mut r = uniform(11);
        let t: Vec<Vec3> = (0..w * h).map(|_| Vec3::new(r(), r(), r()) * 10.0).collect();
        let m = EnvironmentMap::new(w, h, t.clone(), 2.0, 0.0);
        let at = |i: u32, j: u32| 2.0 * t[(j * w + i) as usize];
        // At the map's (u, v): the poles' directions have no azimuth.
        let look = |u: f32, v: f32| m.radiance_at(Vec2::new(u, v));
        // Texel (i, j) lies at u = (i + 0.5) / W, v = j / (H - 1).
        let row = |j: f32| j / (h - 1) as f32;
        for j in 0..h {
            let vc = row(j as f32);
            for i in 0..w {
                let uc = (i as f32 + 0.5) / w as f32;
                assert!(close(look(uc, vc), at(i, j), 1e-4), "texel {i} {j}");
                // Halfway to the right neighbour; column w - 1's is column 0, across u = 0/1.
                let right = (i + 1) % w;
                let mean = (at(i, j) + at(right, j)) / 2.0;
                assert!(close(look((i as f32 + 1.0) / w as f32, vc), mean, 1e-4), "{i} {j}");
                if j + 1 < h {
                    let mean = (at(i, j) + at(i, j + 1)) / 2.0;
                    assert!(close(look(uc, row(j as f32 + 0.5)), mean, 1e-4), "{i} {j}");
                }
            }
        }
        // The seam itself, u = 0 (the direction -z), and the poles, where the first and last
        // rows lie.
        assert!(close(
            m.radiance(uv_to_direction(Vec2::new(0.0, row(1.0)))),
            (at(7, 1) + at(0, 1)) / 2.0,
            1e-4
        ));
        assert!(close(look(0.5 / w as f32, 0.0), at(0, 0), 1e-4));
        assert!(close(look(0.5 / w as f32, 1.0), at(0, h - 1), 1e-4));
        // A quarter of the way in u and v: the bilinear weights.
        let (u, v) = (2.75 / w as f32, row(1.25));
        let want = (at(2, 1) * 0.75 * 0.75 + at(3, 1) * 0.25 * 0.75)
            + (at(2, 2) * 0.75 * 0.25 + at(3, 2) * 0.25 * 0.25);
        assert!(close(look(u, v), want, 1e-4));
    }

    /// Whether `a` and `b` agree up to round-off.
    fn agree(a: f32, b: f32) -> bool {
        (a - b).abs() <= 1e-4 * a.abs().max(b.abs())
    }

    /// A sample's density and radiance are those of its direction, up to round-off: the
    /// direction's (u, v) found again may land an ulp into the next cell (at most 1 in 2000
    /// samples here), where the density can be another cell's.
    #[test]
    fn sample_pdf_agrees_with_pdf() {
        for m in [sun_map(0.0), sun_map(-33.0), smooth_map(), sparse_map(71.0)] {
            for pdf in [C, EnvPdf::Compensated] {
                let mut r = uniform(13);
                let n = 20000;
                let mut other_cell = 0;
                for _ in 0..n {
                    let s = m.sample(Vec2::new(r(), r()), pdf).unwrap();
                    assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{s:?} {pdf:?}");
                    assert!((s.dir.length() - 1.0).abs() < 1e-5);
                    let (radiance, density) = m.radiance_pdf(s.dir, pdf);
                    if !agree(s.pdf, density) {
                        other_cell += 1;
                        continue;
                    }
                    // The bilinear lookup an ulp or two of (u, v) away: beside a sun texel 1e5
                    // times its neighbours, that moves it by up to about 1e-3.
                    let near = |a: f32, b: f32| (a - b).abs() <= 1e-2 * a.abs().max(b.abs());
                    assert!((0..3).all(|c| near(s.radiance[c], radiance[c])), "{s:?} {radiance}");
                }
                assert!(other_cell * 2000 <= n, "{other_cell} of {n} samples' densities disagree");
            }
        }
    }

    /// Chi-square of `n` of the map's samples from its density `pdf` against that density about
    /// `axis`, on the cap z >= z_min (samples outside it are dropped: the expected counts
    /// integrate the pdf over the cap only).
    fn chi2_ok(m: &EnvironmentMap, pdf: EnvPdf, axis: Vec3A, z_min: f32, n: usize, what: &str) {
        let (stat, dof) = chi2(
            |u, _| m.sample(u, pdf).map(|s| s.dir).filter(|d| d.dot(axis) >= z_min),
            |d| m.pdf(d, pdf),
            axis,
            z_min as f64,
            n,
        );
        assert!(stat < chi2_critical(dof), "{what}, {pdf:?}: chi2 {stat} dof {dof}");
    }

    #[test]
    fn sampling_matches_pdf_chi2_sun() {
        let m = sun_map(25.0);
        let sun = Quat::from_rotation_y(25f32.to_radians()) * sun_dir();
        assert!(luminance(m.radiance(sun)) > 400.0);
        // Over the whole sphere the helper's cells are about 9 degrees wide and its expected
        // counts come from a 24 x 24 midpoint rule per cell, which misplaces about 1% of the
        // mass where the density steps by 500 to 1 at the sun's edge: with many more samples
        // than these the statistic would measure that quadrature error rather than the
        // sampling. The axis is tilted off +y so that the cells' edges do not line up with
        // the map's (aligned, the rule's error is systematic).
        let near_y = Vec3A::new(0.1, 1.0, 0.05).normalize();
        chi2_ok(&m, C, near_y, -1.0, 200_000, "sun, about +y");
        chi2_ok(&m, C, sun, -1.0, 200_000, "sun, about the sun");
        // A cap of 20 degrees about the sun: cells of about 0.2 x 9 degrees, quadrature points
        // 0.02 degrees apart, many samples: the sun's texels and their edges are resolved. The
        // compensated density lies wholly in that cap (the sun and the ring of cells its bound
        // reaches; the sky is below the mean), where it steps from its highest to 0: only there
        // does the rule resolve it (over the sphere, chi2 56 for 18 degrees of freedom).
        for pdf in [C, EnvPdf::Compensated] {
            chi2_ok(&m, pdf, sun, 20f32.to_radians().cos(), 1_000_000, "sun, cap about the sun");
        }
    }

    #[test]
    fn sampling_matches_pdf_chi2_smooth() {
        let m = smooth_map();
        for pdf in [C, EnvPdf::Compensated] {
            chi2_ok(&m, pdf, Vec3A::Y, -1.0, 1_000_000, "smooth, about +y");
            chi2_ok(&m, pdf, Vec3A::new(0.3, -0.2, 0.9).normalize(), -1.0, 1_000_000, "smooth, tilted");
        }
    }

    /// The integral of `f` over the sphere, midpoint rule on an equal-area (cos theta, phi) grid
    /// about +z (so the poles of the map, on the y axis, are not grid poles).
    fn sphere_quadrature(f: impl Fn(Vec3A) -> f64, nz: usize, nphi: usize) -> f64 {
        let mut sum = 0.0;
        for i in 0..nz {
            let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
            let s = (1.0 - z * z).sqrt();
            for k in 0..nphi {
                let phi = std::f64::consts::TAU * (k as f64 + 0.5) / nphi as f64;
                sum += f(Vec3A::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32));
            }
        }
        sum * 4.0 * std::f64::consts::PI / (nz * nphi) as f64
    }

    #[test]
    fn pdf_integrates_to_one() {
        let maps = [("sun", sun_map(10.0)), ("smooth", smooth_map()), ("sparse", sparse_map(0.0))];
        for ((name, m), pdf) in maps.iter().flat_map(|m| [(m, C), (m, EnvPdf::Compensated)]) {
            let total = sphere_quadrature(|d| m.pdf(d, pdf) as f64, 1200, 2400);
            assert!((total - 1.0).abs() < 2e-3, "{name} {pdf:?}: {total}");
            // In (u, v), where d omega = 2 pi^2 sin theta du dv, on a grid finer than the cells.
            let (nu, nv) = (m.width() as usize * 8, m.height() as usize * 8);
            let mut sum = 0.0;
            for j in 0..nv {
                let v = (j as f32 + 0.5) / nv as f32;
                for i in 0..nu {
                    let d = uv_to_direction(Vec2::new((i as f32 + 0.5) / nu as f32, v));
                    sum += (m.pdf(d, pdf) * 2.0 * PI * PI * (PI * v).sin()) as f64;
                }
            }
            let total = sum / (nu * nv) as f64;
            assert!((total - 1.0).abs() < 1e-4, "{name} {pdf:?}: {total} in uv");
        }
    }

    #[test]
    fn pdf_is_positive_wherever_radiance_is() {
        for rotate in [0.0, 33.0] {
            let m = sparse_map(rotate);
            let mut r = uniform(21);
            let mut lit = 0;
            for _ in 0..200_000 {
                let d = uniform_sphere(Vec2::new(r(), r()));
                if m.radiance(d).max_element() > 0.0 {
                    lit += 1;
                    assert!(m.pdf(d, C) > 0.0, "{d}");
                }
            }
            assert!(lit > 1000);
        }
        // Every cell, on a grid of points reaching to within 1e-4 of its edges: no cell whose
        // bound is 0 shows light. Light does reach beyond the lit texels' own cells (so a
        // bound from the cell's texel alone would fail), and cells away from them have no
        // density (the bound is local).
        let m = sparse_map(0.0);
        let (w, h) = (16usize, 8usize);
        let (mut lit_cells, mut dense_cells) = (0, 0);
        for j in 0..h {
            for i in 0..w {
                let mut any_light = false;
                let mut any_density = false;
                for a in 0..=10 {
                    for b in 0..=10 {
                        let f = |k: usize| (k as f32 / 10.0).clamp(1e-4, 1.0 - 1e-4);
                        let uv = Vec2::new((i as f32 + f(a)) / w as f32, (j as f32 + f(b)) / h as f32);
                        let d = uv_to_direction(uv);
                        let light = m.radiance(d).max_element() > 0.0;
                        let p = m.pdf(d, C);
                        assert!(!light || p > 0.0, "cell {i} {j} at {uv}");
                        any_light |= light;
                        any_density |= p > 0.0;
                    }
                }
                lit_cells += any_light as usize;
                dense_cells += any_density as usize;
            }
        }
        // 4 isolated texels light their 3 x 3 neighbourhoods (the top corner's and the bottom
        // one's clamped to 3 x 2, the seam's wrapping): 6 + 9 + 6 + 9 cells.
        assert_eq!(lit_cells, 30);
        // And the bound is tight: exactly those cells have density.
        assert_eq!(dense_cells, 30);
        // Two cells away from every lit texel: no density.
        assert_eq!(m.pdf(centre(10, 1, 16, 8), C), 0.0);
    }

    #[test]
    fn importance_sampling_beats_uniform_sampling() {
        let m = sun_map(0.0);
        let n = 200_000;
        let stats = |mut f: Box<dyn FnMut() -> f64>| {
            let (mut s, mut s2) = (0.0, 0.0);
            for _ in 0..n {
                let x = f();
                s += x;
                s2 += x * x;
            }
            let mean = s / n as f64;
            (mean, (s2 / n as f64 - mean * mean) / (mean * mean))
        };
        let mut r = uniform(31);
        let (mean_is, relvar_is) = stats(Box::new(|| match m.sample(Vec2::new(r(), r()), C) {
            Some(s) => luminance(s.radiance) as f64 / s.pdf as f64,
            None => 0.0,
        }));
        let mut r = uniform(37);
        let (mean_uni, relvar_uni) = stats(Box::new(|| {
            let d = uniform_sphere(Vec2::new(r(), r()));
            luminance(m.radiance(d)) as f64 * 4.0 * std::f64::consts::PI
        }));
        assert!(relvar_uni > 20.0 * relvar_is, "relative variance {relvar_is} vs uniform {relvar_uni}");
        // Both estimate the same integral, which the power estimate approximates.
        let exact = sphere_quadrature(|d| luminance(m.radiance(d)) as f64, 1200, 2400);
        assert!((mean_is / exact - 1.0).abs() < 0.01, "{mean_is} {exact}");
        assert!((mean_uni / exact - 1.0).abs() < 0.1, "{mean_uni} {exact}");
        assert!((m.power_estimate() as f64 / exact - 1.0).abs() < 0.05, "{} {exact}", m.power_estimate());
    }

    /// The compensated density is the complete one's excess over the mean: 0 on the sun map's
    /// sky (all of it dimmer than the mean, which the sun raises), higher than the complete
    /// density on the sun; on the smooth map 0 exactly where the cell's bound is at most the
    /// solid-angle mean of the bounds.
    #[test]
    fn compensated_density_leaves_cells_below_the_mean_to_bsdf_sampling() {
        let m = sun_map(0.0);
        let comp = EnvPdf::Compensated;
        // The sky holds about 6% of the complete density's cells' weight: that moves to the sun.
        assert!(m.pdf(sun_dir(), comp) > 1.05 * m.pdf(sun_dir(), C));
        for d in [Vec3A::X, Vec3A::NEG_X, Vec3A::new(0.2, 0.9, 0.3), Vec3A::new(0.1, -0.7, 0.4)] {
            assert!(m.pdf(d, C) > 0.0 && m.pdf(d, comp) == 0.0, "{d}");
        }
        // The smooth map's bounds, recomputed as `EnvironmentMap::new` does (the 3 x 3 maximum
        // of the texels' luminance), against their mean over solid angle.
        let (w, h) = (48u32, 24u32);
        let m = smooth_map();
        let lum =
            |i: i64, j: i64| {
                let (i, j) = (i.rem_euclid(w as i64) as u32, j.clamp(0, h as i64 - 1) as u32);
                luminance(m.radiance(uv_to_direction(Vec2::new(
                    (i as f32 + 0.5) / w as f32,
                    j as f32 / (h - 1) as f32,
                ))))
            };
        let mut bound = vec![0f32; (w * h) as usize];
        for j in 0..h as i64 {
            for i in 0..w as i64 {
                let mut b = 0f32;
                for (di, dj) in (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))) {
                    b = b.max(lum(i + di, j + dj));
                }
                bound[(j * w as i64 + i) as usize] = b;
            }
        }
        let (mut sum, mut area) = (0f64, 0f64);
        for j in 0..h as usize {
            let s = row_sin_theta(j, h as usize) as f64;
            sum += s * bound[j * w as usize..(j + 1) * w as usize].iter().map(|&b| b as f64).sum::<f64>();
            area += s * w as f64;
        }
        let mean = sum / area;
        let (mut above, mut below) = (0, 0);
        for j in 0..h {
            for i in 0..w {
                let b = bound[(j * w + i) as usize] as f64;
                // Cells within rounding of the mean say nothing.
                if (b - mean).abs() < 1e-4 * mean {
                    continue;
                }
                let p = m.pdf(centre(i, j, w, h), comp);
                match b > mean {
                    true => above += (p > 0.0) as usize,
                    false => below += (p == 0.0) as usize,
                }
                assert_eq!(p > 0.0, b > mean, "cell {i} {j}: bound {b}, mean {mean}, density {p}");
            }
        }
        assert!(above > 200 && below > 200, "{above} cells above the mean, {below} below");
    }

    /// A constant map has no cell above its mean: the compensated density falls back to the
    /// complete one (pbrt-v4 does the same), which stays uniform over the sphere. A map that is
    /// black but for equal texels everywhere they are lit is compensated as usual.
    #[test]
    fn constant_map_falls_back_to_the_complete_density() {
        for (w, h, c) in [(7, 5, 1.0), (64, 32, 0.37), (1, 1, 2.0), (3, 200, 1e30)] {
            let m = EnvironmentMap::new(w, h, vec![Vec3::splat(c); (w * h) as usize], 1.0, 20.0);
            assert!(m.compensated.is_none(), "{w} x {h}");
            assert_eq!(m.sampler(EnvPdf::Compensated), m.sampler(C));
            let mut r = uniform(5);
            for _ in 0..1000 {
                let u = Vec2::new(r(), r());
                let (a, b) = (m.sample(u, C).unwrap(), m.sample(u, EnvPdf::Compensated).unwrap());
                assert!(a == b && b.pdf.is_finite() && b.pdf > 0.0, "{a:?} {b:?}");
            }
        }
        assert!(LatLongSampler::compensated(4, 2, &[1.5; 8], 0.0).is_none());
        assert!(LatLongSampler::compensated(4, 2, &[0.0; 8], 0.0).is_none());
        assert!(LatLongSampler::compensated(0, 0, &[], 0.0).is_none());
        // NaN, infinite and negative weights count as 0, as in `new`; what is left is compensated.
        let weights = [f32::NAN, 1.0, f32::INFINITY, -3.0, 1.0, 0.0, 5.0, 0.0];
        let s = LatLongSampler::compensated(4, 2, &weights, 0.0).unwrap();
        let mut r = uniform(6);
        for _ in 0..1000 {
            let (d, pdf) = s.sample(Vec2::new(r(), r())).unwrap();
            assert!(pdf.is_finite() && agree(pdf, s.pdf(d)));
            // The mean is 7 / 8: the cells of weight 1 and 5 exceed it.
            let (uv, _) = direction_to_uv(d).unwrap();
            let cell = ((uv.x * 4.0) as u32, (uv.y * 2.0) as u32);
            assert!([(1, 0), (0, 1), (2, 1)].contains(&cell), "{d} in {cell:?}");
        }
    }

    /// What the compensated density is for, and where it must not go: the sun map's integral
    /// of luminance estimated by (a) light sampling alone with the complete density, (b) the
    /// compensated density combined by the power heuristic with uniform sphere sampling (a
    /// stand-in for BSDF sampling, which reaches every direction), and (c) light sampling alone
    /// with the compensated density. (a) and (b) are unbiased, and (b) is less noisy than the
    /// same MIS with the complete density; (c) misses the sky and must fail (by more than 10%):
    /// the deliberate error of using the compensated density where no MIS happens.
    #[test]
    fn compensated_density_is_unbiased_with_mis_only() {
        let m = sun_map(0.0);
        let exact = sphere_quadrature(|d| luminance(m.radiance(d)) as f64, 1200, 2400);
        let n = 200_000;
        let power = |a: f32, b: f32| (a * a / (a * a + b * b)) as f64;
        let uniform_pdf = 1.0 / (4.0 * PI);
        // One light sample and one uniform sample, each weighted against the other technique.
        let mis = |pdf: EnvPdf, seed| {
            let mut r = uniform(seed);
            let (mut s, mut s2) = (0.0, 0.0);
            for _ in 0..n {
                let mut x = 0.0;
                if let Some(l) = m.sample(Vec2::new(r(), r()), pdf) {
                    x += luminance(l.radiance) as f64 / l.pdf as f64 * power(l.pdf, uniform_pdf);
                }
                let d = uniform_sphere(Vec2::new(r(), r()));
                let (le, p) = m.radiance_pdf(d, pdf);
                x += luminance(le) as f64 / uniform_pdf as f64 * power(uniform_pdf, p);
                (s, s2) = (s + x, s2 + x * x);
            }
            let mean = s / n as f64;
            (mean, s2 / n as f64 - mean * mean)
        };
        let alone = |pdf: EnvPdf, seed| {
            let mut r = uniform(seed);
            let sum: f64 = (0..n)
                .filter_map(|_| m.sample(Vec2::new(r(), r()), pdf))
                .map(|l| luminance(l.radiance) as f64 / l.pdf as f64)
                .sum();
            sum / n as f64
        };
        let complete_alone = alone(C, 51);
        assert!((complete_alone / exact - 1.0).abs() < 0.01, "{complete_alone} {exact}");
        let (comp_mis, comp_var) = mis(EnvPdf::Compensated, 53);
        assert!((comp_mis / exact - 1.0).abs() < 0.01, "{comp_mis} {exact}");
        let (complete_mis, complete_var) = mis(C, 53);
        assert!((complete_mis / exact - 1.0).abs() < 0.01, "{complete_mis} {exact}");
        assert!(comp_var < 0.9 * complete_var, "variance {comp_var} compensated, {complete_var} complete");
        let comp_alone = alone(EnvPdf::Compensated, 55);
        assert!(comp_alone / exact - 1.0 < -0.1, "{comp_alone} {exact}: the sky is not missed");
    }

    #[test]
    fn power_estimate_scale_and_black_maps() {
        let m = EnvironmentMap::new(7, 5, vec![Vec3::ONE; 35], 1.0, 0.0);
        assert!((m.power_estimate() - 4.0 * PI).abs() < 1e-4);
        let m3 = EnvironmentMap::new(7, 5, vec![Vec3::ONE; 35], 3.0, 0.0);
        assert!((m3.power_estimate() - 12.0 * PI).abs() < 1e-4);
        assert_eq!(m3.radiance(Vec3A::new(0.3, 0.2, 0.1)), Vec3::splat(3.0));
        // The scale does not change the density.
        let d = Vec3A::new(0.3, -0.4, 0.5);
        assert_eq!(m.pdf(d, C), m3.pdf(d, C));
        let (a, b) = (sun_map(0.0), EnvironmentMap::new(64, 32, sun_texels(), 0.01, 0.0));
        assert!((a.pdf(sun_dir(), C) - b.pdf(sun_dir(), C)).abs() < 1e-5 * a.pdf(sun_dir(), C));

        // Black (and negative or NaN) maps: nothing to sample, no density, no light.
        let t = vec![Vec3::ZERO, Vec3::splat(-1.0), Vec3::NAN, Vec3::new(0.0, f32::INFINITY, 0.0)];
        for m in
            [EnvironmentMap::new(2, 2, t, 1.0, 0.0), EnvironmentMap::new(2, 2, vec![Vec3::ONE; 4], 0.0, 0.0)]
        {
            assert!(m.sampler(C).is_none() && m.sampler(EnvPdf::Compensated).is_none());
            assert!(m.sample(Vec2::new(0.3, 0.7), C).is_none());
            assert_eq!(m.pdf(Vec3A::X, C), 0.0);
            assert_eq!(m.radiance(Vec3A::X), Vec3::ZERO);
            assert_eq!(m.power_estimate(), 0.0);
        }
        // Directions that are not directions.
        let m = smooth_map();
        for d in [Vec3A::ZERO, Vec3A::NAN, Vec3A::new(f32::INFINITY, 0.0, 0.0)] {
            assert_eq!(m.radiance(d), Vec3::ZERO);
            assert_eq!(m.pdf(d, C), 0.0);
        }
        // The poles have no density (sin theta = 0) but radiance.
        assert_eq!(m.pdf(Vec3A::Y, C), 0.0);
        assert!(m.radiance(Vec3A::Y).max_element() > 0.0);
        // A 1 x 1 map is uniform in (u, v), so 1 / (2 pi^2 sin theta) in solid angle.
        let one = EnvironmentMap::new(1, 1, vec![Vec3::splat(2.0)], 1.0, 0.0);
        let d = Vec3A::new(0.2, 0.5, -0.3);
        let want = 1.0 / (2.0 * PI * PI * direction_to_uv(d).unwrap().1);
        assert!((one.pdf(d, C) - want).abs() < 1e-6 * want);
        assert_eq!(one.radiance(Vec3A::Z), Vec3::splat(2.0));
    }

    #[test]
    fn lat_long_sampler_serves_an_analytic_sky() {
        // A sky brighter towards the zenith, dim below the horizon, sampled by 64 bands.
        let sky = |d: Vec3A| if d.y > 0.0 { 0.2 + 2.0 * d.y * d.y } else { 0.05 };
        let h = 64;
        let bands: Vec<f32> = (0..h).map(|j| sky(centre(0, j, 1, h)).max(0.2)).collect();
        let s = LatLongSampler::new(1, h, &bands, 0.0).unwrap();
        let (stat, dof) = chi2(|u, _| s.sample(u).map(|x| x.0), |d| s.pdf(d), Vec3A::Y, -1.0, 400_000);
        assert!(stat < chi2_critical(dof), "chi2 {stat} dof {dof}");
        let mut r = uniform(41);
        let n = 100_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let (d, pdf) = s.sample(Vec2::new(r(), r())).unwrap();
            assert!(agree(pdf, s.pdf(d)), "{pdf} {}", s.pdf(d));
            sum += (sky(d) / pdf) as f64;
        }
        // The integral of the sky: 2 pi (0.2 + 2 / 3) above, 2 pi 0.05 below.
        let exact = std::f64::consts::TAU * (0.2 + 2.0 / 3.0 + 0.05);
        assert!((sum / n as f64 / exact - 1.0).abs() < 0.01, "{} {exact}", sum / n as f64);
        assert!(LatLongSampler::new(1, 4, &[0.0; 4], 0.0).is_none());
        assert!(LatLongSampler::new(0, 0, &[], 0.0).is_none());
    }

    /// The sun map of materials-env (scenes/assets, as tests/references holds it): 512 x 256, a
    /// 3-degree sun around normalize(-0.5, 0.8, -0.6).
    #[test]
    fn reference_sun_map_is_brightest_where_its_sun_is() {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/assets/env-sun.exr"));
        let m = EnvironmentMap::load(path, 1.0, 0.0).unwrap();
        assert_eq!((m.width(), m.height()), (512, 256));
        // The brightest texel, and the luminance-weighted centre of the texels above half of it.
        let (w, h) = (m.width(), m.height());
        let mut best = (0.0, Vec3A::ZERO);
        for j in 0..h {
            for i in 0..w {
                let d = centre(i, j, w, h);
                let y = luminance(m.radiance(d));
                if y > best.0 {
                    best = (y, d);
                }
            }
        }
        let mut c = Vec3A::ZERO;
        for j in 0..h {
            for i in 0..w {
                let d = centre(i, j, w, h);
                let y = luminance(m.radiance(d));
                if y > 0.5 * best.0 {
                    c += d * y * (PI * (j as f32 + 0.5) / h as f32).sin();
                }
            }
        }
        let sun = sun_dir();
        assert!(best.1.dot(sun) > 3.5f32.to_radians().cos(), "brightest texel at {}", best.1);
        assert!(c.normalize().dot(sun) > 0.5f32.to_radians().cos(), "sun centre at {}", c.normalize());
        // Importance sampling finds it: about half the light, so far more than its share of the
        // sphere (a 3-degree disk is 0.07% of it).
        let mut r = uniform(43);
        let near = (0..20000)
            .filter(|_| m.sample(Vec2::new(r(), r()), C).unwrap().dir.dot(sun) > 5f32.to_radians().cos())
            .count();
        assert!(near > 4000, "{near} of 20000 samples near the sun");
    }

    /// Found by the image fuzzer: a texel of 3e38 (finite in an HDR file) had an infinite
    /// luminance, and the map an infinite power.
    #[test]
    fn texels_brighter_than_the_bound_are_clamped_to_it() {
        let m = EnvironmentMap::new(2, 1, vec![Vec3::splat(3e38), Vec3::ONE], 1.0, 0.0);
        assert!(m.power_estimate().is_finite() && m.power_estimate() > 0.0, "{}", m.power_estimate());
        let s = m.sample(Vec2::new(0.1, 0.5), C).unwrap();
        assert!(s.radiance.max_element() <= MAX_RADIANCE && s.radiance.min_element() > 0.0, "{s:?}");
        assert!(s.pdf.is_finite() && s.pdf > 0.0, "{s:?}");
    }
}
