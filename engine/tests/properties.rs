//! Property tests of the geometry: rays leaving a surface never hit it again, hit points lie on
//! their surface within their error bound, and the BVH finds exactly the brute-force closest hit,
//! over random shapes at scales from 1e-3 to 1e4 and far from the origin, and for rays along
//! the axes.

use glam::Vec3A;
use pathwave_engine::accel::geometry::Geometry;
use pathwave_engine::math::{Ray, offset_ray_origin};
use pathwave_engine::shape::Primitive;
use pathwave_engine::shape::{PrimitiveShape, Quad, Sphere, Triangle};
use proptest::prelude::*;

fn vec3(range: f32) -> impl Strategy<Value = Vec3A> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3A::new(x, y, z))
}

fn unit() -> impl Strategy<Value = Vec3A> {
    vec3(1.0).prop_filter("non-zero", |v| v.length() > 1e-3).prop_map(|v| v.normalize())
}

/// A magnitude between 1e-3 and 1e4, log-uniform.
fn scale() -> impl Strategy<Value = f32> {
    (-3.0f32..4.0).prop_map(|e| 10f32.powf(e))
}

fn sphere() -> impl Strategy<Value = Sphere> {
    (vec3(1.0), scale(), scale()).prop_map(|(c, offset, r)| Sphere::new(c * offset, r))
}

fn quad() -> impl Strategy<Value = Quad> {
    (vec3(1.0), scale(), vec3(1.0), vec3(1.0), scale()).prop_filter_map(
        "non-degenerate",
        |(q, offset, u, v, size)| {
            let (u, v) = (u * size, v * size);
            (u.cross(v).length() > 1e-3 * size * size).then(|| Quad::new(q * offset, u, v)).flatten()
        },
    )
}

fn triangle() -> impl Strategy<Value = Triangle> {
    (vec3(1.0), scale(), vec3(1.0), vec3(1.0), vec3(1.0), scale()).prop_filter_map(
        "non-degenerate",
        |(c, offset, a, b, d, size)| {
            let (a, b, d) = (c * offset + a * size, c * offset + b * size, c * offset + d * size);
            ((b - a).cross(d - a).length() > 1e-3 * size * size).then(|| Triangle::new(a, b, d)).flatten()
        },
    )
}

/// A unit vector, one time in five along an axis with signed zeros (-Z is (-0, -0, -1)).
fn direction() -> impl Strategy<Value = Vec3A> {
    prop_oneof![
        4 => unit(),
        1 => (0usize..3, any::<bool>(), any::<bool>()).prop_map(|(axis, neg, neg_zero)| {
            let zero = if neg_zero { -0.0 } else { 0.0 };
            let mut v = [zero; 3];
            v[axis] = if neg { -1.0 } else { 1.0 };
            Vec3A::from_array(v)
        }),
    ]
}

