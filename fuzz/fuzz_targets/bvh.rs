//! Arbitrary bytes into crowded primitive sets for the 8-wide BVH that every BVH of the engine
//! is (TLAS, mesh BLAS, the primitive BVH): a few groups, each one box that the input copies,
//! nests about its centre, nests along a line, moves by a rounding at a time or scatters, as
//! many times as it says. The tree must validate and stay within `MAX_DEPTH` levels, and rays
//! into it must find what a scan of the boxes finds, alone and in packets; a mesh BLAS of a
//! triangle in each box must find what a scan of the triangles finds. Nothing may panic.
#![no_main]

use glam::Vec3A;
use libfuzzer_sys::fuzz_target;
use obvhs::aabb::Aabb;
use pathwave_engine::accel::bvh8::{Bvh8, MAX_DEPTH, PACKET};
use pathwave_engine::accel::mesh::{MeshBlas, MeshData};
use pathwave_engine::shape::{Primitive, Triangle};
use std::sync::Arc;

/// At most this many boxes (and triangles) per input, to keep an execution short: enough for
/// crowds (more than 8 in a Morton cell) and chains deeper than `MAX_DEPTH` to be rebuilt. At
/// 12,000 a run made 3 executions a second (the checks scan every box for each ray).
const MAX_PRIMS: usize = 150;

/// Entry distance of the ray `o + t d`, `t` in `[0, tmax]`, into `b`.
fn enters(b: &Aabb, o: Vec3A, d: Vec3A, tmax: f32) -> Option<f32> {
    let (t0, t1) = ((b.min - o) / d, (b.max - o) / d);
    let (near, far) = (t0.min(t1).max_element().max(0.0), t0.max(t1).min_element().min(tmax));
    (near <= far).then_some(near)
}

