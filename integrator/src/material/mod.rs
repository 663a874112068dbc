//! How each material scatters light. Directions point away from the surface (`wo` towards the
//! previous vertex, `wi` towards the next); `n` is the unit geometric normal on the shape's
//! outside. Each material has its own file with its sampling, evaluation and tests.

pub mod dielectric;
pub mod lambertian;
pub mod metal;

use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::material::Material;

/// A sampled scattering direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit direction of the next ray.
    pub wi: Vec3A,
    /// Throughput factor `f * |cos| / pdf`.
    pub weight: Vec3,
    /// Density of `wi` (for delta lobes: the discrete probability of the chosen lobe).
    pub pdf: f32,
    /// True when `wi` came from a delta distribution (no MIS, no light sampling).
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection); Russian roulette divides it out.
    pub eta: f32,
}

/// Samples the next direction; `None` when the path is absorbed.
#[inline]
pub fn sample(m: &Material, wo: Vec3A, n: Vec3A, u: Vec2, uc: f32) -> Option<BsdfSample> {
    match *m {
        Material::Lambertian { albedo } => lambertian::sample(albedo, wo, n, u),
        Material::Metal { albedo, fuzz } => metal::sample(albedo, fuzz, wo, n, u, uc),
        Material::Dielectric { ior, fresnel } => dielectric::sample(ior, fresnel, wo, n, uc),
        Material::DiffuseLight { .. } => None,
    }
}

/// `f * |cos(wi, n)|` and the density [`sample`] gives `wi`, for materials that have a
/// non-delta part (see [`has_smooth_part`]); zero otherwise.
#[inline]
pub fn eval(m: &Material, wo: Vec3A, wi: Vec3A, n: Vec3A) -> (Vec3, f32) {
    match *m {
        Material::Lambertian { albedo } => lambertian::eval(albedo, wo, wi, n),
        _ => (Vec3::ZERO, 0.0),
    }
}

/// True when [`eval`] is meaningful, so light sampling and MIS apply. Metal (a perfect or a
/// fuzzed mirror whose density is not evaluated) and glass are sampled only.
#[inline]
pub fn has_smooth_part(m: &Material) -> bool {
    matches!(m, Material::Lambertian { .. })
}

/// Power heuristic (beta = 2) weight of the strategy with density `a` against `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Chi-square goodness of fit of a direction sampler against a density, over a grid of
    //! (cos theta, phi) cells of equal solid angle about a frame axis.

    use glam::{Vec2, Vec3A};
    use pathwave_engine::math::Frame;

    fn rng(seed: u64) -> impl FnMut() -> f32 {
        let mut s = crate::sampler::TestRng::new(seed);
        move || s.next_1d()
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
        let mut r = rng(17);
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
            assert!(
                pool_o <= 5.0 + 3.0 * pool_e.sqrt() + 5.0,
                "{pool_o} samples where {pool_e} are expected"
            );
        }
        (stat, dof.saturating_sub(1))
    }

    /// Upper critical value of the chi-square distribution at significance 1e-4 (Wilson-Hilferty).
    pub fn chi2_critical(dof: usize) -> f64 {
        let k = dof as f64;
        let z = 3.719; // one-sided normal quantile for 1e-4
        k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
    }
}
