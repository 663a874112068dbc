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

use super::disney::{compatible, fresnel, ggx, lerp, reflect_plain, schlick_w, schlick_weight, smith_g1};
use super::microfacet::{GgxAniso, Microfacet, PlainFrame};
use super::principled::{grey, half, zero};
use super::{BsdfEval, BsdfSample, Colors, MaterialModel, Shading};
use crate::format::{Albedo, Color, Positive, Scalar, UnitInterval};
use crate::math::Frame;
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

    /// The shading frame about the unit normal `n`: the tangent at its angle.
    #[inline]
    pub fn frame(&self, n: Vec3A) -> PlainFrame {
        let f = Frame::from_normal(n);
        let (s, c) = self.tangent.sin_cos();
        let t = c * f.t + s * f.b;
        PlainFrame { t: t.into(), b: n.cross(t).into(), n: n.into() }
    }

    /// The lobes' numbers.
    #[inline]
    pub fn lobes(&self) -> ThinLobes {
        let (roughness, anisotropic) = (self.w(ROUGHNESS), self.w(ANISOTROPIC));
        let (st, dt) = (self.w(SPEC_TRANS), self.w(DIFF_TRANS));
        let base = self.base_color;
        let lum = crate::math::luminance(base);
        let spec = ggx(roughness, anisotropic);
        // The specular transmission's distribution: roughness scaled by `0.65 eta - 0.35`.
        let trans = ggx((0.65 * self.eta - 0.35) * roughness, anisotropic);
        // Probabilities of specular reflection, specular transmission, diffuse reflection and
        // diffuse transmission.
        let [a, b, c, d] = self.rates;
        let p = [st * a / 2.0, st * b / 2.0, c * (1.0 - st) * (1.0 - dt), d * (1.0 - st) * dt];
        let total = p[0] + p[1] + p[2] + p[3];
        let p = if total > 0.0 { p.map(|x| x / total) } else { [0.0; 4] };
        ThinLobes {
            base,
            tint: if lum > 0.0 { base / lum } else { Vec3::ONE },
            roughness,
            spec_trans: st,
            diff_trans: dt,
            spec_tint: self.w(SPEC_TINT),
            sheen: self.w(SHEEN),
            sheen_tint: self.w(SHEEN_TINT),
            flatness: self.w(FLATNESS),
            eta: self.eta,
            spec_ax: spec.ax,
            spec_ay: spec.ay,
            trans_ax: trans.ax,
            trans_ay: trans.ay,
            p_spec_reflect: p[0],
            p_spec_trans: p[1],
            p_diff_reflect: p[2],
            p_diff_trans: p[3],
        }
    }
}

/// Everything of a thin principled BSDF at one hit that its lobes read, as plain numbers: what
/// the one-path code and the wavefront's lane kernel ([`ThinLobes::eval_plain`],
/// [`ThinLobes::sample_plain`]) take, so that both compute the same bits.
#[derive(Clone, Copy, Debug, Default)]
pub struct ThinLobes {
    /// Base colour.
    pub base: Vec3,
    /// The base colour over its luminance (white for black).
    pub tint: Vec3,
    /// Roughness.
    pub roughness: f32,
    /// Specular transmission.
    pub spec_trans: f32,
    /// Diffuse transmission (halved: 0 to 1).
    pub diff_trans: f32,
    /// Tint of the specular reflection.
    pub spec_tint: f32,
    /// Sheen amount.
    pub sheen: f32,
    /// Tint of the sheen.
    pub sheen_tint: f32,
    /// Blend towards the fake subsurface.
    pub flatness: f32,
    /// Index of refraction of the sheet.
    pub eta: f32,
    /// The specular reflection's GGX widths.
    pub spec_ax: f32,
    /// See `spec_ax`.
    pub spec_ay: f32,
    /// The specular transmission's GGX widths.
    pub trans_ax: f32,
    /// See `trans_ax`.
    pub trans_ay: f32,
    /// Probability of the specular reflection.
    pub p_spec_reflect: f32,
    /// Of the specular transmission.
    pub p_spec_trans: f32,
    /// Of the diffuse reflection.
    pub p_diff_reflect: f32,
    /// Of the diffuse transmission.
    pub p_diff_trans: f32,
}

