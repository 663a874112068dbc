//! Rays, orthonormal frames and robust ray-origin offsets.

use glam::{Vec2, Vec3A};

/// A ray `origin + t * dir`. `dir` need not be unit length: every shape test is written for
/// arbitrary directions, so `t` keeps its meaning through affine transforms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3A,
    /// Direction (any non-zero length).
    pub dir: Vec3A,
    /// Time within the shutter interval at which the ray samples the scene.
    pub time: f32,
}

impl Ray {
    /// A ray at time 0.
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        Self { origin, dir, time: 0.0 }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + t * self.dir
    }
}

/// An orthonormal frame whose `n` axis is a given unit vector (Duff et al. 2017, branchless).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub t: Vec3A,
    /// Second tangent.
    pub b: Vec3A,
    /// The normal (z axis of the frame).
    pub n: Vec3A,
}

impl Frame {
    /// Builds a frame around the unit vector `n`.
    #[inline]
    pub fn from_normal(n: Vec3A) -> Self {
        let (t, b) = basis(n.into());
        Self { t: t.into(), b: b.into(), n }
    }

    /// Local (x, y, z) to world.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// `v` over its length, on plain numbers: a division, as glam's `Vec3A::normalize` (glam's
/// `Vec3::normalize` multiplies by the reciprocal, which rounds twice).
#[inline(always)]
pub fn normalized(v: glam::Vec3) -> glam::Vec3 {
    v / v.length()
}

/// The tangent and bitangent of [`Frame::from_normal`] on plain numbers (the form the lane
/// kernels run): Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)).
#[inline(always)]
pub fn basis(n: glam::Vec3) -> (glam::Vec3, glam::Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = glam::Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = glam::Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (t, bt)
}

/// Rec. 709 (sRGB primaries) luminance of a linear RGB colour.
#[inline]
pub fn luminance(c: glam::Vec3) -> f32 {
    c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The bound `n u / (1 - n u)` on the relative error of `n` chained f32 operations (pbrt-v4
/// section 6.8.1), with u = 2^-24.
pub const fn gamma(n: u32) -> f32 {
    let u = f32::EPSILON * 0.5;
    n as f32 * u / (1.0 - n as f32 * u)
}

/// Moves a surface point whose coordinates are off by at most `err` (absolute, per component)
/// to the side of `n` (the side the new ray leaves from): by the error bound along the normal,
/// then one ulp further in each component the offset moved, so that rounding of the addition
/// cannot put the point back inside the bound (pbrt-v4 section 6.8.6). Scale invariant: no
/// epsilon to tune per scene.
#[inline]
pub fn offset_ray_origin(p: Vec3A, err: f32, n: Vec3A) -> Vec3A {
    let d = err * n.abs().element_sum();
    let offset = d * n;
    let po = p + offset;
    Vec3A::new(step_away(po.x, offset.x), step_away(po.y, offset.y), step_away(po.z, offset.z))
}

/// `x.next_up()` where `o > 0`, `x.next_down()` where `o < 0`, else `x`: the same bits, by
/// selects on the bit pattern instead of branches on the signs (the signs of the offsets of
/// [`offset_ray_origin`] are as unpredictable as the normals, and the branches were 1.5% of
/// cornell's time).
#[inline(always)]
pub fn step_away(x: f32, o: f32) -> f32 {
    let (up, down) = (o > 0.0, o < 0.0);
    let bits = x.to_bits();
    let negative = bits >> 31 != 0;
    // Away from zero adds one to the magnitude's bits, towards zero subtracts one.
    let moved = if up != negative { bits.wrapping_add(1) } else { bits.wrapping_sub(1) };
    // From either zero the step lands on the smallest subnormal of the step's sign.
    let moved = if bits << 1 == 0 { if up { 1 } else { 0x8000_0001 } } else { moved };
    // NaN, and infinity stepped away from zero, stay as they are (as `next_up` keeps them).
    let stays = !(up || down) || x.is_nan() || (x.is_infinite() && up != negative);
    if stays { x } else { f32::from_bits(moved) }
}

/// The length of `v`, also where its squared length leaves `f32`'s normal range: the cross
/// product of two edges 1e10 long squares to 1e41, beyond `f32::MAX`. Such a vector is divided
/// by its largest component first; others are measured as `length` measures them, to the same
/// bits.
#[inline]
pub fn length(v: Vec3A) -> f32 {
    let m = v.abs().max_element();
    match squared_in_range(v) || !(m > 0.0 && m.is_finite()) {
        true => v.length(),
        false => m * (v / m).length(),
    }
}

/// `v` normalised, or `None` when it is zero or not finite; scaled first where its squared
/// length leaves `f32`'s normal range, as [`length`] does (vertex normals that nearly cancel,
/// the normal of a triangle 1e10 across), to `normalize`'s bits elsewhere.
#[inline]
pub fn unit(v: Vec3A) -> Option<Vec3A> {
    if !(v.is_finite() && v != Vec3A::ZERO) {
        return None;
    }
    Some(match squared_in_range(v) {
        true => v.normalize(),
        false => (v / v.abs().max_element()).normalize(),
    })
}

#[inline]
fn squared_in_range(v: Vec3A) -> bool {
    let l2 = v.length_squared();
    (1e-30..=f32::MAX).contains(&l2)
}

/// Mirror reflection of `wo` (pointing away from the surface) about `n`.
#[inline]
pub fn reflect(wo: Vec3A, n: Vec3A) -> Vec3A {
    2.0 * wo.dot(n) * n - wo
}

/// Shirley-Chiu concentric map from the unit square to the unit disk ([`disk_branch_free`]'s
/// numbers).
#[inline(always)]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let (x, y) = disk_branch_free([u.x, u.y]);
    Vec2::new(x, y)
}

/// sin and cos on [-pi/4, pi/4] (Taylor to degree 7 and 8: errors below 3.2e-7 and 2.5e-8).
#[inline(always)]
fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    (s, c)
}

/// The dot product of plain coordinates, summed as glam sums a `Vec3A`'s ((x + y) + z): the
/// lane kernels that must reproduce glam's bits use it.
#[inline(always)]
pub fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `(cos, sin)` of the angle `2 pi u` (`u` in [0, 1]) from the polynomial of the nearest
/// quarter turn, branch-free: the same bits in a scalar call and across lanes (sphere lights'
/// cone samples), which the C library's `sinf` and `cosf` do not promise.
#[inline(always)]
pub fn cos_sin_turn(u: f32) -> (f32, f32) {
    let t = 4.0 * u;
    let k = (t + 0.5).floor();
    let (s, c) = sin_cos_quarter((t - k) * std::f32::consts::FRAC_PI_2);
    // Rotate (c, s) by k quarter turns (k = 4 is none).
    let (k1, k2, k3) = (k == 1.0, k == 2.0, k == 3.0);
    let cos = if k1 {
        -s
    } else if k2 {
        -c
    } else if k3 {
        s
    } else {
        c
    };
    let sin = if k1 {
        c
    } else if k2 {
        -s
    } else if k3 {
        -c
    } else {
        s
    };
    (cos, sin)
}

/// [`concentric_disk`] with a polynomial sine and cosine, branch-free: it vectorises across
/// lanes (the Lambertian kernel's directions and the sky's light samples).
#[inline(always)]
pub fn disk_branch_free(u: [f32; 2]) -> (f32, f32) {
    let (ox, oy) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    let wide = ox.abs() > oy.abs();
    let (r, ratio) = if wide { (ox, oy / ox) } else { (oy, ox / oy) };
    let (s, c) = sin_cos_quarter(std::f32::consts::FRAC_PI_4 * ratio);
    let (x, y) = if wide { (r * c, r * s) } else { (r * s, r * c) };
    let zero = ox == 0.0 && oy == 0.0;
    (if zero { 0.0 } else { x }, if zero { 0.0 } else { y })
}

/// Uniform direction on the unit sphere.
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (cos_phi, sin_phi) = cos_sin_turn(u.y);
    Vec3A::new(r * cos_phi, r * sin_phi, z)
}

