//! PrincipledThin: the thin-surface Disney BSDF as Mitsuba 3's `principledthin`
//! (`src/bsdfs/principledthin.cpp`): a two-sided sheet without interior (leaves, paper, cloth)
//! that reflects with the Disney diffuse, sheen and fake subsurface of
//! [`super::principled`], transmits diffusely (`diff_trans`, 0 to 2 as Burley's), and has a
//! specular pair weighted by `spec_trans`: a GGX reflection with a thin-film Fresnel and a
//! transmission that goes straight through, mirrored from a reflection off a distribution
//! whose roughness is scaled by `0.65 eta - 0.35` (Burley 2015, figure 15).
//!
//! Both sides alike: the directions are turned to the side `wo` is on. The lobes are chosen with
//! probabilities that do not depend on the directions (Mitsuba's: the specular pair
//! `spec_trans / 2` each, diffuse reflection `(1 - spec_trans)(1 - diff_trans / 2)` and
//! transmission `(1 - spec_trans) diff_trans / 2`, each times its sampling rate), so sampling
//! follows the density exactly.

use super::microfacet::Microfacet;
use super::principled::{
    compatible, fresnel, ggx, grey, half, lerp, schlick_w, schlick_weight, smith_g1, zero,
};
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Shading};
use crate::format::{Albedo, Color, Positive, Scalar, UnitInterval};
use crate::math::{Frame, reflect};
use glam::{Vec2, Vec3, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The thin-sheet Disney BSDF as Mitsuba 3's `principledthin` (leaves, paper, cloth): both sides
/// alike, `Principled`'s diffuse, sheen and flatness, diffuse transmission `diff_trans` (0 to 2,
/// Burley's range: 1 transmits half), and a specular pair weighted by `spec_trans`: a GGX
/// reflection with the thin Fresnel (dielectric of `eta`, default 1.5, blended towards the tinted
/// Schlick by `spec_tint`) and a transmission straight through off a GGX of roughness scaled by
/// `0.65 eta - 0.35` (Burley 2015). Weights numbers or textures as `Principled`'s; `sampling_rates`
/// (specular reflection and transmission, diffuse reflection and transmission, default 1).
#[derive(serde::Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct PrincipledThinDesc {
    /// Colour in [0, 1] or a texture (default 0.5).
    #[serde(default = "grey")]
    pub base_color: Color<Albedo>,
    /// Roughness in [0, 1] (default 0.5).
    #[serde(default = "half")]
    pub roughness: Scalar<UnitInterval>,
    /// Anisotropy in [0, 1] (default 0), along the surface's tangent.
    #[serde(default = "zero")]
    pub anisotropic: Scalar<UnitInterval>,
    /// Weight of the specular pair in [0, 1] (default 0).
    #[serde(default = "zero")]
    pub spec_trans: Scalar<UnitInterval>,
    /// Diffuse transmission in [0, 2] (default 0): 0 reflects only, 1 half, 2 transmits only.
    #[serde(default = "no_diff_trans")]
    pub diff_trans: Scalar<DiffTrans>,
    /// Index of refraction of the sheet (> 0, default 1.5).
    #[serde(default = "glass")]
    pub eta: Positive,
    /// Tint of the specular reflection towards the base colour (default 0).
    #[serde(default = "zero")]
    pub spec_tint: Scalar<UnitInterval>,
    /// Sheen (default 0).
    #[serde(default = "zero")]
    pub sheen: Scalar<UnitInterval>,
    /// Tint of the sheen (default 0).
    #[serde(default = "zero")]
    pub sheen_tint: Scalar<UnitInterval>,
    /// Blend towards the fake subsurface (default 0).
    #[serde(default = "zero")]
    pub flatness: Scalar<UnitInterval>,
    /// Sampling rates of the specular reflection, specular transmission, diffuse reflection
    /// and diffuse transmission (each >= 0, default 1; Mitsuba's `*_sampling_rate`).
    #[serde(default = "ones")]
    pub sampling_rates: (f32, f32, f32, f32),
}

/// A diffuse transmission in [0, 2].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffTrans(pub f32);

impl<'de> serde::Deserialize<'de> for DiffTrans {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f32::deserialize(d)?;
        match (0.0..=2.0).contains(&v) {
            true => Ok(DiffTrans(v)),
            false => Err(serde::de::Error::custom(format!("expected a number in [0, 2], found {v}"))),
        }
    }
}

impl From<DiffTrans> for f32 {
    fn from(v: DiffTrans) -> f32 {
        v.0
    }
}

fn no_diff_trans() -> Scalar<DiffTrans> {
    Scalar::Value(DiffTrans(0.0))
}

fn glass() -> Positive {
    Positive(1.5)
}

fn ones() -> (f32, f32, f32, f32) {
    (1.0, 1.0, 1.0, 1.0)
}

