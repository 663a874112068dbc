//! Triangle meshes in object space ([`MeshData`], with their attributes) and their
//! bottom-level BVH ([`MeshBlas`], in `blas.rs`), whose leaves are blocks of up to eight
//! triangles tested eight at a time (`block.rs`).

mod blas;
mod block;

pub use blas::{MeshBlas, MeshHit, terminator_lift};
pub use block::TriRay;

use glam::Vec3A;

/// A triangle mesh: positions and index triples. Degenerate triangles are kept here and
/// skipped by the BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3A>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Vertex normals (indexed like `positions`), for smooth shading; `None`: flat shading.
    pub normals: Option<Vec<Vec3A>>,
    /// Vertex texture coordinates (indexed like `positions`); `None`: barycentric uv.
    pub uvs: Option<Vec<glam::Vec2>>,
    /// Named values per vertex or per triangle (a PLY file's other properties), for the
    /// `MeshAttribute` texture.
    pub attributes: Vec<MeshAttribute>,
}

/// Values a mesh file gives each vertex or each face beside its positions, normals and uv
/// (Mitsuba 3's mesh attributes, `include/mitsuba/render/mesh.h`): flat, `channels` per vertex
/// (indexed like `MeshData::positions`) or per triangle (like `MeshData::triangles`; a polygon's
/// triangles repeat its values).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// Mitsuba's name: `vertex_` or `face_` and the property's prefix (`vertex_color`,
    /// `face_weight`); the first word says which.
    pub name: String,
    /// Values per vertex or triangle: 1 or 3.
    pub channels: usize,
    /// The values, `channels` per vertex or triangle.
    pub values: Vec<f32>,
}

impl MeshAttribute {
    /// Per vertex (interpolated by barycentric weights), not per face.
    pub fn per_vertex(&self) -> bool {
        self.name.starts_with("vertex_")
    }

    /// The attribute at a point of triangle `tri` (vertices `v`) with barycentric weights `b` of
    /// its second and third vertices: interpolated per vertex, constant per face; one channel is
    /// grey. Indices beyond the values give black (a checked mesh has none).
    pub fn at(&self, tri: u32, v: [u32; 3], b: glam::Vec2) -> glam::Vec3 {
        let value = |i: usize| {
            let c = self.channels;
            match self.values.get(i * c..i * c + c) {
                Some(&[x]) => glam::Vec3::splat(x),
                Some(&[x, y, z]) => glam::Vec3::new(x, y, z),
                _ => glam::Vec3::ZERO,
            }
        };
        if !self.per_vertex() {
            return value(tri as usize);
        }
        let [a, bb, c] = v.map(|i| value(i as usize));
        (1.0 - b.x - b.y) * a + b.x * bb + b.y * c
    }
}

impl MeshData {
    /// Triangle `i`.
    #[inline]
    pub fn triangle(&self, i: u32) -> [Vec3A; 3] {
        self.triangles[i as usize].map(|v| self.positions[v as usize])
    }

