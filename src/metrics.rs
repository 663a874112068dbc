//! Image error metrics against a reference.

use glam::Vec3;

/// Relative MSE: mean over pixels and channels of (x - r)^2 / (r^2 + 0.01).
pub fn rel_mse(x: &[Vec3], reference: &[Vec3]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(a, r)| {
            (0..3).map(|c| ((a[c] - r[c]) as f64).powi(2) / ((r[c] as f64).powi(2) + 0.01)).sum::<f64>()
        })
        .sum();
    sum / (3 * x.len()) as f64
}

/// Root mean squared error over pixels and channels.
pub fn rmse(x: &[Vec3], reference: &[Vec3]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(a, r)| (0..3).map(|c| ((a[c] - r[c]) as f64).powi(2)).sum::<f64>())
        .sum();
    (sum / (3 * x.len()) as f64).sqrt()
}

/// Mean over pixels and channels.
pub fn mean(x: &[Vec3]) -> f64 {
    x.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>() / (3 * x.len()) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error() {
        let a = vec![Vec3::new(0.5, 1.0, 2.0); 4];
        assert_eq!(rel_mse(&a, &a), 0.0);
        assert_eq!(rmse(&a, &a), 0.0);
    }

    #[test]
    fn rel_mse_weights_by_reference() {
        let r = vec![Vec3::splat(1.0)];
        let x = vec![Vec3::splat(1.1)];
        assert!((rel_mse(&x, &r) - 0.01 / 1.01).abs() < 1e-6);
        assert!((rmse(&x, &r) - 0.1).abs() < 1e-6);
    }
}
