//! The energy a single-scattering GGX lobe loses, and the factor that gives it back.
//!
//! A microfacet BRDF that counts one bounce on the microsurface drops the light that reflects
//! off a second facet: a white GGX metal of width 1 seen head-on reflects 31% of the light
//! (separable Smith masking). Turquin (2019), "Practical multiple scattering compensation for
//! microfacet models", scales the lobe by `1 + Fms (1 - E(mu)) / E(mu)`, where `E(mu)` is the
//! directional albedo of the lobe with a Fresnel factor of 1 seen at `mu = cos(wo)` and `Fms`
//! the Fresnel factor of the light that scatters more than once: Kulla and Conty (2017),
//! "Revisiting Physically Based Shading at Imageworks", appendix, with `E_avg` the
//! cosine-weighted mean of `E` and `F_avg` that of the Fresnel factor,
//! `Fms = F_avg E_avg / (1 - F_avg (1 - E_avg))` (one factor `F_avg` of their expression
//! cancelled, as the lobe already carries one Fresnel factor). With `F = 1` the scaled lobe
//! reflects all the light at every angle; the sampling density does not change. Blender's Cycles
//! renders its multiple-scattering GGX this way (the Principled BSDF of Blender 4 and later),
//! and the glTF specification suggests the compensation ("Microfacet Surfaces").
//!
//! The same numbers couple a diffuse base to the specular layer above it without losing or
//! making light (Kulla and Conty 2017, section "Energy conservation" of their layered
//! material; the coupling the glTF specification names): the base is weighted by
//! `(1 - A(mu_o)) (1 - A(mu_i)) / (1 - A_avg)`, where `A` is the directional albedo of the
//! compensated specular layer with its Fresnel factor. With Schlick's factor
//! `F = f0 + (1 - f0) (1 - wo.h)^5` it is linear in `f0`:
//! `A = (f0 E + (1 - f0) S) (1 + Fms (1 - E) / E)`, `S` the lobe's albedo weighted by
//! `(1 - wo.h)^5`, and its mean `A_avg` needs `E_avg`, `S_avg = 2 ∫ S mu dmu` and
//! `2 ∫ S (1 - E) / E mu dmu`.
//!
//! The tables are for pathwave's GGX with separable Smith masking ([`super::microfacet::Ggx`]):
//! `E` and `S` at 32 x 32 nodes over `sqrt(alpha)` and `mu` in [0, 1] (bilinear between them),
//! the means at 32 nodes of `sqrt(alpha)`. They are numbers written into the source by the test
//! `tables_are_the_quadratures` (`PATHWAVE_BLESS=1`), so that an image does not depend on the
//! machine that computed them.

use glam::{Vec2, Vec3};

/// Nodes per axis of the tables.
const NODES: usize = 32;

include!("ggx_energy_table.rs");

/// The position of `x` in [0, 1] between the nodes: the lower node and the share of the upper.
#[inline(always)]
fn node(x: f32) -> (usize, f32) {
    let t = x.clamp(0.0, 1.0) * (NODES - 1) as f32;
    let i = (t as usize).min(NODES - 2);
    (i, t - i as f32)
}

/// `(E(mu), S(mu))`: the directional albedos of a GGX lobe of width `alpha` seen at
/// `mu = cos(wo)`, with a Fresnel factor of 1 and of `(1 - wo.h)^5` (interpolated in the tables).
#[inline(always)]
pub fn albedos(alpha: f32, mu: f32) -> (f32, f32) {
    let (i, s) = node(alpha.sqrt());
    let (j, t) = node(mu);
    // One table of pairs: each corner's two numbers in one load.
    let corner = |i: usize, j: usize| Vec2::from_array(ALBEDOS[i][j]);
    let lo = corner(i, j).lerp(corner(i, j + 1), t);
    let hi = corner(i + 1, j).lerp(corner(i + 1, j + 1), t);
    let e = lo.lerp(hi, s);
    (e.x, e.y)
}

/// The means over the cosine-weighted hemisphere of a GGX lobe's albedos (see the module's notes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Averages {
    /// `E_avg = 2 ∫ E mu dmu`.
    pub e: f32,
    /// `S_avg = 2 ∫ S mu dmu`.
    pub s: f32,
    /// `2 ∫ S (1 - E) / E mu dmu`.
    pub s_missing: f32,
}

/// The [`Averages`] of a GGX lobe of width `alpha` (interpolated in the tables).
pub fn averages(alpha: f32) -> Averages {
    let (i, t) = node(alpha.sqrt());
    let lerp = |table: &[f32; NODES]| table[i] + (table[i + 1] - table[i]) * t;
    Averages { e: lerp(&AVERAGE), s: lerp(&SCHLICK_AVERAGE), s_missing: lerp(&SCHLICK_MISSING) }
}

/// The cosine-weighted mean of Schlick's Fresnel factor `f0 + (1 - f0) (1 - mu)^5`:
/// `f0 + (1 - f0) / 21`.
#[inline(always)]
pub fn schlick_average(f0: Vec3) -> Vec3 {
    f0 + (Vec3::ONE - f0) * (1.0 / 21.0)
}