    /// The (2,3) torus-knot tube of the Embree comparison (`benches/embree/anchor.c`) with
    /// `rings` rings of `segments` vertices: `2 rings segments` triangles (1,000,000 for 2000 x 250).
    pub fn knot(rings: u32, segments: u32) -> Self {
        use std::f64::consts::TAU;
        let mut positions = Vec::with_capacity((rings * segments) as usize);
        for i in 0..rings {
            let t = TAU * i as f64 / rings as f64;
            let (s2, c2, s3, c3) = ((2.0 * t).sin(), (2.0 * t).cos(), (3.0 * t).sin(), (3.0 * t).cos());
            let r = c3 + 2.0;
            let (r1, r2) = (-3.0 * s3, -9.0 * c3);
            let c = glam::DVec3::new(r * c2, r * s2, -s3);
            let d1 = glam::DVec3::new(r1 * c2 - 2.0 * r * s2, r1 * s2 + 2.0 * r * c2, -3.0 * c3);
            let d2 = glam::DVec3::new(
                r2 * c2 - 4.0 * r1 * s2 - 4.0 * r * c2,
                r2 * s2 + 4.0 * r1 * c2 - 4.0 * r * s2,
                9.0 * s3,
            );
            // Frenet frame: T along c', N the part of c'' across T, B = T x N.
            let tangent = d1.normalize();
            let normal = (d2 - d2.dot(tangent) * tangent).normalize();
            let binormal = tangent.cross(normal);
            for j in 0..segments {
                let theta = TAU * j as f64 / segments as f64;
                let rad = 0.4 * (1.0 + 0.08 * (60.0 * t).sin() * (6.0 * theta).sin());
                let p = c + rad * (theta.cos() * normal + theta.sin() * binormal);
                positions.push(p.as_vec3().into());
            }
        }
        let mut triangles = Vec::with_capacity(2 * (rings * segments) as usize);
        let at = |i: u32, j: u32| (i % rings) * segments + j % segments;
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Self { positions, triangles, normals: None, uvs: None, attributes: Vec::new() }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::accel::bvh8::PACKET;
    use crate::shape::{PrimitiveShape, Triangle};
    use std::sync::Arc;

    /// The AVX2 block test and its scalar fallback agree: the same lanes hit, the same lanes
    /// left to the exact test, the same distances where hit (rays through the knot's blocks,
    /// some from its vertices).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[test]
    fn the_scalar_block_test_gives_the_avx2_bits() {
        let mesh = Arc::new(MeshData::knot(40, 16));
        let blas = MeshBlas::build(mesh.clone());
        let mut rnd = crate::testing::signed(7);
        let mut hits = 0;
        for i in 0..3000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 5.0;
            let o = if i % 4 == 0 { mesh.positions[i % mesh.positions.len()] } else { o };
            let d = Vec3A::new(rnd(), rnd(), rnd()) * 2.0 - o * 0.5 * (i % 2) as f32;
            let r = TriRay::new(o, d);
            let tmax = if i % 3 == 0 { 2.0 } else { f32::INFINITY };
            for b in &blas.blocks {
                let (t, hit, zero) = b.lanes(&r, tmax);
                let (t_s, hit_s, zero_s) = b.lanes_scalar(&r, tmax);
                assert_eq!((hit, zero), (hit_s, zero_s), "ray {o} {d}");
                for l in (0..8).filter(|l| hit >> l & 1 != 0) {
                    assert_eq!(t[l].to_bits(), t_s[l].to_bits(), "ray {o} {d} lane {l}");
                }
                hits += hit.count_ones();
            }
        }
        assert!(hits > 1000, "the rays hit triangles ({hits})");
    }

    /// Triangles up to the scene's coordinate bound (1e15) are hit, by the mesh and alone, at
    /// their distance, with a unit normal: at 1e10 their area once squared beyond `f32` (the
    /// mesh dropped them as having no finite area), and from 1e13 the watertight test's scaled
    /// distance overflowed (they were missed).
    #[test]
    fn triangles_as_large_and_far_as_the_scene_allows_are_hit() {
        for s in [1.0f32, 1e10, 1e12, 1e13, 1e14, 3e14] {
            let mesh = Arc::new(MeshData {
                positions: vec![Vec3A::new(-s, -s, 0.0), Vec3A::new(s, -s, 0.0), Vec3A::new(0.0, s, 0.0)],
                triangles: vec![[0, 1, 2]],
                ..Default::default()
            });
            let blas = MeshBlas::build(mesh.clone());
            let tri = Triangle::new(mesh.positions[0], mesh.positions[1], mesh.positions[2]).unwrap();
            assert!(tri.area() / (2.0 * s * s) - 1.0 < 1e-6, "{s}: area {}", tri.area());
            for (o, d) in [
                (Vec3A::new(0.0, 0.0, 3.0 * s), Vec3A::NEG_Z),
                (Vec3A::new(0.1 * s, -0.2 * s, -3.0 * s), Vec3A::new(0.01, 0.02, 1.0)),
            ] {
                let want = 3.0 * s / d.z.abs();
                let alone = tri.intersect(o, d, f32::INFINITY);
                let hit = blas.intersect(o, d, f32::INFINITY).unwrap_or_else(|| panic!("{s}: missed"));
                assert!((alone / want - 1.0).abs() < 1e-5, "{s}: t {alone} for {want}");
                assert_eq!(hit.t, alone, "{s}");
                assert!(blas.occluded(o, d, f32::INFINITY), "{s}");
                assert!(!blas.occluded(o, d, 0.5 * want), "{s}");
                let n = tri.surface(o + hit.t * d).n;
                assert!((n.length() - 1.0).abs() < 1e-6 && n.z.abs() > 0.999, "{s}: normal {n}");
            }
        }
    }