/// Number slots, in [`Colors::scalar`] order.
const ROUGHNESS: usize = 0;
const ANISOTROPIC: usize = 1;
const SPEC_TRANS: usize = 2;
/// Half the diffuse transmission (in [0, 1]).
const DIFF_TRANS: usize = 3;
const SPEC_TINT: usize = 4;
const SHEEN: usize = 5;
const SHEEN_TINT: usize = 6;
const FLATNESS: usize = 7;

/// The thin principled BSDF; weights as 16-bit fractions, as [`super::principled::Principled`]'s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledThin {
    /// Base colour.
    pub base_color: Vec3,
    /// The weights by slot, as `round(w * 65535)` (the diffuse transmission halved).
    pub weights: [u16; 8],
    /// Index of refraction of the sheet.
    pub eta: f32,
    /// The tangent's angle about the shading normal.
    pub tangent: f32,
    /// Sampling rates: specular reflection, specular transmission, diffuse reflection, diffuse
    /// transmission.
    pub rates: [f32; 4],
}

impl PrincipledThin {
    #[inline]
    fn w(&self, i: usize) -> f32 {
        self.weights[i] as f32 * (1.0 / 65535.0)
    }

    #[inline]
    fn set_w(&mut self, i: usize, v: f32) {
        self.weights[i] = (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
    }

    #[inline]
    fn frame(&self, n: Vec3A) -> Frame {
        let f = Frame::from_normal(n);
        let (s, c) = self.tangent.sin_cos();
        let t = c * f.t + s * f.b;
        Frame { t, b: n.cross(t), n }
    }

    /// Probabilities of specular reflection, specular transmission, diffuse reflection and
    /// diffuse transmission.
    #[inline]
    fn probabilities(&self) -> [f32; 4] {
        let (st, dt) = (self.w(SPEC_TRANS), self.w(DIFF_TRANS));
        let [a, b, c, d] = self.rates;
        let p = [st * a / 2.0, st * b / 2.0, c * (1.0 - st) * (1.0 - dt), d * (1.0 - st) * dt];
        let total = p[0] + p[1] + p[2] + p[3];
        if total > 0.0 { p.map(|x| x / total) } else { [0.0; 4] }
    }

    /// The specular transmission's distribution: roughness scaled by `0.65 eta - 0.35`.
    #[inline]
    fn ggx_trans(&self) -> super::microfacet::GgxAniso {
        ggx((0.65 * self.eta - 0.35) * self.w(ROUGHNESS), self.w(ANISOTROPIC))
    }

    /// `f |cos|` and the density for local directions, `lo` above the surface.
    fn eval_local(&self, lo: Vec3A, li: Vec3A) -> BsdfEval {
        let (cos_i, cos_o) = (lo.z, li.z);
        if cos_i <= 0.0 || cos_o == 0.0 {
            return BsdfEval::ZERO;
        }
        let reflect = cos_o > 0.0;
        let (roughness, st, dt) = (self.w(ROUGHNESS), self.w(SPEC_TRANS), self.w(DIFF_TRANS));
        let base = self.base_color;
        let wh = (lo + Vec3A::new(li.x, li.y, li.z.abs())).normalize_or_zero();
        if wh == Vec3A::ZERO {
            return BsdfEval::ZERO;
        }
        let spec = ggx(roughness, self.w(ANISOTROPIC));
        let trans = self.ggx_trans();
        let ok = compatible(wh, lo, li, cos_i, reflect);
        let mut value = Vec3::ZERO;
        if st > 0.0 && ok {
            let f = fresnel(lo.dot(wh), self.eta).0;
            if reflect {
                let lum = crate::math::luminance(base);
                let tint = if lum > 0.0 { base / lum } else { Vec3::ONE };
                let r0 = tint * ((self.eta - 1.0) / (self.eta + 1.0)).powi(2);
                let w = schlick_w(lo.dot(wh), self.eta);
                let schlick = r0 + (Vec3::ONE - r0) * w;
                let spec_tint = self.w(SPEC_TINT);
                let f_thin = Vec3::splat(f) * (1.0 - spec_tint) + schlick * spec_tint;
                let dg = spec.d(wh) * smith_g1(&spec, lo, wh) * smith_g1(&spec, li, wh);
                value += f_thin * (st * dg / (4.0 * cos_i));
            } else {
                let dg = trans.d(wh) * smith_g1(&trans, lo, wh) * smith_g1(&trans, li, wh);
                value += base * (st * (1.0 - f) * dg / (4.0 * cos_i));
            }
        }
        if reflect && st < 1.0 && dt < 1.0 {
            let (fo, fi) = (schlick_weight(cos_o), schlick_weight(cos_i));
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let cos_d = wh.dot(li);
            let rr = 2.0 * roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let mut lobe = f_diff + f_retro;
            let flatness = self.w(FLATNESS);
            if flatness > 0.0 {
                let fss90 = rr / 2.0;
                let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
                let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
                lobe = lerp(lobe, f_ss, flatness);
            }
            value += base * ((1.0 - st) * cos_o * FRAC_1_PI * (1.0 - dt) * lobe);
            let sheen = self.w(SHEEN);
            if sheen > 0.0 {
                let fd = schlick_weight(cos_d.abs());
                let lum = crate::math::luminance(base);
                let tint = if lum > 0.0 { base / lum } else { Vec3::ONE };
                let c = Vec3::ONE.lerp(tint, self.w(SHEEN_TINT));
                value += c * (sheen * (1.0 - st) * fd * (1.0 - dt) * cos_o);
            }
        }
        if !reflect && st < 1.0 && dt > 0.0 {
            value += base * ((1.0 - st) * dt * FRAC_1_PI * cos_o.abs());
        }
        let [p_sr, p_st, p_dr, p_dt] = self.probabilities();
        let mut pdf = 0.0;
        if st > 0.0 && ok {
            let dwh_dwo = (1.0 / (4.0 * Vec3A::new(li.x, li.y, li.z.abs()).dot(wh))).abs();
            let (md, p) = if reflect { (&spec, p_sr) } else { (&trans, p_st) };
            pdf += p * md.d(wh) * smith_g1(md, lo, wh) * lo.dot(wh).abs() / cos_i * dwh_dwo;
        }
        pdf += match reflect {
            true => p_dr * cos_o * FRAC_1_PI,
            false => p_dt * -cos_o * FRAC_1_PI,
        };
        if !(value.is_finite() && pdf.is_finite()) {
            return BsdfEval::ZERO;
        }
        BsdfEval { f_cos: value, pdf }
    }
}

impl MaterialModel for PrincipledThin {
    type Desc = PrincipledThinDesc;
    const SHADING: Shading = Shading::Glossy;

