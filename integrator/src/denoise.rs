//! A denoiser in plain Rust: the edge-avoiding à-trous wavelet filter of Dammertz et al. (HPG
//! 2010) with the variance-guided luminance weight of SVGF (Schied et al., HPG 2017), guided by
//! the albedo and normal images of [`crate::aov`].
//!
//! Emission seen directly (lights, the sky) is taken out first and added back at the end: it is
//! not noise, and its edges are the sharpest in the image. The rest is divided by the albedo
//! (texture detail then survives the blur: only the illumination is filtered) and multiplied
//! back at the end. Each of the passes blurs with a
//! 5x5 B3-spline kernel whose taps lie `2^i` pixels apart, each tap weighted by how alike the
//! two pixels are: normals (`max(0, n_p . n_q)^normal_power`), albedos
//! (`exp(-|a_p - a_q|^2 / sigma_albedo^2)`) and illumination, whose difference is measured
//! against the pixel's own noise (`exp(-|l_p - l_q| / (sigma_luminance sd_p))`, sd the standard
//! deviation of the pixel mean, from the film's sums of squares, filtered along with the
//! colour). Where the guides agree and the noise is large the kernel spreads; across an edge
//! of the guides, or a difference the noise cannot explain, it stops.

use crate::aov::Aovs;
use glam::Vec3;
use rayon::prelude::*;

/// Filter settings. SVGF uses 5 passes and `sigma_luminance` 4 on variance accumulated over
/// frames; on single frames of 16-64 spp (cornell-diffuse, cornell, mesh, cornell-smoke
/// against their references) 4 passes and 2 keep 8x8-block means closer to the reference
/// (the wider, looser filter carries light across illumination gradients: up to 9% off in a
/// dark corner at 16 spp, where the noisy render is 7% off) for a relMSE within 10-30% of
/// the loosest (benches/results/denoiser.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Passes; the kernel reaches `2^(passes + 1)` pixels.
    pub passes: u32,
    /// Illumination differences are allowed this many standard deviations of the noise.
    pub sigma_luminance: f32,
    /// Exponent of the normals' cosine.
    pub normal_power: f32,
    /// Albedo difference (RGB distance) at which a tap keeps `1/e` of its weight.
    pub sigma_albedo: f32,
}

impl Default for Options {
    fn default() -> Self {
        Self { passes: 4, sigma_luminance: 2.0, normal_power: 128.0, sigma_albedo: 0.1 }
    }
}

/// Rec. 709 luminance weights.
const LUMA: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Albedo channels are divided out as at least this (a black channel would divide by zero; a
/// switch between dividing and not, per pixel, would make neighbours incomparable).
const MIN_ALBEDO: f32 = 0.02;

/// Denoises `color` (per-pixel means) given the variance of each mean (per channel; infinite
/// where unknown, which leaves only the guides to stop the kernel) and the guides.
pub fn denoise(color: &[Vec3], variance: &[Vec3], aovs: &Aovs, opts: &Options) -> Vec<Vec3> {
    let _span = tracing::info_span!("denoise", width = aovs.width, height = aovs.height).entered();
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    assert!(color.len() == w * h && variance.len() == w * h && aovs.albedo.len() == w * h);
    let divisor: Vec<Vec3> = aovs.albedo.iter().map(|a| a.max(Vec3::splat(MIN_ALBEDO))).collect();
    // The emission taken out is at most the pixel's colour: where the film discarded samples
    // (non-finite, or above its cap) that the emission image kept, the difference would be
    // negative, and the result too.
    let emission: Vec<Vec3> =
        aovs.emission.iter().zip(color).map(|(le, c)| le.min(*c).max(Vec3::ZERO)).collect();
    let mut e: Vec<Vec3> =
        color.iter().zip(&emission).zip(&divisor).map(|((c, le), d)| (*c - *le) / *d).collect();
    // Variance of the illumination's luminance (channels taken as independent).
    let mut var: Vec<f32> =
        variance.iter().zip(&divisor).map(|(v, d)| (*v * LUMA * LUMA / (*d * *d)).element_sum()).collect();
    let normal: Vec<Vec3> = aovs.normal.iter().map(|n| n.normalize_or_zero()).collect();
    let guides = Guides { w, h, normal: &normal, albedo: &aovs.albedo };
    for pass in 0..opts.passes {
        let smooth = blur3(&var, w, h);
        let (ne, nv) = guides.pass(&e, &var, &smooth, 1 << pass, opts);
        (e, var) = (ne, nv);
    }
    e.iter().zip(&divisor).zip(&emission).map(|((e, d), le)| *e * *d + *le).collect()
}

/// The guide images of one denoise.
struct Guides<'a> {
    w: usize,
    h: usize,
    normal: &'a [Vec3],
    albedo: &'a [Vec3],
}