/// `Fms = F_avg E_avg / (1 - F_avg (1 - E_avg))`: the Fresnel factor of the light scattered more
/// than once in a lobe of mean albedo `e_avg` whose Fresnel factor averages `f_avg`.
#[inline(always)]
pub fn multiple_fresnel(f_avg: Vec3, e_avg: f32) -> Vec3 {
    f_avg * e_avg / (Vec3::ONE - f_avg * (1.0 - e_avg))
}

/// The factor `1 + Fms (1 - e) / e` that gives a single-scattering lobe of albedo `e` (from
/// [`albedos`]) back the light scattered more than once, `fms` from [`multiple_fresnel`].
#[inline(always)]
pub fn compensation(e: f32, fms: f32) -> f32 {
    1.0 + fms * (1.0 - e) / e
}

/// [`compensation`] for a coloured `Fms` (a metal's).
#[inline(always)]
pub fn compensation_rgb(e: f32, fms: Vec3) -> Vec3 {
    Vec3::ONE + fms * ((1.0 - e) / e)
}

/// `A(mu)`: the directional albedo of a compensated lobe with Schlick's factor of `f0`, from the
/// albedos `(e, s)` of [`albedos`] at `mu` and its scalar `Fms`.
#[inline(always)]
pub fn layer_albedo(f0: f32, (e, s): (f32, f32), fms: f32) -> f32 {
    (f0 * e + (1.0 - f0) * s) * compensation(e, fms)
}

