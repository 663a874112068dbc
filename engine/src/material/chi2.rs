//! Chi-square goodness of fit of a direction sampler against a density, over a grid of
//! (cos theta, phi) cells of equal solid angle about a frame axis: what the materials' tests
//! (here and in the integrator's kernels) check their sampling with.

use crate::math::Frame;
use glam::{Vec2, Vec3A};

/// Deterministic numbers in [0, 1) (SplitMix64 by Steele, Lea and Flood 2014, top 24 bits).
fn uniform(mut s: u64) -> impl FnMut() -> f32 {
    move || {
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Returns the chi-square statistic and its degrees of freedom. Cells cover cos(theta) in
/// [z_min, 1] about `axis` (every sample must fall there); `pdf` is the density in solid
/// angle, integrated over each cell numerically; cells with expected count < 5 are pooled.
pub fn chi2(
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3A>,
    pdf: impl Fn(Vec3A) -> f32,
    axis: Vec3A,
    z_min: f64,
    n: usize,
) -> (f64, usize) {
    const CT: usize = 20;
    const PH: usize = 40;
    let frame = Frame::from_normal(axis);
    let cell = |w: Vec3A| {
        let l = Vec3A::new(w.dot(frame.t), w.dot(frame.b), w.dot(frame.n));
        let ct = (((l.z as f64 - z_min) / (1.0 - z_min) * CT as f64).max(0.0) as usize).min(CT - 1);
        let ph = ((l.y.atan2(l.x) / std::f32::consts::TAU + 0.5) * PH as f32) as usize % PH;
        ct * PH + ph
    };
    let mut observed = vec![0f64; CT * PH];
    let mut r = uniform(17);
    for _ in 0..n {
        if let Some(w) = sample(Vec2::new(r(), r()), r()) {
            observed[cell(w)] += 1.0;
        }
    }
    // Expected counts: integrate the pdf over each cell with a Q x Q midpoint rule.
    const Q: usize = 24;
    let mut expected = vec![0f64; CT * PH];
    let d_omega = std::f64::consts::TAU * (1.0 - z_min) / (CT * PH * Q * Q) as f64;
    for (c, e) in expected.iter_mut().enumerate() {
        let (ct, ph) = (c / PH, c % PH);
        for i in 0..Q {
            for j in 0..Q {
                let z = z_min + (ct as f64 + (i as f64 + 0.5) / Q as f64) / CT as f64 * (1.0 - z_min);
                let phi =
                    ((ph as f64 + (j as f64 + 0.5) / Q as f64) / PH as f64 - 0.5) * std::f64::consts::TAU;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let l = Vec3A::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                *e += pdf(frame.to_world(l)) as f64 * d_omega * n as f64;
            }
        }
    }
    let (mut stat, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
            continue;
        }
        stat += (o - e) * (o - e) / e;
        dof += 1;
    }
    if pool_e >= 5.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e;
        dof += 1;
    } else {
        assert!(pool_o <= 5.0 + 3.0 * pool_e.sqrt() + 5.0, "{pool_o} samples where {pool_e} are expected");
    }
    (stat, dof.saturating_sub(1))
}

/// Upper critical value of the chi-square distribution at significance 1e-4 (Wilson-Hilferty).
pub fn chi2_critical(dof: usize) -> f64 {
    let k = dof as f64;
    let z = 3.719; // one-sided normal quantile for 1e-4
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}