impl Guides<'_> {
    /// One à-trous pass with taps `step` apart: the filtered illumination and its variance.
    fn pass(
        &self,
        e: &[Vec3],
        var: &[f32],
        smooth: &[f32],
        step: usize,
        o: &Options,
    ) -> (Vec<Vec3>, Vec<f32>) {
        const K: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];
        let (w, h) = (self.w, self.h);
        let inv_albedo = 1.0 / (o.sigma_albedo * o.sigma_albedo);
        let mut out_e = vec![Vec3::ZERO; w * h];
        let mut out_v = vec![0.0f32; w * h];
        out_e.par_chunks_mut(w).zip(out_v.par_chunks_mut(w)).enumerate().for_each(|(y, (row_e, row_v))| {
            for x in 0..w {
                let p = y * w + x;
                let (lp, np, ap) = (e[p].dot(LUMA), self.normal[p], self.albedo[p]);
                let (mut sum_e, mut sum_v, mut sum_w) = (Vec3::ZERO, 0.0f32, 0.0f32);
                for (j, ky) in K.iter().enumerate() {
                    let qy = y as isize + (j as isize - 2) * step as isize;
                    if qy < 0 || qy >= h as isize {
                        continue;
                    }
                    for (i, kx) in K.iter().enumerate() {
                        let qx = x as isize + (i as isize - 2) * step as isize;
                        if qx < 0 || qx >= w as isize {
                            continue;
                        }
                        let q = qy as usize * w + qx as usize;
                        let wn = normal_weight(np, self.normal[q], o.normal_power);
                        let wa = (-(ap - self.albedo[q]).length_squared() * inv_albedo).exp();
                        let sd = (smooth[p] + smooth[q]).max(0.0).sqrt();
                        let wl = (-(lp - e[q].dot(LUMA)).abs() / (o.sigma_luminance * sd + 1e-6)).exp();
                        let wt = ky * kx * wn * wa * wl;
                        if wt == 0.0 {
                            // Also keeps an unknown (infinite) variance out of the sum.
                            continue;
                        }
                        sum_e += wt * e[q];
                        sum_v += wt * wt * var[q];
                        sum_w += wt;
                    }
                }
                // The centre tap has weight K[2]^2 > 0, so sum_w > 0.
                row_e[x] = sum_e / sum_w;
                row_v[x] = sum_v / (sum_w * sum_w);
            }
        });
        (out_e, out_v)
    }
}

/// `max(0, cos)^power` between unit normals; pixels without a surface (zero normal) only
/// match each other.
#[inline]
fn normal_weight(a: Vec3, b: Vec3, power: f32) -> f32 {
    match (a == Vec3::ZERO, b == Vec3::ZERO) {
        (true, true) => 1.0,
        (false, false) => a.dot(b).max(0.0).powf(power),
        _ => 0.0,
    }
}