/// `A_avg = 2 ∫ A mu dmu` of [`layer_albedo`]'s lobe, from its [`Averages`].
pub fn layer_average(f0: f32, avg: Averages, fms: f32) -> f32 {
    f0 * (avg.e + fms * (1.0 - avg.e)) + (1.0 - f0) * (avg.s + fms * avg.s_missing)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::microfacet::{Ggx, Microfacet, SMOOTH_ALPHA};
    use rayon::prelude::*;
    use std::fmt::Write;

    /// The quadrature of `(E(mu), S(mu))` for a lobe of width `alpha`: visible normals sampled
    /// at the midpoints of a `k x k` grid, each weighed by what is left of `f cos / pdf` with a
    /// Fresnel factor of 1, `G1(wi)` above the surface, and that times `(1 - wo.m)^5`.
    fn albedos_by_quadrature(alpha: f32, mu: f32, k: usize) -> (f64, f64) {
        let ggx = Ggx { alpha: alpha.max(SMOOTH_ALPHA) };
        let mu = mu.max(1e-3);
        let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        let (mut e, mut s) = (0.0f64, 0.0f64);
        for a in 0..k {
            for b in 0..k {
                let u = Vec2::new((a as f32 + 0.5) / k as f32, (b as f32 + 0.5) / k as f32);
                let m = ggx.sample_visible(wo, u);
                let wi = 2.0 * wo.dot(m) * m - wo;
                if wi.z > 0.0 && m.z > 0.0 {
                    let g = ggx.g1(wi) as f64;
                    e += g;
                    s += g * ((1.0 - wo.dot(m).clamp(0.0, 1.0)) as f64).powi(5);
                }
            }
        }
        let n = (k * k) as f64;
        (e / n, s / n)
    }

    /// The [`Averages`] by quadrature at `n` midpoints of `mu`.
    fn averages_by_quadrature(alpha: f32, n: usize, k: usize) -> [f64; 3] {
        let mut sums = [0.0f64; 3];
        for j in 0..n {
            let mu = (j as f64 + 0.5) / n as f64;
            let (e, s) = albedos_by_quadrature(alpha, mu as f32, k);
            for (sum, v) in sums.iter_mut().zip([e, s, s * (1.0 - e) / e]) {
                *sum += 2.0 * v * mu / n as f64;
            }
        }
        sums
    }

    /// The width of the table's row `i`.
    fn row_alpha(i: usize) -> f32 {
        let r = i as f32 / (NODES - 1) as f32;
        r * r
    }

    /// Grid points per axis of the blessed tables' quadrature.
    const K: usize = 256;
    /// Points of `mu` of `E_avg`'s quadrature.
    const MUS: usize = 64;

    /// A row of the tables: `(E, S)` at each `mu`, and the means.
    type Row = (Vec<(f64, f64)>, [f64; 3]);

    fn write_tables() -> String {
        let rows: Vec<Row> = (0..NODES)
            .into_par_iter()
            .map(|i| {
                let alpha = row_alpha(i);
                let row = (0..NODES)
                    .map(|j| albedos_by_quadrature(alpha, j as f32 / (NODES - 1) as f32, K))
                    .collect();
                (row, averages_by_quadrature(alpha, MUS, K))
            })
            .collect();
        let mut s = String::from(
            "// Written by `ggx_energy::tests::tables_are_the_quadratures` (PATHWAVE_BLESS=1).\n",
        );
        s.push_str(
            "\n/// `[E(mu), S(mu)]` at `sqrt(alpha) = i / 31` (rows) and `mu = j / 31` (columns).\n\
             #[rustfmt::skip]\nstatic ALBEDOS: [[[f32; 2]; NODES]; NODES] = [\n",
        );
        for (row, _) in &rows {
            let cells: Vec<String> = row.iter().map(|&(e, sc)| format!("[{e:.6}, {sc:.6}]")).collect();
            writeln!(s, "    [{}],", cells.join(", ")).unwrap();
        }
        s.push_str("];\n");
        for (name, what, pick) in [
            ("AVERAGE", "E_avg", 0),
            ("SCHLICK_AVERAGE", "S_avg", 1),
            ("SCHLICK_MISSING", "2 ∫ S (1 - E) / E mu dmu", 2),
        ] {
            let cells: Vec<String> = rows.iter().map(|(_, a)| format!("{:.6}", a[pick])).collect();
            write!(
                s,
                "\n/// `{what}` at `sqrt(alpha) = i / 31`.\n#[rustfmt::skip]\nstatic {name}: [f32; NODES] = [\n    {},\n];\n",
                cells.join(", ")
            )
            .unwrap();
        }
        s
    }

    /// The tables in the source are the quadratures (a sample of nodes recomputed, with a
    /// coarser grid than the blessed one's); `PATHWAVE_BLESS=1` writes them. (Checked to fail
    /// with the reflected direction's masking `G1(wi)` replaced by 1.)
    #[test]
    fn tables_are_the_quadratures() {
        if std::env::var("PATHWAVE_BLESS").is_ok_and(|v| v == "1") {
            let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/material/ggx_energy_table.rs");
            std::fs::write(path, write_tables()).unwrap();
            return;
        }
        for (i, j) in [(1, 0), (3, 31), (8, 5), (15, 15), (22, 2), (31, 0), (31, 31), (27, 20)] {
            let (e, s) = albedos_by_quadrature(row_alpha(i), j as f32 / (NODES - 1) as f32, 96);
            let [te, ts] = ALBEDOS[i][j].map(f64::from);
            assert!((te - e).abs() < 2e-3, "E at ({i}, {j}): table {te}, quadrature {e}");
            assert!((ts - s).abs() < 2e-3, "S at ({i}, {j}): table {ts}, quadrature {s}");
        }
        for i in [2, 16, 31] {
            let want = averages_by_quadrature(row_alpha(i), 16, 48);
            let got = [AVERAGE[i], SCHLICK_AVERAGE[i], SCHLICK_MISSING[i]];
            for (g, w) in got.iter().zip(want) {
                assert!((*g as f64 - w).abs() < 4e-3, "means at {i}: table {got:?}, quadrature {want:?}");
            }
        }
    }

    /// A white metal of width 1 seen head-on reflects `1 - ln 2` in single scattering with
    /// separable masking (the closed form of the glTF BRDF's white furnace), a smooth one all.
    #[test]
    fn albedo_has_its_closed_forms() {
        let head_on = albedos(1.0, 1.0).0;
        assert!((head_on - (1.0 - std::f32::consts::LN_2)).abs() < 2e-3, "{head_on}");
        let smooth = albedos(SMOOTH_ALPHA, 1.0);
        assert!(smooth.0 > 0.999 && smooth.1 < 1e-6, "{smooth:?}");
        for [e, s] in ALBEDOS.iter().flatten() {
            assert!(*e > 0.05 && *e <= 1.0 && *s >= 0.0 && s < e, "E {e}, S {s}");
        }
    }

    /// A compensated lobe with a Fresnel factor of 1 reflects all the light seen from any
    /// angle, between the nodes too ([`layer_albedo`] with `f0` 1); with Schlick's factor,
    /// less; and `A_avg` is the mean of `A` (a quadrature over `mu` of the interpolated tables).
    #[test]
    fn layer_albedos_add_up() {
        for alpha in [0.01f32, 0.1, 0.37, 0.8, 1.0] {
            let avg = averages(alpha);
            for mu in [0.05f32, 0.3, 0.61, 1.0] {
                let white = layer_albedo(1.0, albedos(alpha, mu), multiple_fresnel(Vec3::ONE, avg.e).x);
                assert!((white - 1.0).abs() < 1e-5, "{alpha} {mu}: {white}");
            }
            let fms = multiple_fresnel(schlick_average(Vec3::splat(0.04)), avg.e).x;
            let n = 2000;
            let mean: f32 = (0..n)
                .map(|j| {
                    let mu = (j as f32 + 0.5) / n as f32;
                    2.0 * layer_albedo(0.04, albedos(alpha, mu), fms) * mu / n as f32
                })
                .sum();
            let by_table = layer_average(0.04, avg, fms);
            assert!(by_table < 1.0 && (mean - by_table).abs() < 2e-3, "{alpha}: {mean} vs {by_table}");
        }
    }
}