/// `sin(x)`: the angle reduced to a turn in `f64`, then [`cos_sin_turn`]'s polynomial (absolute
/// error below 6e-7). The same bits on every machine, which the C library's
/// `sinf` does not promise.
#[inline]
pub fn sin(x: f32) -> f32 {
    let t = x as f64 / std::f64::consts::TAU;
    cos_sin_turn((t - t.floor()) as f32).1
}

/// `atan2(y, x)` from IEEE operations alone: the ratio of the smaller magnitude to the larger,
/// reduced to [-tan(pi/8), tan(pi/8)], and the polynomial of Cephes' `atanf` (S. L. Moshier,
/// Cephes Mathematical Library); absolute error below 3e-7. The same bits on every machine,
/// which the C library's `atan2f` does not promise. Unlike it, `atan2(+-0, -0)` is `+-0` and
/// two infinities give NaN; NaN in, NaN out.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let (ax, ay) = (x.abs(), y.abs());
    // Comparisons with NaN are false: a NaN reaches the ratio and the result.
    let steep = ay > ax;
    let (lo, hi) = if steep { (ax, ay) } else { (ay, ax) };
    let a = if hi == 0.0 { 0.0 } else { lo / hi };
    let far = a > 0.414_213_57;
    let t = if far { (a - 1.0) / (a + 1.0) } else { a };
    let z = t * t;
    let p = (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t + t;
    let r = if far { FRAC_PI_4 + p } else { p };
    let r = if steep { FRAC_PI_2 - r } else { r };
    let r = if x < 0.0 { PI - r } else { r };
    r.copysign(y)
}

