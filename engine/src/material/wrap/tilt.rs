//! The tilted shading normals of bump maps (Blinn 1978, "Simulation of Wrinkled Surfaces") and
//! normal maps, Mitsuba's `flip_invalid_normals`, the tangent under a tilt, and the shadowing
//! term of Estevez et al. 2019 ("A Microfacet-Based Shadowing Function to Solve the Bump
//! Terminator Problem", Ray Tracing Gems, chapter 12).

use crate::math::Frame;
use crate::shape::SurfacePoint;
use glam::{Vec2, Vec3, Vec3A};

/// The normal of a bump-mapped surface, from the geometric normal `ng`, the shading normal
/// `ns`, the derivatives `dpdu` and `dpdv` and the height's derivatives `dh` along u and v:
/// the cross product of the tangents `dp/du` and `dp/dv` (their parts across `ns` replaced by
/// the height's slopes along it), on `ng`'s side. `None` where they are parallel.
pub fn bump_normal(ng: Vec3A, ns: Vec3A, dpdu: Vec3A, dpdv: Vec3A, dh: Vec2) -> Option<Vec3A> {
    let du = dpdu - ns * ns.dot(dpdu) + ns * dh.x;
    let dv = dpdv - ns * ns.dot(dpdv) + ns * dh.y;
    let n = du.cross(dv).normalize_or_zero();
    match n == Vec3A::ZERO {
        true => None,
        false => Some(if n.dot(ng) < 0.0 { -n } else { n }),
    }
}

/// The unit tangent of the frame at a hit with shading normal `ns`: `dpdu` across it, or
/// any tangent where there is none (or it lies along `ns`).
fn tangent(ns: Vec3A, dpdu: Option<Vec3A>) -> Vec3A {
    dpdu.map(|d| (d - ns * ns.dot(d)).normalize_or_zero())
        .filter(|s| *s != Vec3A::ZERO)
        .unwrap_or_else(|| Frame::from_normal(ns).t)
}

/// The normal that a normal map's value `code` gives at a hit with shading normal `ns` and
/// `dpdu` (if the surface has one): `2 code - 1` in the frame of the tangent `s` along `dpdu`,
/// `ns x s` and `ns`. `None` for a zero vector.
pub fn normal_map_normal(ns: Vec3A, dpdu: Option<Vec3A>, code: Vec3) -> Option<Vec3A> {
    let local = Vec3A::from(code) * 2.0 - Vec3A::ONE;
    let s = tangent(ns, dpdu);
    let n = (s * local.x + ns.cross(s) * local.y + ns * local.z).normalize_or_zero();
    (n != Vec3A::ZERO).then_some(n)
}

/// The tilted normal `n` mirrored about the base normal `ns` (its part across `ns` negated)
/// where it faces away from `wo` on the other side of `ns` than `wo` does (Mitsuba's
/// `flip_invalid_normals`): a view that sees the base surface from the front sees the tilted
/// one from the front too, where the mirror does.
pub fn flip_invalid(ns: Vec3A, n: Vec3A, wo: Vec3A) -> Vec3A {
    match wo.dot(ns) * wo.dot(n) <= 0.0 {
        true => 2.0 * n.dot(ns) * ns - n,
        false => n,
    }
}

/// The tangent that an anisotropic material at `sp` takes from `dpdu`: across the base
/// normal first where a map tilted the normal (the map's frame turns with it, as Mitsuba's
/// `normalmap` turns the shading frame), `dpdu` itself elsewhere.
pub fn base_tangent(sp: &SurfacePoint, dpdu: Vec3A) -> Vec3A {
    match sp.ns == sp.ns_base {
        true => dpdu,
        false => dpdu - sp.ns_base * sp.ns_base.dot(dpdu),
    }
}