    fn build(desc: &PrincipledThinDesc, colors: &mut Colors) -> Self {
        let base_color = colors.get(&desc.base_color);
        let mut m =
            PrincipledThin { base_color, weights: [0; 8], eta: desc.eta.0, tangent: 0.0, rates: [1.0; 4] };
        m.set_w(ROUGHNESS, colors.scalar(&desc.roughness));
        m.set_w(ANISOTROPIC, colors.scalar(&desc.anisotropic));
        m.set_w(SPEC_TRANS, colors.scalar(&desc.spec_trans));
        m.set_w(DIFF_TRANS, colors.scalar(&desc.diff_trans) / 2.0);
        for (i, s) in [
            (SPEC_TINT, &desc.spec_tint),
            (SHEEN, &desc.sheen),
            (SHEEN_TINT, &desc.sheen_tint),
            (FLATNESS, &desc.flatness),
        ] {
            m.set_w(i, colors.scalar(s));
        }
        let (a, b, c, d) = desc.sampling_rates;
        m.rates = [a, b, c, d];
        if matches!(desc.anisotropic, Scalar::Texture(_)) || desc.anisotropic != zero() {
            colors.tangent();
        }
        m
    }

    #[inline]
    fn set_color(&mut self, _slot: usize, value: Vec3) {
        self.base_color = value.clamp(Vec3::ZERO, Vec3::ONE);
    }

    #[inline]
    fn set_scalar(&mut self, slot: usize, value: f32) {
        self.set_w(slot, if slot == DIFF_TRANS { value / 2.0 } else { value });
    }

    #[inline]
    fn set_tangent(&mut self, n: Vec3A, dpdu: Vec3A) {
        self.tangent = super::rough_conductor::tangent_angle(n, dpdu);
    }

    fn sample(&self, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
        let frame = self.frame(n);
        let lo = super::microfacet::to_local(&frame, wo);
        if lo.z == 0.0 {
            return None;
        }
        // Both sides alike: work from above and turn the result back.
        let side = lo.z.signum();
        let lo = lo * side;
        let [p_sr, p_st, p_dr, _] = self.probabilities();
        let li = if uc < p_sr {
            let m = ggx(self.w(ROUGHNESS), self.w(ANISOTROPIC)).sample_visible(lo, u);
            let li = reflect(lo, m);
            if li.z <= 0.0 || !compatible(m, lo, li, lo.z, true) {
                return None;
            }
            li
        } else if uc < p_sr + p_st {
            let m = self.ggx_trans().sample_visible(lo, u);
            let r = reflect(lo, m);
            let li = Vec3A::new(r.x, r.y, -r.z);
            if li.z >= 0.0 || !compatible(m, lo, li, lo.z, false) {
                return None;
            }
            li
        } else if uc < p_sr + p_st + p_dr {
            super::lambertian::cosine_hemisphere(u)
        } else {
            -super::lambertian::cosine_hemisphere(u)
        };
        let e = self.eval_local(lo, li);
        if !(e.pdf > 0.0) {
            return None;
        }
        let wi = frame.to_world(li * side).normalize();
        Some(BsdfSample { wi, weight: e.f_cos / e.pdf, pdf: e.pdf, eta: 1.0, delta: false, null: false })
    }

    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        let frame = self.frame(n);
        let (lo, li) = (super::microfacet::to_local(&frame, wo), super::microfacet::to_local(&frame, wi));
        let side = if lo.z < 0.0 { -1.0 } else { 1.0 };
        self.eval_local(lo * side, li * side)
    }