/// `acos(x)` for x in [-1, 1] as [`atan2`] of `sqrt((1 - x)(1 + x))` and `x` (absolute error
/// below 3e-7); NaN outside.
#[inline]
pub fn acos(x: f32) -> f32 {
    atan2(((1.0 - x) * (1.0 + x)).sqrt(), x)
}

/// The cube root of `x`: an estimate from the exponent bits, two steps of Halley's iteration
/// in `f64` (each cubes the relative error, 3% -> 3e-5 -> 3e-14), rounded to `f32`. The same
/// bits on every machine, which the C library's `cbrtf` does not promise. Without branches
/// (zero, infinities and NaN are selected after), so that a loop over lanes of it vectorises.
#[inline(always)]
pub fn cbrt(x: f32) -> f32 {
    let a = x.abs();
    // Kahan's estimate: the biased exponent (and mantissa bits) divided by three, on `f32`
    // bits (a `u64` division has no vector instruction); a subnormal `a` scaled by 2^24 first
    // and its root by 2^-8 after.
    let tiny = a < f32::MIN_POSITIVE;
    let scaled = if tiny { a * 16_777_216.0 } else { a };
    let y0 = f32::from_bits(scaled.to_bits() / 3 + 0x2a51_4067) * if tiny { 1.0 / 256.0 } else { 1.0 };
    let (a, mut y) = (a as f64, y0 as f64);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * a) / (2.0 * y3 + a);
    }
    let root = (y as f32).copysign(x);
    if x == 0.0 || !x.is_finite() { x } else { root }
}

/// Subintervals of [`ln`]'s table: `|r| < 0.008`, so that four terms of `log1p(r)` leave a
/// relative error below 1e-9.
const LN_BITS: u32 = 6;

/// `ln(2)` in `f64`.
const LN2: f64 = std::f64::consts::LN_2;

/// `ln(c)` for `c` in [0.5, 2] in `f64`, at compile time: `2 atanh(s)` with `s = (c-1)/(c+1)`
/// (|s| <= 1/3) summed until the terms vanish.
const fn ln_series(c: f64) -> f64 {
    let s = (c - 1.0) / (c + 1.0);
    let (s2, mut term, mut sum, mut k) = (s * s, s, 0.0, 0);
    while k < 40 {
        sum += term / (2 * k + 1) as f64;
        term *= s2;
        k += 1;
    }
    2.0 * sum
}

