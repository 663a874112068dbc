//! Eight triangles at a time: a BLAS leaf's block, stored lane by lane, and the watertight
//! test of [`Triangle::intersect`](crate::shape::Triangle::intersect) across its lanes (AVX2
//! where the build has it, else the scalar loop; same operations, same bits).

#![cfg_attr(
    all(target_arch = "x86_64", target_feature = "avx2"),
    expect(unsafe_code, reason = "AVX2 intrinsics for the blocks' tests")
)]

use crate::math::gamma;
use crate::shape::{PrimitiveShape, Triangle};
use glam::Vec3A;

/// Up to eight triangles, lane by lane: `v[vertex][axis][lane]`. Unused lanes hold NaN, which
/// fails every comparison of the test.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct TriBlock {
    pub(super) v: [[[f32; 8]; 3]; 3],
    /// Triangle index (into the mesh) per lane.
    pub(super) id: [u32; 8],
}

/// A ray prepared for the watertight test: the permutation that makes z the direction's
/// largest axis and the shear that maps the direction to +z.
#[derive(Clone, Copy, Debug)]
pub struct TriRay {
    k: [usize; 3],
    o: [f32; 3],
    s: [f32; 3],
}

impl TriRay {
    /// Prepares the ray `o + t d`.
    #[inline(always)]
    pub fn new(o: Vec3A, d: Vec3A) -> Self {
        let kz = d.abs().max_position();
        let k = [(kz + 1) % 3, (kz + 2) % 3, kz];
        let dp = [d[k[0]], d[k[1]], d[k[2]]];
        Self { k, o: [o[k[0]], o[k[1]], o[k[2]]], s: [-dp[0] / dp[2], -dp[1] / dp[2], 1.0 / dp[2]] }
    }
}

impl TriBlock {
    /// Distances of the eight lanes, each in `(0, tmax)` where the lane's bit in the returned
    /// mask is set (the other lanes hold anything); lanes whose edge functions are exactly
    /// zero in `f32`, or whose distance overflows it, are decided by the scalar test (in `f64`).
    #[inline(always)]
    pub(super) fn intersect(&self, r: &TriRay, o: Vec3A, d: Vec3A, tmax: f32) -> ([f32; 8], u32) {
        let (mut out, mut hit, mut scalar) = self.lanes(r, tmax);
        // NaN lanes compare unequal to zero, so unused lanes never come here.
        while scalar != 0 {
            let l = scalar.trailing_zeros() as usize;
            scalar &= scalar - 1;
            let p = [0, 1, 2].map(|j| Vec3A::new(self.v[j][0][l], self.v[j][1][l], self.v[j][2][l]));
            out[l] = Triangle { p, uv: None }.intersect(o, d, tmax);
            hit |= ((out[l] < tmax) as u32) << l;
        }
        (out, hit)
    }

    /// The eight tests without AVX2.
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    #[inline(always)]
    pub(super) fn lanes(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
        self.lanes_scalar(r, tmax)
    }