/// A closest distance the traversal found, against the scan's: a box test by reciprocal (the
/// traversal's) and one by division (the scan's) may round a ray's entry a few ulps apart.
fn close(got: f32, want: f32) -> bool {
    got == want || (got.is_finite() && want.is_finite() && got >= want && got.to_bits() - want.to_bits() <= 8)
}

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else { return };
    let max_leaf = 1 + first as u32 % 24;
    // Groups of 8 bytes: centre (3), size, kind, count (2), shape.
    let (mut boxes, mut tris) = (Vec::new(), Vec::new());
    for g in rest.chunks_exact(8) {
        let c = Vec3A::new(g[0] as i8 as f32, g[1] as i8 as f32, g[2] as i8 as f32) * 0.25;
        let size = 2f32.powi(g[3] as i32 % 24 - 12);
        let count = (u16::from_le_bytes([g[5], g[6]]) as usize % MAX_PRIMS + 1).min(MAX_PRIMS - boxes.len());
        let shape =
            Vec3A::new(1.0 + (g[7] & 3) as f32, 1.0 + (g[7] >> 2 & 3) as f32, (g[7] >> 4) as f32 / 4.0);
        let tri = [
            c + Vec3A::X * size * shape.x,
            c + Vec3A::Y * size * shape.y,
            c - Vec3A::ONE * size * (shape.z + 0.1),
        ];
        for k in 0..count {
            let s = k as f32;
            let (at, scale) = match g[4] % 5 {
                0 => (c, 1.0),                                  // copies
                1 => (c, (s + 1.0) / count as f32),             // nested about the centre
                2 => (c + Vec3A::X * s * size * 0.01, 1.0 + s), // nested along a line
                3 => (c + Vec3A::splat(s * f32::EPSILON), 1.0), // a rounding apart
                _ => (c + Vec3A::new(s.sin(), (s * 1.7).cos(), (s * 0.3).sin()) * size * 8.0, 1.0),
            };
            let e = shape * size * scale;
            boxes.push(Aabb { min: at - e, max: at + e });
            tris.push(tri.map(|v| at + (v - c) * scale));
        }
        if boxes.len() == MAX_PRIMS {
            break;
        }
    }
    if boxes.is_empty() {
        return;
    }

    // Leaf `k` (handed back as `(k, 1)`) holds `order[leaves[k].0..leaves[k].1]`.
    let (mut order, mut leaves) = (Vec::new(), Vec::new());
    let bvh = Bvh8::build(&boxes, max_leaf, |p| {
        leaves.push((order.len(), order.len() + p.len()));
        order.extend_from_slice(p);
        (leaves.len() as u32 - 1, 1)
    });
    assert!(bvh.depth() <= MAX_DEPTH);
    let items = |leaf: u32| &order[leaves[leaf as usize].0..leaves[leaf as usize].1];
    let bounds = |leaf: u32, _| items(leaf).iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
    bvh.validate(bounds).unwrap();
    assert!(leaves.iter().all(|(a, b)| b - a <= max_leaf as usize));

    // Rays from a hash of the input: from outside towards a box, or from inside one.
    let mut rnd = pathwave_fuzz::numbers(data);
    let mut ray = |k: usize| {
        let b = &boxes[(rnd() * (boxes.len() - 1) as f32) as usize];
        let to = b.center() + (b.max - b.min) * (rnd() - 0.5);
        // No direction component near zero: the scan divides by it.
        let d = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        let d = d + d.signum() * 0.05;
        if k % 4 == 3 { (to, d) } else { (to - d * 200.0, d) }
    };
    let scan = |o: Vec3A, d: Vec3A| {
        boxes.iter().filter_map(|b| enters(b, o, d, f32::INFINITY)).fold(f32::INFINITY, f32::min)
    };
    for k in 0..24 {
        let (o, d) = ray(k);
        let want = scan(o, d);
        let got = bvh.closest(o, d, f32::INFINITY, |leaf, _, best| {
            items(leaf).iter().filter_map(|&i| enters(&boxes[i as usize], o, d, best)).fold(best, f32::min)
        });
        assert!(close(got, want), "ray {k}: {got} against {want}");
        let any = bvh.any(o, d, f32::INFINITY, |leaf, _| {
            items(leaf).iter().any(|&i| enters(&boxes[i as usize], o, d, f32::INFINITY).is_some())
        });
        assert_eq!(any, want.is_finite(), "ray {k}");
    }
    let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
    for l in 0..PACKET {
        let (ol, dl) = ray(l);
        for a in 0..3 {
            (o[a][l], d[a][l]) = (ol[a], dl[a]);
        }
    }
    let lane = |l: usize| (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
    let mut best = [f32::INFINITY; PACKET];
    bvh.closest_packet(&o, &d, &mut best, |leaf, _, active, best| {
        for l in (0..PACKET).filter(|l| active >> l & 1 != 0) {
            let (o, d) = lane(l);
            best[l] = items(leaf)
                .iter()
                .filter_map(|&i| enters(&boxes[i as usize], o, d, best[l]))
                .fold(best[l], f32::min);
        }
    });
    let hit = bvh.any_packet(&o, &d, &[f32::INFINITY; PACKET], |leaf, _, active| {
        (0..PACKET)
            .filter(|l| active >> l & 1 != 0)
            .filter(|&l| {
                let (o, d) = lane(l);
                items(leaf).iter().any(|&i| enters(&boxes[i as usize], o, d, f32::INFINITY).is_some())
            })
            .fold(0, |m, l| m | 1 << l)
    });
    for l in 0..PACKET {
        let (o, d) = lane(l);
        let want = scan(o, d);
        assert!(close(best[l], want), "lane {l}: {} against {want}", best[l]);
        assert_eq!(hit >> l & 1 != 0, want.is_finite(), "lane {l}");
    }

    // The same crowds as triangles in a mesh BLAS (whose block test has the bits of
    // `Triangle`'s), against a scan of the triangles.
    let mesh = MeshData {
        positions: tris.iter().flatten().copied().collect(),
        triangles: (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        normals: None,
        uvs: None,
        attributes: Vec::new(),
    };
    let blas = MeshBlas::build(Arc::new(mesh));
    blas.validate().unwrap();
    let prims: Vec<Primitive> =
        tris.iter().filter_map(|&[a, b, c]| Triangle::new(a, b, c)).map(Primitive::Triangle).collect();
    if prims.is_empty() {
        return;
    }
    for k in 0..16 {
        let t = prims[(rnd() * (prims.len() - 1) as f32) as usize].aabb();
        let to = t.center();
        let d = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        let d = d + d.signum() * 0.05;
        let o = if k % 4 == 3 { to } else { to - d * 200.0 };
        let want = prims.iter().map(|p| p.intersect(o, d, f32::INFINITY)).fold(f32::INFINITY, f32::min);
        let got = blas.intersect(o, d, f32::INFINITY).map_or(f32::INFINITY, |h| h.t);
        assert!(close(got, want), "mesh ray {k}: {got} against {want}");
        assert_eq!(blas.occluded(o, d, f32::INFINITY), want.is_finite(), "mesh ray {k}");
    }
});