    #[test]
    fn blas_hits_equal_a_scan_of_the_scalar_test() {
        let mesh = Arc::new(MeshData::knot(60, 24));
        let blas = MeshBlas::build(mesh.clone());
        blas.validate().unwrap();
        let mut rnd = crate::testing::signed(3);
        let mut hits = 0;
        for i in 0..4000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 5.0;
            // Some rays start on the surface: at a vertex, aimed across the mesh.
            let o = if i % 4 == 0 { mesh.positions[i % mesh.positions.len()] } else { o };
            let d = Vec3A::new(rnd(), rnd(), rnd()) * 2.0 - o * 0.5 * (i % 2) as f32;
            let all: Vec<(f32, u32)> = (0..mesh.triangles.len() as u32)
                .map(|k| {
                    let [a, b, c] = mesh.triangle(k);
                    (Triangle { p: [a, b, c], uv: None }.intersect(o, d, f32::INFINITY), k)
                })
                .filter(|h| h.0.is_finite())
                .collect();
            let scan = all.iter().fold((f32::INFINITY, u32::MAX), |a, b| if b.0 < a.0 { *b } else { a });
            let mut want: Vec<f32> = all.iter().map(|h| h.0).collect();
            let mut listed = Vec::new();
            blas.all_hits(o, d, &mut listed);
            want.sort_by(f32::total_cmp);
            listed.sort_by(f32::total_cmp);
            assert_eq!(listed, want, "every hit of ray {o} {d}");
            let got = blas.intersect(o, d, f32::INFINITY);
            assert_eq!(got.map(|h| h.t), scan.1.ne(&u32::MAX).then_some(scan.0), "ray {o} {d}");
            assert_eq!(blas.occluded(o, d, f32::INFINITY), got.is_some());
            if let Some(h @ MeshHit { t, id, p }) = got {
                hits += 1;
                let [a, b, c] = mesh.triangle(id);
                assert_eq!(p, [a, b, c], "the block's corners are the mesh's");
                assert_eq!(h.ng(), (b - a).cross(c - a));
                assert_eq!(t, scan.0);
                assert!(!blas.occluded(o, d, t * 0.999) || t < 1e-3, "nothing lies before the closest hit");
                assert!(blas.occluded(o, d, t * 1.001), "the closest hit occludes");
            }
        }
        assert!(hits > 1000, "{hits}");
    }

    /// Rays of a packet: one origin and directions within `spread` of one another (a pixel's
    /// samples when small, bounce rays when large); `tmax` negative (left out), finite or not.
    pub(crate) fn packet(
        rnd: &mut impl FnMut() -> f32,
        spread: f32,
        scale: f32,
    ) -> ([[f32; PACKET]; 3], [[f32; PACKET]; 3], [f32; PACKET]) {
        let (o0, d0) = (Vec3A::new(rnd(), rnd(), rnd()) * 5.0 * scale, Vec3A::new(rnd(), rnd(), rnd()));
        let (mut o, mut d) = ([[0.0; PACKET]; 3], [[0.0; PACKET]; 3]);
        let mut tmax = [f32::INFINITY; PACKET];
        for l in 0..PACKET {
            let (ol, dl) = (
                o0 + Vec3A::new(rnd(), rnd(), rnd()) * 0.01 * scale,
                -o0 / scale + (d0 + Vec3A::new(rnd(), rnd(), rnd()) * spread),
            );
            for a in 0..3 {
                (o[a][l], d[a][l]) = (ol[a], dl[a]);
            }
            tmax[l] = match l % 5 {
                0 => -1.0,
                1 => rnd().abs() * 1.5,
                _ => f32::INFINITY,
            };
        }
        (o, d, tmax)
    }

    #[test]
    fn packets_find_what_each_ray_finds_alone() {
        let blas = MeshBlas::build(Arc::new(MeshData::knot(60, 24)));
        let mut rnd = crate::testing::signed(8);
        let (mut occluded, mut rays) = (0, 0);
        for i in 0..400 {
            let (o, d, tmax) = packet(&mut rnd, if i % 2 == 0 { 0.02 } else { 2.0 }, 1.0);
            let occ = crate::simd::lanes(|| blas.occluded_packet(&o, &d, &tmax));
            for l in 0..PACKET {
                let (ol, dl) = (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
                let alone = tmax[l] >= 0.0 && blas.occluded(ol, dl, tmax[l]);
                assert_eq!(occ >> l & 1 != 0, alone, "lane {l} of packet {i}");
                (occluded, rays) = (occluded + alone as u32, rays + (tmax[l] >= 0.0) as u32);
            }
        }
        assert!(occluded > 1000 && rays - occluded > 500, "{occluded} of {rays} occluded");
    }

    #[test]
    fn the_knot_has_the_anchor_triangle_count() {
        let m = MeshData::knot(2000, 250);
        assert_eq!(m.triangles.len(), 1_000_000);
        assert!(m.positions.iter().all(|p| p.is_finite() && p.length() < 3.5));
    }
}