/// Per subinterval `i` of [`ln`]'s reduced argument, `(1/c, ln c)` for `c` its middle.
const LN_TABLE: [(f64, f64); 1 << LN_BITS] = {
    let mut t = [(0.0, 0.0); 1 << LN_BITS];
    let mut i = 0;
    while i < t.len() {
        let c = f32::from_bits(LN_OFF + ((i as u32) << (23 - LN_BITS)) + (1 << (22 - LN_BITS))) as f64;
        t[i] = (1.0 / c, ln_series(c));
        i += 1;
    }
    t
};

/// The bits of the reduced argument's lower end, 0.6992...: `z` lies in [0.699, 1.398).
const LN_OFF: u32 = 0x3f33_0000;

/// `ln(x)` from IEEE operations alone, the method of ARM's optimized-routines `logf`
/// (Szabolcs Nagy): `x = 2^k z` with `z` in [0.699, 1.398), `ln x = k ln 2 + ln c + log1p(z/c -
/// 1)` for the `c` of `z`'s subinterval (64, from a table computed at compile time), `log1p` by
/// four terms, all in `f64` and rounded once. The same bits on every machine, which the C
/// library's `logf` does not promise; as fast (no call, a short dependency chain). `ln(0)` is
/// `-inf`, negative numbers give NaN, `ln(inf)` is `inf`.
#[inline]
pub fn ln(x: f32) -> f32 {
    let mut ix = x.to_bits();
    let mut k0 = 0i32;
    if !(ix.wrapping_sub(0x0080_0000) < 0x7f80_0000 - 0x0080_0000) {
        // Zero, subnormal, negative, infinite or NaN.
        if ix << 1 == 0 {
            return f32::NEG_INFINITY;
        }
        if ix == 0x7f80_0000 || x.is_nan() {
            return x;
        }
        if ix >> 31 != 0 {
            return f32::NAN;
        }
        // Subnormal: normalised by 2^23.
        ix = (x * 8_388_608.0).to_bits();
        k0 = -23;
    }
    ln_core(ix, k0)
}

/// [`ln`] without branches, for loops that compute across lanes (the lane kernels): every
/// case is computed and the result selected. The same bits as [`ln`] for every input but NaN
/// (a NaN in, a NaN out, its payload not kept).
#[inline(always)]
pub fn ln_branch_free(x: f32) -> f32 {
    let ix = x.to_bits();
    // Positive subnormals, normalised by 2^23.
    let sub = ix.wrapping_sub(1) < 0x007f_ffff;
    let v = ln_core(if sub { (x * 8_388_608.0).to_bits() } else { ix }, if sub { -23 } else { 0 });
    let normal = ix.wrapping_sub(0x0080_0000) < 0x7f80_0000 - 0x0080_0000;
    let special = match () {
        _ if ix << 1 == 0 => f32::NEG_INFINITY,
        _ if ix == 0x7f80_0000 || x.is_nan() => x,
        _ => f32::NAN,
    };
    if normal || sub { v } else { special }
}

/// [`ln`] of the positive normal number whose bits are `ix`, times `2^k0`.
#[inline(always)]
fn ln_core(ix: u32, k0: i32) -> f32 {
    let tmp = ix.wrapping_sub(LN_OFF);
    let i = (tmp >> (23 - LN_BITS)) as usize % (1 << LN_BITS);
    let k = (tmp as i32 >> 23) + k0;
    let z = f32::from_bits(ix.wrapping_sub(tmp & 0xff80_0000)) as f64;
    let (invc, logc) = LN_TABLE[i];
    let r = z * invc - 1.0;
    let r2 = r * r;
    // log1p(r) = r - r^2/2 + r^3/3 - r^4/4 (Estrin's scheme).
    let p = (r - 0.5 * r2) + r2 * (r * (1.0 / 3.0) - 0.25 * r2);
    (k as f64 * LN2 + logc + p) as f32
}

