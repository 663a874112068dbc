use super::*;

/// Independent uniform numbers in [0, 1) (xorshift64*), for the histograms.
fn uniforms(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect()
}

const BINS: usize = 64;
/// Pearson's chi-square critical value for 63 degrees of freedom at p = 0.001.
const CRITICAL: f64 = 103.4;

/// Pearson's chi-square of `filter`'s sampled offsets against the normalised density of
/// `model`, over `BINS` bins across `model`'s radius (expected counts by the midpoint rule on
/// 64 points a bin).
fn chi_square(filter: &PixelFilter, model: &PixelFilter, n: usize) -> f64 {
    let r = model.radius().max(filter.radius());
    let mut counts = [0u64; BINS];
    for u in uniforms(n, 7) {
        let x = filter.sample_1d(u);
        assert!(x.is_finite() && x.abs() <= filter.radius(), "offset {x} from u = {u}");
        let b = (((x + r) / (2.0 * r)) * BINS as f32) as usize;
        counts[b.min(BINS - 1)] += 1;
    }
    let mass: Vec<f64> = (0..BINS)
        .map(|b| {
            (0..64)
                .map(|k| {
                    let x = -r + 2.0 * r * (b as f32 + (k as f32 + 0.5) / 64.0) / BINS as f32;
                    model.eval(x) as f64
                })
                .sum()
        })
        .collect();
    let total: f64 = mass.iter().sum();
    counts
        .iter()
        .zip(&mass)
        .filter(|(_, m)| **m > 0.0)
        .map(|(&c, m)| {
            let e = m / total * n as f64;
            (c as f64 - e) * (c as f64 - e) / e.max(1e-9)
        })
        .sum()
}

/// The sampled offsets' histogram matches the normalised filter (chi-square at p = 0.001),
/// and the same test rejects a filter that is slightly wrong: the Gaussian's samples against
/// stddev 0.55 instead of 0.5, the tent's against radius 1.1 instead of 1, the box's against
/// a tent.
#[test]
fn offsets_follow_the_filter_and_a_wrong_filter_is_rejected() {
    let n = 400_000;
    let gauss = PixelFilter::Gaussian(Gaussian::new(0.5));
    let tent = PixelFilter::Tent { radius: 1.0 };
    for (f, wrong) in [
        (gauss, PixelFilter::Gaussian(Gaussian::new(0.55))),
        (PixelFilter::Gaussian(Gaussian::new(2.5)), PixelFilter::Gaussian(Gaussian::new(2.6))),
        (tent, PixelFilter::Tent { radius: 1.1 }),
        (PixelFilter::Tent { radius: 3.0 }, PixelFilter::Tent { radius: 3.2 }),
        (PixelFilter::Box, tent),
    ] {
        let good = chi_square(&f, &f, n);
        assert!(good < CRITICAL, "{f:?}: chi-square {good} against its own density");
        let bad = chi_square(&f, &wrong, n);
        assert!(bad > 10.0 * CRITICAL, "{f:?} against {wrong:?}: chi-square only {bad}");
    }
}

/// The Gaussian's closed-form CDF (through the series erf) against the midpoint rule, and
/// its inverse: sample(cdf(x) / total) = x.
#[test]
fn gaussian_cdf_and_inverse() {
    for stddev in [0.1, 0.5, 1.7] {
        let g = Gaussian::new(stddev);
        let r = g.radius;
        let steps = 200_000;
        let mut sum = 0.0;
        for k in 0..steps {
            let x = -r + 2.0 * r * (k as f64 + 0.5) / steps as f64;
            sum += g.eval(x) * 2.0 * r / steps as f64;
            if k % 20_000 == 0 {
                let xk = -r + 2.0 * r * (k as f64 + 1.0) / steps as f64;
                assert!((g.cdf(xk) - sum).abs() < 1e-6 * g.total, "stddev {stddev}: cdf({xk})");
                let back = g.sample((g.cdf(xk) / g.total) as f32) as f64;
                assert!((back - xk).abs() < 1e-4 * r, "stddev {stddev}: {back} against {xk}");
            }
        }
        assert!((g.total - sum).abs() < 1e-6 * sum);
        // The ends: u = 0 at -radius, u just below 1 near +radius, never beyond.
        assert_eq!(g.sample(0.0) as f64, -r as f32 as f64);
        let top = g.sample(1.0 - f32::EPSILON / 2.0);
        assert!(top <= r as f32 && top > 0.5 * r as f32);
    }
}

/// The box's position is the pixel plus the numbers, the bits of the renderer without filters.
#[test]
fn box_position_is_pixel_plus_u() {
    for (p, u) in [((3, 9), [0.25f32, 0.999_999_9]), ((1023, 0), [0.0, 0.5])] {
        let got = PixelFilter::Box.position(p, u);
        assert_eq!(got.map(f32::to_bits), [p.0 as f32 + u[0], p.1 as f32 + u[1]].map(f32::to_bits));
    }
}

#[test]
fn integrals_in_closed_form_are_the_filters_sums() {
    let filters =
        [PixelFilter::Box, PixelFilter::Tent { radius: 1.5 }, PixelFilter::Gaussian(Gaussian::new(0.5))];
    for f in filters {
        let (r, n) = (f.radius() as f64, 100_000);
        let sum: f64 =
            (0..n).map(|k| f.eval((-r + 2.0 * r * (k as f64 + 0.5) / n as f64) as f32) as f64).sum();
        let numeric = sum * 2.0 * r / n as f64;
        assert!(
            (f.integral() / numeric - 1.0).abs() < 1e-4,
            "{}: {} against {numeric}",
            f.describe(),
            f.integral()
        );
    }
}