/// A 3x3 binomial blur (edges clamped): SVGF's smoothing of the variance estimate.
fn blur3(v: &[f32], w: usize, h: usize) -> Vec<f32> {
    const K: [f32; 3] = [0.25, 0.5, 0.25];
    let at =
        |x: isize, y: isize| v[y.clamp(0, h as isize - 1) as usize * w + x.clamp(0, w as isize - 1) as usize];
    (0..w * h)
        .into_par_iter()
        .map(|p| {
            let (x, y) = ((p % w) as isize, (p / w) as isize);
            let mut s = 0.0;
            for (j, ky) in K.iter().enumerate() {
                for (i, kx) in K.iter().enumerate() {
                    s += ky * kx * at(x + i as isize - 1, y + j as isize - 1);
                }
            }
            s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aovs(w: u32, h: u32, albedo: impl Fn(u32, u32) -> Vec3, normal: impl Fn(u32, u32) -> Vec3) -> Aovs {
        let px = |f: &dyn Fn(u32, u32) -> Vec3| {
            (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect()
        };
        Aovs {
            width: w,
            height: h,
            albedo: px(&albedo),
            normal: px(&normal),
            emission: vec![Vec3::ZERO; (w * h) as usize],
        }
    }

    /// Noise of standard deviation `sd` on `truth`, from a fixed hash.
    fn noisy(truth: &[Vec3], sd: f32) -> Vec<Vec3> {
        truth
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut x = (i as u32).wrapping_mul(0x9e3779b9) ^ 0x5bd1e995;
                let mut u = || {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    (x >> 8) as f32 / (1 << 24) as f32
                };
                // Sum of four uniforms: roughly normal, variance 4/12.
                let mut n = || (u() + u() + u() + u() - 2.0) / (1.0f32 / 3.0).sqrt();
                *t + sd * Vec3::new(n(), n(), n())
            })
            .collect()
    }

    fn mse(a: &[Vec3], b: &[Vec3]) -> f32 {
        a.iter().zip(b).map(|(a, b)| (*a - *b).length_squared()).sum::<f32>() / a.len() as f32
    }

    #[test]
    fn flat_noise_is_smoothed_and_its_mean_kept() {
        let (w, h) = (64, 64);
        let truth = vec![Vec3::new(0.5, 0.4, 0.3); 64 * 64];
        let color = noisy(&truth, 0.1);
        let var = vec![Vec3::splat(0.01); w * h];
        let g = aovs(64, 64, |_, _| Vec3::splat(0.8), |_, _| Vec3::Z);
        let out = denoise(&color, &var, &g, &Options::default());
        assert!(
            mse(&out, &truth) < 0.02 * mse(&color, &truth),
            "{} {}",
            mse(&out, &truth),
            mse(&color, &truth)
        );
        let mean = |v: &[Vec3]| v.iter().sum::<Vec3>() / v.len() as f32;
        assert!((mean(&out) - mean(&color)).abs().max_element() < 2e-3);
    }

    #[test]
    fn edges_of_the_guides_survive() {
        // Left half one surface, right half another, twice as bright: a blur that ignored
        // the guides would mix them along the seam.
        let (w, h) = (64usize, 32usize);
        let truth: Vec<Vec3> =
            (0..w * h).map(|p| Vec3::splat(if p % w < w / 2 { 0.2 } else { 0.4 })).collect();
        let color = noisy(&truth, 0.05);
        let var = vec![Vec3::splat(0.0025); w * h];
        let seam = |v: &[Vec3]| {
            (0..h)
                .flat_map(|y| [y * w + w / 2 - 1, y * w + w / 2])
                .map(|p| (v[p] - truth[p]).abs().max_element())
                .fold(0.0, f32::max)
        };
        let normal = |x: u32, _| if x < 32 { Vec3::Z } else { Vec3::X };
        let albedo = |x: u32, _| Vec3::splat(if x < 32 { 0.5 } else { 0.9 });
        for (what, g) in [
            ("normals", aovs(64, 32, |_, _| Vec3::splat(0.5), normal)),
            ("albedos", aovs(64, 32, albedo, |_, _| Vec3::Z)),
        ] {
            let out = denoise(&color, &var, &g, &Options::default());
            assert!(seam(&out) < 0.06, "{what}: seam off by {}", seam(&out));
            assert!(mse(&out, &truth) < 0.1 * mse(&color, &truth), "{what}");
        }
        // Without guides and without the luminance weight the seam blurs: the check can fail.
        let blind = Options { sigma_luminance: f32::INFINITY, ..Options::default() };
        let flat = aovs(64, 32, |_, _| Vec3::splat(0.5), |_, _| Vec3::Z);
        assert!(seam(&denoise(&color, &var, &flat, &blind)) > 0.06);
    }

    /// Where the film discarded samples that the emission image kept (a light above the
    /// film's cap, a NaN), the emission image exceeds the colour: the result stays finite and
    /// non-negative.
    #[test]
    fn emission_beyond_the_colour_leaves_no_negative_or_nan() {
        let (w, h) = (16usize, 16usize);
        let color = noisy(&vec![Vec3::splat(0.5); w * h], 0.05);
        let var = vec![Vec3::splat(0.0025); w * h];
        let mut g = aovs(16, 16, |_, _| Vec3::splat(0.5), |_, _| Vec3::Z);
        for (p, le) in g.emission.iter_mut().enumerate() {
            *le = match p % 3 {
                0 => Vec3::splat(1e20),
                1 => Vec3::splat(f32::NAN),
                _ => Vec3::ZERO,
            };
        }
        let out = denoise(&color, &var, &g, &Options::default());
        for (p, o) in out.iter().enumerate() {
            assert!(o.is_finite() && o.min_element() >= 0.0, "pixel {p}: {o}");
        }
    }
}