/// Subintervals of a unit of [`exp`]'s exponent of two.
const EXP_BITS: u32 = 5;

/// `2^(i/32)` for `i` in 0..32, at compile time (the series of `exp(i ln 2 / 32)`).
const EXP_TABLE: [f64; 1 << EXP_BITS] = {
    let mut t = [0.0; 1 << EXP_BITS];
    let mut i = 0;
    while i < t.len() {
        let y = i as f64 * LN2 / (1 << EXP_BITS) as f64;
        let (mut term, mut sum, mut k) = (1.0, 0.0, 1);
        while k < 30 {
            sum += term;
            term *= y / k as f64;
            k += 1;
        }
        t[i] = sum;
        i += 1;
    }
    t
};

/// `exp(x)` from IEEE operations alone, the method of ARM's optimized-routines `expf`
/// (Szabolcs Nagy): `x = (k + r/1) ln 2 / 32` with integer `k` and |r| <= 1/2, `exp x = 2^(k/32)
/// 2^(r/32)`, the first factor from a table computed at compile time and the exponent's bits,
/// the second by five terms of its series, all in `f64` and rounded once. The same bits on
/// every machine, which the C library's `expf` does not promise. Overflows to `inf` above
/// 88.73, underflows to `0` below -104; NaN in, NaN out.
#[inline]
pub fn exp(x: f32) -> f32 {
    if !(x.abs() < 88.0) {
        if x > 88.0 {
            // Past 88.72 even the rounding to f32 overflows; below, f64 holds it.
            return if x > 88.8 { f32::INFINITY } else { exp_core(x) };
        }
        if x < -104.0 {
            return 0.0;
        }
        if x.is_nan() {
            return x;
        }
    }
    exp_core(x)
}

/// [`exp`] without branches, for loops that compute across lanes (the lane kernels): the
/// argument clamped to the range the core computes, the ends selected. The same bits as
/// [`exp`] for every input but NaN (a NaN in, a NaN out, its payload not kept).
#[inline(always)]
pub fn exp_branch_free(x: f32) -> f32 {
    let v = exp_core(x.clamp(-104.0, 88.8));
    if x > 88.8 {
        f32::INFINITY
    } else if x < -104.0 {
        0.0
    } else {
        v
    }
}

/// [`exp`] for `x` in [-104, 88.8].
#[inline(always)]
fn exp_core(x: f32) -> f32 {
    const N: f64 = (1 << EXP_BITS) as f64;
    // 1.5 2^52: added to |z| < 2^51, the sum's last place is 1, so its mantissa holds
    // `round_ties_even(z) + 2^51` (no conversion from float to integer, which the lane
    // kernels' loops do not vectorise).
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let z = x as f64 * (N / LN2);
    let shifted = z + SHIFT;
    let kd = shifted - SHIFT;
    let r = (z - kd) * (LN2 / N);
    let ki = (shifted.to_bits() & ((1 << 52) - 1)) as i64 - (1 << 51);
    let t = EXP_TABLE[(ki & ((1 << EXP_BITS) - 1)) as usize];
    // 2^(ki / N) = 2^(ki mod N / N) 2^floor(ki / N): the second factor added to the exponent.
    let s = f64::from_bits(t.to_bits().wrapping_add(((ki >> EXP_BITS) as u64) << 52));
    let r2 = r * r;
    // exp(r) = 1 + r + r^2/2 + r^3/6 + r^4/24 (Estrin's scheme).
    let p = (1.0 + r) + r2 * ((0.5 + r * (1.0 / 6.0)) + r2 * (1.0 / 24.0));
    (s * p) as f32
}