impl ThinLobes {
    /// `f |cos|` and the density for local directions, `lo` above the surface, on plain numbers
    /// and without branches (every lobe computed, those that apply added).
    #[inline(always)]
    pub fn eval_plain(&self, lo: Vec3, li: Vec3) -> BsdfEval {
        let (cos_i, cos_o) = (lo.z, li.z);
        let reflect = cos_o > 0.0;
        let (roughness, st, dt) = (self.roughness, self.spec_trans, self.diff_trans);
        let base = self.base;
        let li_up = Vec3::new(li.x, li.y, li.z.abs());
        let wh = (lo + li_up).normalize_or_zero();
        let defined = cos_i > 0.0 && cos_o != 0.0 && wh != Vec3::ZERO;
        let spec = GgxAniso { ax: self.spec_ax, ay: self.spec_ay };
        let trans = GgxAniso { ax: self.trans_ax, ay: self.trans_ay };
        let ok = compatible(wh, lo, li, cos_i, reflect);
        let add = |on: bool, v: Vec3| if on { v } else { Vec3::ZERO };

        let f = fresnel(lo.dot(wh), self.eta).0;
        let r0 = self.tint * ((self.eta - 1.0) / (self.eta + 1.0)).powi(2);
        let w = schlick_w(lo.dot(wh), self.eta);
        let schlick = r0 + (Vec3::ONE - r0) * w;
        let f_thin = Vec3::splat(f) * (1.0 - self.spec_tint) + schlick * self.spec_tint;
        let dg_spec = spec.d(wh) * smith_g1(&spec, lo, wh) * smith_g1(&spec, li, wh);
        let dg_trans = trans.d(wh) * smith_g1(&trans, lo, wh) * smith_g1(&trans, li, wh);
        let specular = match reflect {
            true => f_thin * (st * dg_spec / (4.0 * cos_i)),
            false => base * (st * (1.0 - f) * dg_trans / (4.0 * cos_i)),
        };
        let mut value = add(st > 0.0 && ok, specular);

        let diffuse = reflect && st < 1.0 && dt < 1.0;
        let (fo, fi) = (schlick_weight(cos_o), schlick_weight(cos_i));
        let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
        let cos_d = wh.dot(li);
        let rr = 2.0 * roughness * cos_d * cos_d;
        let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
        let lobe = f_diff + f_retro;
        let fss90 = rr / 2.0;
        let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
        let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
        let lobe = if self.flatness > 0.0 { lerp(lobe, f_ss, self.flatness) } else { lobe };
        value += add(diffuse, base * ((1.0 - st) * cos_o * FRAC_1_PI * (1.0 - dt) * lobe));
        let fd = schlick_weight(cos_d.abs());
        let c = Vec3::ONE.lerp(self.tint, self.sheen_tint);
        let sheen = diffuse && self.sheen > 0.0;
        value += add(sheen, c * (self.sheen * (1.0 - st) * fd * (1.0 - dt) * cos_o));
        let diffuse_through = !reflect && st < 1.0 && dt > 0.0;
        value += add(diffuse_through, base * ((1.0 - st) * dt * FRAC_1_PI * cos_o.abs()));

        let dwh_dwo = (1.0 / (4.0 * li_up.dot(wh))).abs();
        let visible =
            |md: &GgxAniso, p: f32| p * md.d(wh) * smith_g1(md, lo, wh) * lo.dot(wh).abs() / cos_i * dwh_dwo;
        let (spec_pdf, trans_pdf) = (visible(&spec, self.p_spec_reflect), visible(&trans, self.p_spec_trans));
        let mut pdf = if st > 0.0 && ok { if reflect { spec_pdf } else { trans_pdf } } else { 0.0 };
        pdf += match reflect {
            true => self.p_diff_reflect * cos_o * FRAC_1_PI,
            false => self.p_diff_trans * -cos_o * FRAC_1_PI,
        };
        match defined && value.is_finite() && pdf.is_finite() {
            true => BsdfEval { f_cos: value, pdf },
            false => BsdfEval::ZERO,
        }
    }

    /// Samples a local direction from `lo` (above the surface) with the numbers `u` and `uc`,
    /// choosing the lobe by its fixed probability, on plain numbers and without branches
    /// (every lobe's direction computed, the chosen one kept): the direction, its
    /// [`Self::eval_plain`], and whether there is a sample.
    #[inline(always)]
    pub fn sample_plain(&self, lo: Vec3, u: Vec2, uc: f32) -> (Vec3, BsdfEval, bool) {
        let spec = GgxAniso { ax: self.spec_ax, ay: self.spec_ay };
        let trans = GgxAniso { ax: self.trans_ax, ay: self.trans_ay };
        let m_spec = spec.sample_visible(lo, u);
        let li_spec = reflect_plain(lo, m_spec);
        let m_trans = trans.sample_visible(lo, u);
        let r = reflect_plain(lo, m_trans);
        let li_trans = Vec3::new(r.x, r.y, -r.z);
        let d = super::lambertian::cosine_hemisphere_plain(u);
        let (p_sr, p_st, p_dr) = (self.p_spec_reflect, self.p_spec_trans, self.p_diff_reflect);
        let (li, fits) = match (uc < p_sr, uc < p_sr + p_st, uc < p_sr + p_st + p_dr) {
            (true, _, _) => (li_spec, li_spec.z > 0.0 && compatible(m_spec, lo, li_spec, lo.z, true)),
            (false, true, _) => {
                (li_trans, li_trans.z < 0.0 && compatible(m_trans, lo, li_trans, lo.z, false))
            }
            (false, false, true) => (d, true),
            (false, false, false) => (-d, true),
        };
        let e = self.eval_plain(lo, li);
        (li, e, fits && e.pdf > 0.0)
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
        let lo = frame.local(wo.into());
        // Both sides alike: work from above and turn the result back.
        let side = if lo.z < 0.0 { -1.0 } else { 1.0 };
        let (li, e, valid) = self.lobes().sample_plain(lo * side, u, uc);
        (valid && lo.z != 0.0).then(|| BsdfSample {
            wi: frame.world_unit(li * side).into(),
            weight: e.f_cos / e.pdf,
            pdf: e.pdf,
            eta: 1.0,
            delta: false,
            null: false,
        })
    }

    fn eval(&self, wo: Vec3A, wi: Vec3A, n: Vec3A) -> BsdfEval {
        let frame = self.frame(n);
        let (lo, li) = (frame.local(wo.into()), frame.local(wi.into()));
        let side = if lo.z < 0.0 { -1.0 } else { 1.0 };
        self.lobes().eval_plain(lo * side, li * side)
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
    use crate::math::reflect;
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