    #[inline]
    fn albedo(&self) -> Vec3 {
        self.base_color
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::material::microfacet::testing::assert_chi2;
    use crate::testing::material_desc as parse;

    /// `[roughness, anisotropic, spec_trans, diff_trans / 2, spec_tint, sheen, sheen_tint,
    /// flatness]`.
    fn thin(w: [f32; 8]) -> PrincipledThin {
        let mut m = PrincipledThin {
            base_color: Vec3::new(0.7, 0.3, 0.2),
            weights: [0; 8],
            eta: 1.33,
            tangent: 1.1,
            rates: [1.0; 4],
        };
        for (i, v) in w.into_iter().enumerate() {
            m.set_w(i, v);
        }
        m
    }

    fn cases() -> Vec<(&'static str, PrincipledThin)> {
        vec![
            ("leaf", thin([0.5, 0.0, 0.0, 0.4, 0.0, 0.3, 0.5, 0.5])),
            // Roughness high enough that the transmission lobe (roughness scaled by 0.51)
            // spreads over the chi-square cells, which gather about the mirror direction.
            ("film", thin([0.8, 0.6, 0.8, 0.1, 0.5, 0.0, 0.0, 0.0])),
            ("all", thin([0.6, 0.4, 0.5, 0.6, 0.3, 0.8, 0.2, 0.3])),
        ]
    }

    /// Sampling follows the density on both sides, weights are `f cos / pdf`, and both
    /// sides are alike. Halving the diffuse transmission's density failed the chi-square.
    #[test]
    fn sampling_matches_eval_on_both_sides() {
        let n = Vec3A::new(0.2, -0.3, 0.9).normalize();
        let mut r = crate::testing::uniform(4);
        for (what, m) in cases() {
            for deg in [10.0f32, 65.0] {
                let t = deg.to_radians();
                let wo = Frame::from_normal(n).to_world(Vec3A::new(t.sin() * 0.6, t.sin() * 0.8, t.cos()));
                for wo in [wo, -wo] {
                    let what =
                        format!("{what}, {deg} deg, {}", if wo.dot(n) > 0.0 { "front" } else { "back" });
                    assert_chi2(
                        &what,
                        |u, uc| m.sample(wo, n, u, uc).map(|s| s.wi),
                        |wi| m.eval(wo, wi, n).pdf,
                        (n, reflect(wo, n), 0.4),
                        300_000,
                    );
                    for _ in 0..300 {
                        let Some(s) = m.sample(wo, n, Vec2::new(r(), r()), r()) else { continue };
                        let e = m.eval(wo, s.wi, n);
                        assert!((s.pdf - e.pdf).abs() <= 2e-3 * e.pdf, "{what}");
                        let w = e.f_cos / e.pdf;
                        assert!(
                            (s.weight - w).abs().max_element() <= 2e-3 * w.max_element().max(1e-3),
                            "{what}"
                        );
                        let flipped = m.eval(-wo, -s.wi, n);
                        assert!(
                            (flipped.f_cos - e.f_cos).abs().max_element()
                                <= 1e-4 * e.f_cos.max_element().max(1e-3)
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn descriptions_parse_and_bad_values_are_refused() {
        let (m, slots) = Material::build(
            &parse(r#"PrincipledThin(base_color: (0.7, 0.1, 0.1), diff_trans: "d", anisotropic: 0.3, eta: 1.33)"#).unwrap(),
            &mut |_| (2, Vec3::splat(1.4)),
        );
        let Material::PrincipledThin(p) = m else { unreachable!() };
        assert!((p.w(DIFF_TRANS) - 0.7).abs() < 1e-4 && p.eta == 1.33 && slots.tangent);
        assert_eq!(slots.scalars[DIFF_TRANS], Some(2));
        for (text, message) in [
            ("PrincipledThin(diff_trans: 2.5)", "expected a number in [0, 2], found 2.5"),
            ("PrincipledThin(roughness: -1)", "expected a number in [0, 1]"),
            ("PrincipledThin(eta: 0)", "> 0"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(message), "{text}: {e}");
        }
    }
}