    /// The eight tests: distances, the lanes hit and the lanes left to the caller's scalar test
    /// (an edge function exactly zero, a distance beyond `f32`).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[inline(always)]
    pub(super) fn lanes(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
        use std::arch::x86_64::*;
        // SAFETY: aligned loads of whole 32-byte lane arrays of `self` (32-byte aligned); AVX2
        // is enabled for the whole build.
        unsafe {
            let [kx, ky, kz] = r.k;
            let splat = _mm256_set1_ps;
            let (ox, oy, oz) = (splat(r.o[0]), splat(r.o[1]), splat(r.o[2]));
            let (sx, sy, sz) = (splat(r.s[0]), splat(r.s[1]), splat(r.s[2]));
            let ld = |j: usize, a: usize| _mm256_load_ps(self.v[j][a].as_ptr());
            let (add, sub, mul) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps);
            let mut x = [_mm256_setzero_ps(); 3];
            let mut y = x;
            let mut z = x;
            for j in 0..3 {
                let pz = sub(ld(j, kz), oz);
                x[j] = add(sub(ld(j, kx), ox), mul(sx, pz));
                y[j] = add(sub(ld(j, ky), oy), mul(sy, pz));
                z[j] = mul(pz, sz);
            }
            let zero = _mm256_setzero_ps();
            let e0 = sub(mul(x[1], y[2]), mul(y[1], x[2]));
            let e1 = sub(mul(x[2], y[0]), mul(y[2], x[0]));
            let e2 = sub(mul(x[0], y[1]), mul(y[0], x[1]));
            let eq0 = |e| _mm256_cmp_ps::<_CMP_EQ_OQ>(e, zero);
            let zero_edge = _mm256_movemask_ps(_mm256_or_ps(_mm256_or_ps(eq0(e0), eq0(e1)), eq0(e2))) as u32;
            let cmp_ge = |a, b| _mm256_cmp_ps::<_CMP_GE_OQ>(a, b);
            let (and, or) = (_mm256_and_ps, _mm256_or_ps);
            let all_ge = and(and(cmp_ge(e0, zero), cmp_ge(e1, zero)), cmp_ge(e2, zero));
            let all_le = and(and(cmp_ge(zero, e0), cmp_ge(zero, e1)), cmp_ge(zero, e2));
            let inside = or(all_ge, all_le);
            // Most blocks a ray reaches it passes by: skip the division and the error bound.
            if _mm256_movemask_ps(inside) == 0 {
                return ([f32::INFINITY; 8], 0, zero_edge);
            }
            let abs = |v| _mm256_andnot_ps(splat(-0.0), v);
            let det = add(add(e0, e1), e2);
            let t_scaled = add(add(mul(e0, z[0]), mul(e1, z[1])), mul(e2, z[2]));
            // A distance beyond f32's range (a triangle 1e13 across, 3e13 away) is the scalar
            // test's, in f64.
            let finite = _mm256_cmp_ps::<_CMP_LT_OQ>(abs(t_scaled), splat(f32::INFINITY));
            let scalar = zero_edge | _mm256_movemask_ps(_mm256_andnot_ps(finite, inside)) as u32;
            let inv_det = _mm256_div_ps(splat(1.0), det);
            let t = mul(t_scaled, inv_det);
            let max3 = |v: [__m256; 3]| _mm256_max_ps(_mm256_max_ps(abs(v[0]), abs(v[1])), abs(v[2]));
            let (max_x, max_y, max_z) = (max3(x), max3(y), max3(z));
            let delta_z = mul(splat(gamma(3)), max_z);
            let delta_x = mul(splat(gamma(5)), add(max_x, max_z));
            let delta_y = mul(splat(gamma(5)), add(max_y, max_z));
            let delta_e = mul(
                splat(2.0),
                add(add(mul(mul(splat(gamma(2)), max_x), max_y), mul(delta_y, max_x)), mul(delta_x, max_y)),
            );
            let max_e = max3([e0, e1, e2]);
            let delta_t = mul(
                mul(
                    splat(3.0),
                    add(
                        add(mul(mul(splat(gamma(3)), max_e), max_z), mul(delta_e, max_z)),
                        mul(delta_z, max_e),
                    ),
                ),
                abs(inv_det),
            );
            let cmp_gt = |a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b);
            let tmax_det = mul(splat(tmax), det);
            let neg = and(cmp_gt(zero, det), and(cmp_gt(zero, t_scaled), cmp_ge(t_scaled, tmax_det)));
            let pos = and(cmp_gt(det, zero), and(cmp_gt(t_scaled, zero), cmp_ge(tmax_det, t_scaled)));
            let hit = and(
                and(inside, or(neg, pos)),
                and(cmp_gt(t, delta_t), _mm256_cmp_ps::<_CMP_LT_OQ>(t, splat(tmax))),
            );
            let mut out = [0.0f32; 8];
            _mm256_storeu_ps(out.as_mut_ptr(), t);
            (out, _mm256_movemask_ps(hit) as u32 & !scalar, scalar)
        }
    }

    /// [`Self::lanes`] without AVX2, lane by lane, with the same operations in the same order
    /// (so the same bits where a lane is hit). Built for the tests too, which compare the two.
    #[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
    #[inline(always)]
    pub(super) fn lanes_scalar(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
        let [kx, ky, kz] = r.k;
        let mut x = [[0.0f32; 8]; 3];
        let mut y = [[0.0f32; 8]; 3];
        let mut z = [[0.0f32; 8]; 3];
        for j in 0..3 {
            for l in 0..8 {
                let pz = self.v[j][kz][l] - r.o[2];
                x[j][l] = (self.v[j][kx][l] - r.o[0]) + r.s[0] * pz;
                y[j][l] = (self.v[j][ky][l] - r.o[1]) + r.s[1] * pz;
                z[j][l] = pz * r.s[2];
            }
        }
        let mut out = [f32::INFINITY; 8];
        let mut hit = 0u32;
        let mut scalar = 0u32;
        for l in 0..8 {
            let e0 = x[1][l] * y[2][l] - y[1][l] * x[2][l];
            let e1 = x[2][l] * y[0][l] - y[2][l] * x[0][l];
            let e2 = x[0][l] * y[1][l] - y[0][l] * x[1][l];
            let det = e0 + e1 + e2;
            let t_scaled = e0 * z[0][l] + e1 * z[1][l] + e2 * z[2][l];
            let same_sign = (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
            let zero = (e0 == 0.0) | (e1 == 0.0) | (e2 == 0.0);
            scalar |= (zero || (same_sign && !(t_scaled.abs() < f32::INFINITY))) as u32 * (1 << l);
            let inv_det = 1.0 / det;
            let t = t_scaled * inv_det;
            let max_z = z[0][l].abs().max(z[1][l].abs()).max(z[2][l].abs());
            let max_x = x[0][l].abs().max(x[1][l].abs()).max(x[2][l].abs());
            let max_y = y[0][l].abs().max(y[1][l].abs()).max(y[2][l].abs());
            let delta_z = gamma(3) * max_z;
            let delta_x = gamma(5) * (max_x + max_z);
            let delta_y = gamma(5) * (max_y + max_z);
            let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
            let max_e = e0.abs().max(e1.abs()).max(e2.abs());
            let delta_t =
                3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * inv_det.abs();
            let in_range = if det < 0.0 {
                t_scaled < 0.0 && t_scaled >= tmax * det
            } else {
                t_scaled > 0.0 && t_scaled <= tmax * det
            };
            if same_sign && det != 0.0 && in_range && t > delta_t && t < tmax {
                out[l] = t;
                hit |= 1 << l;
            }
        }
        (out, hit & !scalar, scalar)
    }
}