/// A direction in the hemisphere about `n` (not grazing: cos > 0.01).
fn leaving(n: Vec3A, d: Vec3A) -> Option<Vec3A> {
    let d = if d.dot(n) < 0.0 { -d } else { d };
    (d.dot(n) > 0.01).then_some(d)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn a_ray_leaving_a_sphere_never_hits_it(s in sphere(), from in unit(), dir in unit()) {
        // A point on the sphere found by a ray, as the renderer finds them.
        let o = s.center + from * s.radius * 3.0;
        let t = s.intersect(o, -from, f32::INFINITY);
        prop_assume!(t.is_finite());
        let sp = s.surface(o - t * from, true);
        let Some(d) = leaving(sp.n, dir) else { return Ok(()) };
        let start = offset_ray_origin(sp.p, sp.err, sp.n);
        prop_assert_eq!(s.intersect(start, d, f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn a_ray_leaving_a_quad_on_either_side_never_hits_it(q in quad(), a in 0.0f32..1.0, b in 0.0f32..1.0, dir in unit()) {
        let sp = q.surface(q.q + a * q.u + b * q.v);
        for side in [sp.n, -sp.n] {
            let Some(d) = leaving(side, dir) else { continue };
            let start = offset_ray_origin(sp.p, sp.err, side);
            prop_assert_eq!(q.intersect(start, d, f32::INFINITY), f32::INFINITY);
        }
    }

    #[test]
    fn hit_points_lie_on_the_surface_within_their_bound(s in sphere(), q in quad(), o in vec3(1.0), d in unit(), aim in vec3(0.5)) {
        let o = o * s.radius.max(q.u.length()) * 4.0 + s.center;
        // Aim at the sphere.
        let dir = (s.center + aim * s.radius - o).normalize_or(d);
        let t = s.intersect(o, dir, f32::INFINITY);
        if t.is_finite() {
            let sp = s.surface(o + t * dir, true);
            let off = ((sp.p - s.center).length() - s.radius).abs();
            prop_assert!(off <= 2.0 * sp.err, "sphere: {} off, bound {}", off, sp.err);
        }
        let t = q.intersect(o, d, f32::INFINITY);
        if t.is_finite() {
            let sp = q.surface(o + t * d);
            let off = sp.n.dot(sp.p - q.q).abs();
            prop_assert!(off <= sp.err * sp.n.abs().element_sum(), "quad: {} off, bound {}", off, sp.err);
        }
    }

    #[test]
    fn a_ray_leaving_a_triangle_on_either_side_never_hits_it(t in triangle(), a in 0.0f32..1.0, b in 0.0f32..1.0, dir in unit()) {
        let (b1, b2) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
        let target = t.p[0] + b1 * (t.p[1] - t.p[0]) + b2 * (t.p[2] - t.p[0]);
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
        for side in [n, -n] {
            let o = target + side * (t.p[1] - t.p[0]).length();
            let hit = t.intersect(o, target - o, f32::INFINITY);
            prop_assume!(hit.is_finite());
            let sp = t.surface(o + hit * (target - o));
            // Off the plane by at most the bound; within the plane, the barycentric
            // reconstruction may wander by rounding times the triangle's conditioning.
            let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
            let cond = e1.length() * e2.length() / e1.cross(e2).length();
            let dev = sp.p - target;
            // The distance to the plane in f64: the f32 `target` is itself off the plane by its
            // rounding (about 2e-6 at coordinates near 20), which the bound does not cover.
            let (p0, n64) = (t.p[0].as_dvec3(), e1.as_dvec3().cross(e2.as_dvec3()).normalize());
            let off = (sp.p.as_dvec3() - p0).dot(n64);
            prop_assert!(off.abs() <= (sp.err * n.abs().element_sum()) as f64, "off the plane by {}", off);
            prop_assert!(dev.length() <= sp.err + 1e-6 * e1.length().max(e2.length()) * cond, "{dev}");
            let Some(d) = leaving(side, dir) else { continue };
            let start = offset_ray_origin(sp.p, sp.err, side);
            prop_assert_eq!(t.intersect(start, d, f32::INFINITY), f32::INFINITY);
        }
    }

    #[test]
    fn bvh_closest_hit_equals_brute_force(
        spheres in prop::collection::vec(sphere(), 1..40),
        quads in prop::collection::vec(quad(), 1..40),
        triangles in prop::collection::vec(triangle(), 0..40),
        rays in prop::collection::vec((vec3(1.0), scale(), direction()), 1..40),
    ) {
        let prims: Vec<Primitive> = spheres
            .into_iter()
            .map(Primitive::Sphere)
            .chain(quads.into_iter().map(Primitive::Quad))
            .chain(triangles.into_iter().map(Primitive::Triangle))
            .collect();
        let n = prims.len() as u32;
        let geo = Geometry::build_bvh(prims.clone(), (0..n).collect());
        for (o, s, d) in rays {
            let o = o * s;
            let brute = prims.iter().map(|p| p.intersect(o, d, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = geo.intersect(&Ray::new(o, d), f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
            prop_assert_eq!(got, brute, "ray from {} along {}", o, d);
        }
    }
}

/// A general affine map: any 3x3 with entries in [-2, 2] (shears included) that is not close to
/// singular, and a translation.
fn affine() -> impl Strategy<Value = glam::Affine3A> {
    (vec3(2.0), vec3(2.0), vec3(2.0), vec3(5.0)).prop_filter_map("not singular", |(x, y, z, t)| {
        let m = glam::Mat3A::from_cols(x, y, z);
        (m.determinant().abs() > 0.05).then_some(glam::Affine3A { matrix3: m, translation: t })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn normals_stay_perpendicular_under_any_affine_map(m in affine(), from in unit(), t1 in unit()) {
        // A hit on the transformed unit sphere: its world normal must be perpendicular to
        // every world tangent, the images M t of object tangents t (perpendicular to the object
        // normal).
        use pathwave_engine::shape::TransformedSphere;
        let ts = TransformedSphere::new(Sphere::new(Vec3A::ZERO, 1.0), m).unwrap();
        let o = m.transform_point3a(from * 4.0);
        let d = m.transform_point3a(Vec3A::ZERO) - o;
        let t = ts.intersect(o, d, f32::INFINITY);
        prop_assert!(t.is_finite());
        let sp = ts.surface(o + t * d, true);
        let n_obj = m.inverse().transform_point3a(sp.p).normalize();
        let tangent = t1.cross(n_obj);
        prop_assume!(tangent.length() > 1e-2);
        let world_tangent = m.transform_vector3a(tangent).normalize();
        // Rounding grows with the map's condition number |M| |M^-1| (Frobenius norms).
        let frobenius = |a: glam::Mat3A| (a.x_axis.length_squared() + a.y_axis.length_squared() + a.z_axis.length_squared()).sqrt();
        let cond = frobenius(m.matrix3) * frobenius(m.matrix3.inverse());
        prop_assert!(sp.n.dot(world_tangent).abs() < 1e-5 * cond, "n {} . tangent {} (condition {cond})", sp.n, world_tangent);
        prop_assert!(sp.n.dot(d) < 0.0, "the normal faces the ray that came from outside");
        // A quad under the same map: the normal is perpendicular to both mapped edges.
        let Some(q) = Quad::new(m.transform_point3a(Vec3A::ZERO), m.transform_vector3a(Vec3A::X), m.transform_vector3a(t1)) else { return Ok(()) };
        let qn = q.surface(q.q).n;
        prop_assert!(qn.dot(q.u.normalize()).abs() < 1e-4 && qn.dot(q.v.normalize()).abs() < 1e-4);
    }
}
