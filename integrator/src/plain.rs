//! Vector steps written component by component, on plain numbers: the forms the lane kernels
//! run per lane (so that they vectorise across lanes) and the one-path code shares with them.

use glam::Vec3;

#[inline(always)]
pub(crate) fn sel3(c: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(if c { a.x } else { b.x }, if c { a.y } else { b.y }, if c { a.z } else { b.z })
}

#[inline(always)]
pub(crate) fn dot(a: Vec3, b: Vec3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// `offset_ray_origin` on plain numbers: error bound along the normal, then one ulp further.
#[inline(always)]
pub(crate) fn offset(p: Vec3, err: f32, n: Vec3) -> Vec3 {
    let d = err * (n.x.abs() + n.y.abs() + n.z.abs());
    let o = Vec3::new(d * n.x, d * n.y, d * n.z);
    let po = Vec3::new(p.x + o.x, p.y + o.y, p.z + o.z);
    let away = |x: f32, o: f32| {
        // next_up / next_down on the bits, branch-free for finite non-zero x.
        let bits = x.to_bits() as i32;
        let up = if x >= 0.0 { 1 } else { -1 };
        let step = if o > 0.0 {
            up
        } else if o < 0.0 {
            -up
        } else {
            0
        };
        let moved = f32::from_bits(bits.wrapping_add(step) as u32);
        if x == 0.0 {
            if o > 0.0 {
                f32::from_bits(1)
            } else if o < 0.0 {
                -f32::from_bits(1)
            } else {
                x
            }
        } else {
            moved
        }
    };
    Vec3::new(away(po.x, o.x), away(po.y, o.y), away(po.z, o.z))
}