/// World bounds of an object box under an affine map (its eight corners mapped).
pub fn transform_box(b: &obvhs::aabb::Aabb, m: &glam::Affine3A) -> obvhs::aabb::Aabb {
    let mut out = obvhs::aabb::Aabb::empty();
    for i in 0..8 {
        let c = Vec3A::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        );
        out.extend(m.transform_point3a(c));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vectors whose squared length is subnormal or underflows normalise to unit length (the
    /// sum of cancelling vertex normals the `serialized` fuzzer found normalised to 0.92), and
    /// so do those whose squared length overflows (the normal of a triangle 1e10 across, once
    /// dropped as having no finite area); ordinary ones to the bits `normalize` and `length`
    /// give.
    #[test]
    fn lengths_and_unit_vectors_beyond_the_squares_range() {
        for v in [Vec3A::new(1e-20, 0.0, 5e-38), Vec3A::new(3e-23, -2e-23, 1e-45), Vec3A::splat(1e-30)] {
            let n = unit(v).unwrap();
            assert!((n.length() - 1.0).abs() < 1e-6, "{v} -> {n}");
        }
        for v in [Vec3A::new(4e20, -3e20, 0.0), Vec3A::new(1e30, 2e30, -2e30), Vec3A::splat(f32::MAX)] {
            let n = unit(v).unwrap();
            assert!((n.length() - 1.0).abs() < 1e-6, "{v} -> {n}");
            let expected = v.as_dvec3().length();
            assert!((length(v) as f64 / expected - 1.0).abs() < 1e-6 || expected > f32::MAX as f64);
        }
        assert_eq!(length(Vec3A::new(4e20, -3e20, 0.0)), 5e20);
        let v = Vec3A::new(0.3, -0.2, 0.9);
        assert_eq!(unit(v), Some(v.normalize()));
        assert_eq!(length(v), v.length());
        assert_eq!(unit(Vec3A::ZERO), None);
        assert_eq!(unit(Vec3A::new(f32::NAN, 0.0, 1.0)), None);
        assert_eq!(length(Vec3A::ZERO), 0.0);
        assert!(length(Vec3A::new(f32::NAN, 0.0, 1.0)).is_nan());
    }

    #[test]
    fn polynomial_sine_and_cosine_are_accurate_on_the_quarter() {
        for k in 0..=2000 {
            let x = -std::f32::consts::FRAC_PI_4 + std::f32::consts::FRAC_PI_4 * 2.0 * k as f32 / 2000.0;
            let (s, c) = sin_cos_quarter(x);
            assert!((s - x.sin()).abs() < 4e-7 && (c - x.cos()).abs() < 2e-7, "{x}");
        }
    }

    #[test]
    fn turns_give_the_cosine_and_sine_of_the_whole_circle() {
        for k in 0..=40_000 {
            let u = k as f32 / 40_000.0;
            let (c, s) = cos_sin_turn(u);
            let a = std::f64::consts::TAU * u as f64;
            assert!((c as f64 - a.cos()).abs() < 1e-6 && (s as f64 - a.sin()).abs() < 1e-6, "{u}: {c} {s}");
        }
    }

    #[test]
    fn disk_matches_the_concentric_map() {
        for k in 0..10_000 {
            let u = [(k % 100) as f32 / 100.0 + 0.003, (k / 100) as f32 / 100.0 + 0.007];
            let (x, y) = disk_branch_free(u);
            // Shirley and Chiu's map in f64 with the C library's sine and cosine.
            let (ox, oy) = (2.0 * u[0] as f64 - 1.0, 2.0 * u[1] as f64 - 1.0);
            let (r, theta) = match ox.abs() > oy.abs() {
                true => (ox, std::f64::consts::FRAC_PI_4 * (oy / ox)),
                false => (oy, std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (ox / oy)),
            };
            let (rx, ry) = (r * theta.cos(), r * theta.sin());
            assert!((x as f64 - rx).abs() < 1e-6 && (y as f64 - ry).abs() < 1e-6, "{u:?}");
        }
        assert_eq!(disk_branch_free([0.5, 0.5]), (0.0, 0.0));
    }

    #[test]
    fn sine_arctangent_arccosine_and_cube_root_are_accurate() {
        let mut worst = [0f64; 4];
        for k in 0..=200_000 {
            // Angles around the circle at radii from 1e-30 to 1e30.
            let a = std::f64::consts::TAU * k as f64 / 200_000.0 - std::f64::consts::PI;
            let r = 10f64.powi(k % 61 - 30);
            let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
            worst[0] = worst[0].max((atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs());
            let c = (k as f32 / 100_000.0 - 1.0).clamp(-1.0, 1.0);
            worst[1] = worst[1].max((acos(c) as f64 - (c as f64).acos()).abs());
            let s = (k as f32 - 100_000.0) * 0.031;
            worst[2] = worst[2].max((sin(s) as f64 - (s as f64).sin()).abs());
            let v = (k as f32 + 0.5) * 10f32.powi(k % 41 - 25);
            let exact = (v as f64).cbrt();
            worst[3] = worst[3].max((cbrt(v) as f64 - exact).abs() / exact);
            assert_eq!(cbrt(-v), -cbrt(v));
            // Subnormals too.
            let t = v * 1e-15;
            worst[3] = worst[3].max((cbrt(t) as f64 - (t as f64).cbrt()).abs() / (t as f64).cbrt());
        }
        assert!(worst[0] < 3e-7 && worst[1] < 3e-7 && worst[2] < 6e-7 && worst[3] < 6e-8, "{worst:?}");
        use std::f32::consts::{FRAC_PI_2, PI};
        for (y, x, want) in [(0.0, 1.0, 0.0), (1.0, 0.0, FRAC_PI_2), (0.0, -1.0, PI), (-1.0, 0.0, -FRAC_PI_2)]
        {
            assert_eq!(atan2(y, x), want, "atan2({y}, {x})");
        }
        assert_eq!((atan2(0.0, 0.0), atan2(-0.0, 1.0).to_bits()), (0.0, (-0.0f32).to_bits()));
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan() && acos(1.5).is_nan());
        assert_eq!((cbrt(0.0), cbrt(8.0), cbrt(-27.0), cbrt(1.0)), (0.0, 2.0, -3.0, 1.0));
        assert_eq!((cbrt(f32::INFINITY), cbrt(-0.0).to_bits()), (f32::INFINITY, (-0.0f32).to_bits()));
        assert!(cbrt(f32::NAN).is_nan());
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3A::Z, -Vec3A::Z, Vec3A::X, Vec3A::new(0.3, -0.4, 0.866).normalize()] {
            let f = Frame::from_normal(n);
            assert!((f.t.length() - 1.0).abs() < 1e-6);
            assert!((f.b.length() - 1.0).abs() < 1e-6);
            assert!(f.t.dot(f.b).abs() < 1e-6 && f.t.dot(n).abs() < 1e-6 && f.b.dot(n).abs() < 1e-6);
            assert!((f.t.cross(f.b) - n).length() < 1e-5, "right handed");
        }
    }

    #[test]
    fn step_away_is_next_up_and_next_down() {
        let mut xs = vec![0.0f32, -0.0, 1.0, -1.0, f32::MAX, f32::MIN, f32::INFINITY, f32::NEG_INFINITY];
        xs.extend([f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::from_bits(1), -f32::from_bits(1), f32::NAN]);
        xs.extend((0..2000).map(|k| f32::from_bits((k as u32).wrapping_mul(2_654_435_761))));
        for x in xs {
            for o in [1.0f32, -1.0, 0.0, -0.0, f32::NAN, 1e-30] {
                let want = if o > 0.0 {
                    x.next_up()
                } else if o < 0.0 {
                    x.next_down()
                } else {
                    x
                };
                assert_eq!(step_away(x, o).to_bits(), want.to_bits(), "{x:e} ({:#x}) {o}", x.to_bits());
            }
        }
    }

    #[test]
    fn offset_clears_the_error_bound_at_every_scale() {
        for scale in [1e-6f32, 1e-3, 1.0, 555.0, 1e5] {
            let p = Vec3A::new(0.3, -0.7, 0.2) * scale;
            let n = Vec3A::new(0.0, 1.0, 0.0);
            let err = gamma(4) * scale;
            let o = offset_ray_origin(p, err, n);
            assert_eq!((o.x, o.z), (p.x, p.z));
            assert!(o.y - p.y >= err, "scale {scale}");
            assert!(
                o.y - p.y <= 2.0 * err + 2.0 * (p.y.next_up() - p.y).abs(),
                "scale {scale}: offset too large"
            );
        }
    }

    /// Distance in units of the last place of f32 between `got` and the exact `want`.
    fn ulps(got: f32, want: f64) -> f64 {
        let w = want as f32;
        let ulp = (w.abs().next_up() - w.abs()) as f64;
        (got as f64 - want).abs() / ulp.max(f32::from_bits(1) as f64)
    }

    #[test]
    fn ln_is_within_an_ulp_everywhere_and_exact_where_it_must_be() {
        // Every 97th float from the smallest subnormal to the largest finite one.
        let mut worst: f64 = 0.0;
        for bits in (1..0x7f80_0000u32).step_by(97) {
            let x = f32::from_bits(bits);
            worst = worst.max(ulps(ln(x), (x as f64).ln()));
        }
        assert!(worst < 0.51, "worst {worst} ulp");
        // Near 1, where ln x ~ x - 1 is small.
        for k in 1..2000 {
            for x in [1.0 + k as f32 * f32::EPSILON, 1.0 - k as f32 * f32::EPSILON / 2.0] {
                worst = worst.max(ulps(ln(x), (x as f64).ln()));
            }
        }
        assert!(worst < 0.51, "worst {worst} ulp near 1");
        assert_eq!(ln(1.0), 0.0);
        let specials = (ln(0.0), ln(-0.0), ln(f32::INFINITY));
        assert_eq!(specials, (f32::NEG_INFINITY, f32::NEG_INFINITY, f32::INFINITY));
        assert!(ln(-1.0).is_nan() && ln(f32::NAN).is_nan() && ln(f32::NEG_INFINITY).is_nan());
    }

    #[test]
    fn exp_is_within_an_ulp_everywhere_and_exact_where_it_must_be() {
        let mut worst: f64 = 0.0;
        // From -103.5 (subnormal results) to 88.65.
        for i in -2_300_000..=1_970_000 {
            let x = i as f32 * 4.5e-5;
            worst = worst.max(ulps(exp(x), (x as f64).exp()));
        }
        for x in [88.7f32, 88.72, -87.3, -100.0, -103.9, 1e-7, -1e-7, 1e-30] {
            worst = worst.max(ulps(exp(x), (x as f64).exp()));
        }
        assert!(worst < 0.51, "worst {worst} ulp");
        assert_eq!(exp(0.0), 1.0);
        let specials = (exp(89.0), exp(f32::INFINITY), exp(-105.0), exp(f32::NEG_INFINITY));
        assert_eq!(specials, (f32::INFINITY, f32::INFINITY, 0.0, 0.0));
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(exp(88.73), f32::INFINITY, "past f32::MAX");
    }

    /// The lane kernels' [`ln_branch_free`] and [`exp_branch_free`] give [`ln`]'s and [`exp`]'s
    /// bits on every 61st float of either sign (subnormals, zeros, infinities and the ends of
    /// `exp`'s range included), and NaN for NaN.
    #[test]
    fn branch_free_ln_and_exp_have_the_bits_of_the_others() {
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let edges =
            [0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 88.8, 88.80001, -104.0, -104.00001];
        let every = (0..=u32::MAX).step_by(61).map(f32::from_bits);
        for x in every.chain(edges) {
            assert!(same(ln_branch_free(x), ln(x)), "ln({x:e}): {} vs {}", ln_branch_free(x), ln(x));
            assert!(same(exp_branch_free(x), exp(x)), "exp({x:e}): {} vs {}", exp_branch_free(x), exp(x));
        }
    }
}