/// The shadowing that a bump or normal map's tilt casts on the unit direction `wi` at `sp`
/// (Estevez et al. 2019): Smith's GGX shadowing `2 / (1 + sqrt(1 + a^2 tan^2))` of `wi`'s
/// angle to the base normal, the roughness `a^2 = min(tan^2(tilt) / 8, 1)` from the angle
/// between the tilted and the base normal. 1 where nothing tilted the normal, towards 0 at
/// the base surface's horizon.
#[inline]
pub fn terminator_shadowing(sp: &SurfacePoint, wi: Vec3A) -> f32 {
    if sp.ns == sp.ns_base {
        return 1.0;
    }
    let tan2 = |c: f32| (1.0 - c * c).max(0.0) / (c * c);
    let a2 = (0.125 * tan2(sp.ns.dot(sp.ns_base))).min(1.0);
    if a2 == 0.0 {
        return 1.0;
    }
    2.0 / (1.0 + (1.0 + a2 * tan2(wi.dot(sp.ns_base))).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(v: [f32; 3]) -> Vec3A {
        Vec3A::from(v).normalize()
    }

    /// On a plane with heights `h = a u + b v` (dp/du, dp/dv the axes), the bumped normal is
    /// that of the displaced plane, `(-a, -b, 1)` normalised, whatever the tangents' lengths
    /// along the normal; it stays on the geometric normal's side. (Swapping the two slopes, or
    /// keeping dp/du's part along the normal, fails.)
    #[test]
    fn bump_normals_are_the_displaced_surfaces() {
        for (a, b) in [(0.3, -0.7), (0.0, 2.0), (-5.0, 0.1)] {
            let want = unit([-a, -b, 1.0]);
            let (du, dv) = (Vec3A::new(1.0, 0.0, 0.4), Vec3A::new(0.0, 1.0, -0.2));
            let n = bump_normal(Vec3A::Z, Vec3A::Z, du, dv, Vec2::new(a, b)).unwrap();
            assert!((n - want).length() < 1e-6, "{n} vs {want}");
            // dp/dv the other way (a parameterisation with v flipped, and its slope with it):
            // the same surface, the same normal.
            let n = bump_normal(Vec3A::Z, Vec3A::Z, du, -dv, Vec2::new(a, -b)).unwrap();
            assert!((n - want).length() < 1e-6, "flipped v: {n} vs {want}");
            // Seen from the other side of the geometry, it turns with the geometric normal.
            let n = bump_normal(-Vec3A::Z, Vec3A::Z, du, dv, Vec2::new(a, b)).unwrap();
            assert!((n + want).length() < 1e-6);
        }
        // Parallel tangents give none.
        assert_eq!(bump_normal(Vec3A::Z, Vec3A::Z, Vec3A::X, 2.0 * Vec3A::X, Vec2::ZERO), None);
    }

    /// A normal map's value is the normal in the frame (dp/du across the normal, n x that,
    /// n): (0.5, 0.5, 1) is the normal itself, and the axes come out where they belong,
    /// however dp/du leans out of the tangent plane. (Taking the second axis as s x n fails.)
    #[test]
    fn normal_maps_read_the_tangent_frame() {
        let ns = unit([0.0, 0.0, 1.0]);
        let dpdu = Some(Vec3A::new(2.0, 0.0, 0.7));
        let at = |code: [f32; 3]| normal_map_normal(ns, dpdu, Vec3::from(code)).unwrap();
        assert!((at([0.5, 0.5, 1.0]) - ns).length() < 1e-6);
        assert!((at([1.0, 0.5, 0.5]) - Vec3A::X).length() < 1e-6);
        assert!((at([0.5, 1.0, 0.5]) - Vec3A::Y).length() < 1e-6);
        assert!((at([1.0, 1.0, 1.0]) - unit([1.0, 1.0, 1.0])).length() < 1e-6);
        // Without dp/du any tangent serves, and the normal is still ns for the flat value.
        let n = normal_map_normal(ns, None, Vec3::new(0.5, 0.5, 1.0)).unwrap();
        assert!((n - ns).length() < 1e-6);
        assert_eq!(normal_map_normal(ns, dpdu, Vec3::splat(0.5)), None);
    }

    /// A tilted normal that faces away from `wo` while the base faces it is mirrored about the
    /// base; one that agrees with the base is kept.
    #[test]
    fn invalid_normals_flip_about_the_base() {
        let ns = Vec3A::Z;
        let wo = unit([1.0, 0.0, 0.2]);
        let away = unit([-1.0, 0.3, 0.1]);
        assert!(wo.dot(away) < 0.0);
        let flipped = flip_invalid(ns, away, wo);
        assert!((flipped - unit([1.0, -0.3, 0.1])).length() < 1e-6);
        assert!(wo.dot(flipped) > 0.0);
        let fine = unit([0.2, 0.1, 1.0]);
        assert_eq!(flip_invalid(ns, fine, wo), fine);
    }

    /// Estevez et al.'s term: 1 without a tilt, Smith's GGX shadowing with a^2 = tan^2 / 8 of
    /// the tilt (at most 1) elsewhere, falling to 0 at the base's horizon.
    #[test]
    fn terminator_shadowing_is_smiths_of_the_tilt() {
        let mut sp = SurfacePoint::flat(Vec3A::Z, Vec2::ZERO);
        let wi = unit([3f32.sqrt(), 0.0, 1.0]);
        assert_eq!(terminator_shadowing(&sp, wi), 1.0);
        // A tilt of 45 degrees (tan^2 1, a^2 1/8) and wi at 60 degrees (tan^2 3).
        sp.ns = unit([1.0, 0.0, 1.0]);
        let want = 2.0 / (1.0 + (1.0f32 + 3.0 / 8.0).sqrt());
        assert!((terminator_shadowing(&sp, wi) - want).abs() < 1e-5);
        assert!(terminator_shadowing(&sp, unit([1.0, 0.0, 1e-4])) < 0.01);
        assert_eq!(terminator_shadowing(&sp, Vec3A::X), 0.0);
        // Steep tilts saturate at a^2 = 1.
        sp.ns = unit([10.0, 0.0, 1.0]);
        let want = 2.0 / (1.0 + (1.0f32 + 3.0).sqrt());
        assert!((terminator_shadowing(&sp, wi) - want).abs() < 1e-5);
    }

    /// Under a tilt, an anisotropic material's tangent is dp/du across the base normal (the
    /// map's frame, which the material projects across the tilted one); elsewhere dp/du.
    #[test]
    fn tangents_turn_with_the_map() {
        let mut sp = SurfacePoint::flat(Vec3A::Z, Vec2::ZERO);
        let dpdu = Vec3A::new(1.0, 0.0, 0.5);
        assert_eq!(base_tangent(&sp, dpdu), dpdu);
        sp.ns = unit([0.3, 0.2, 1.0]);
        assert_eq!(base_tangent(&sp, dpdu), Vec3A::X);
    }
}
