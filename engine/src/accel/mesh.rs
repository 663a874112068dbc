//! Triangle meshes in object space and their bottom-level BVH: an [`Bvh8`] whose leaves are
//! blocks of up to eight triangles stored lane by lane, tested eight at a time with the
//! watertight test of [`Triangle::intersect`] (same operations, same bits).

#![cfg_attr(
    target_arch = "x86_64",
    expect(unsafe_code, reason = "AVX2 intrinsics for the triangle blocks' tests, and prefetches")
)]

use crate::accel::bvh8::{Bvh8, PACKET};
use crate::math::{gamma, unit};
use crate::shape::{MeshPoint, PrimitiveShape, SurfacePoint, Triangle};
use glam::Vec3A;
use obvhs::aabb::Aabb;
use std::sync::Arc;

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

/// Up to eight triangles, lane by lane: `v[vertex][axis][lane]`. Unused lanes hold NaN, which
/// fails every comparison of the test.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct TriBlock {
    v: [[[f32; 8]; 3]; 3],
    /// Triangle index (into the mesh) per lane.
    id: [u32; 8],
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
    fn intersect(&self, r: &TriRay, o: Vec3A, d: Vec3A, tmax: f32) -> ([f32; 8], u32) {
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
    fn lanes(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
        self.lanes_scalar(r, tmax)
    }

    /// The eight tests: distances, the lanes hit and the lanes left to the caller's scalar test
    /// (an edge function exactly zero, a distance beyond `f32`).
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    #[inline(always)]
    fn lanes(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
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
    fn lanes_scalar(&self, r: &TriRay, tmax: f32) -> ([f32; 8], u32, u32) {
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

/// A ray's closest hit on a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshHit {
    /// Distance along the ray.
    pub t: f32,
    /// Triangle index.
    pub id: u32,
    /// The triangle's corners, from the block the traversal just read: the surface point is
    /// made without a second look at the mesh (its index and position buffers are cache misses
    /// on a large mesh), unless the mesh has vertex normals or texture coordinates.
    pub p: [Vec3A; 3],
}

impl MeshHit {
    /// Geometric normal (not normalised) `(p1 - p0) x (p2 - p0)`.
    pub fn ng(&self) -> Vec3A {
        let [p0, p1, p2] = self.p;
        (p1 - p0).cross(p2 - p0)
    }
}

/// A mesh's bottom-level BVH.
#[derive(Debug, Default)]
pub struct MeshBlas {
    /// The mesh.
    pub mesh: Arc<MeshData>,
    bvh: Bvh8,
    blocks: Vec<TriBlock>,
}

impl MeshBlas {
    /// Builds the BVH of `mesh` (triangles without area are left out).
    pub fn build(mesh: Arc<MeshData>) -> Self {
        let _span = tracing::info_span!("build_blas", triangles = mesh.triangles.len()).entered();
        let ids: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&i| {
                let [a, b, c] = mesh.triangle(i);
                Triangle::new(a, b, c).is_some()
            })
            .collect();
        let aabbs: Vec<Aabb> = ids
            .iter()
            .map(|&i| {
                let [a, b, c] = mesh.triangle(i);
                Aabb { min: a.min(b).min(c), max: a.max(b).max(c) }
            })
            .collect();
        let mut blocks = Vec::with_capacity(ids.len() / 4);
        // Leaves of up to three blocks: the bottom level of small nodes becomes leaves, which
        // on the 1M-triangle knot cuts nodes from 53k to 21k and bytes per triangle from 68 to
        // 53, and traces bounce rays 7% faster than one-block leaves (benches/RESULTS.md).
        let bvh = Bvh8::build(&aabbs, 24, |prims| {
            let first = blocks.len() as u32;
            for chunk in prims.chunks(8) {
                let mut b = TriBlock { v: [[[f32::NAN; 8]; 3]; 3], id: [u32::MAX; 8] };
                for (l, &p) in chunk.iter().enumerate() {
                    let id = ids[p as usize];
                    for (j, v) in mesh.triangle(id).iter().enumerate() {
                        for a in 0..3 {
                            b.v[j][a][l] = v[a];
                        }
                    }
                    b.id[l] = id;
                }
                blocks.push(b);
            }
            (first, blocks.len() as u32 - first)
        });
        Self { mesh, bvh, blocks }
    }

    /// Bounds in object space.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds
    }

    /// Checks the BLAS's invariants ([`Bvh8::validate`], each leaf's box around its blocks'
    /// triangles).
    pub fn validate(&self) -> Result<(), String> {
        self.bvh.validate(|first, count| {
            let blocks = &self.blocks[first as usize..(first + count) as usize];
            let corners = blocks.iter().flat_map(|b| {
                (0..8).filter(move |&l| b.id[l] != u32::MAX).flat_map(move |l| {
                    (0..3).map(move |j| Vec3A::new(b.v[j][0][l], b.v[j][1][l], b.v[j][2][l]))
                })
            });
            corners.fold(Aabb::empty(), |a, p| Aabb { min: a.min.min(p), max: a.max.max(p) })
        })
    }

    /// Bytes held by the BVH and the triangle blocks (not the mesh itself).
    pub fn bytes(&self) -> usize {
        self.bvh.node_bytes() + self.blocks.len() * size_of::<TriBlock>()
    }

    /// Closest hit with `t` in `(0, tmax)`, in object space.
    #[inline]
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<MeshHit> {
        let r = TriRay::new(o, d);
        let (mut block, mut lane) = (u32::MAX, 0);
        let t = self.bvh.closest_prefetching(
            o,
            d,
            tmax,
            |first, count, best| {
                let mut best = best;
                for bi in first..first + count {
                    let (ts, mut hit) = self.blocks[bi as usize].intersect(&r, o, d, best);
                    while hit != 0 {
                        let l = hit.trailing_zeros() as usize;
                        hit &= hit - 1;
                        if ts[l] < best {
                            (best, block, lane) = (ts[l], bi, l);
                        }
                    }
                }
                best
            },
            |first, count| self.prefetch(first, count),
        );
        (block != u32::MAX).then(|| {
            let b = &self.blocks[block as usize];
            let p = [0, 1, 2].map(|j| Vec3A::new(b.v[j][0][lane], b.v[j][1][lane], b.v[j][2][lane]));
            MeshHit { t, id: b.id[lane], p }
        })
    }

    /// Which of [`PACKET`] rays in object space meet a triangle with `t` in `(0, tmax[l])`,
    /// traced together ([`Bvh8::any_packet`]), as a bit mask: [`Self::occluded`]'s answers. A
    /// negative `tmax` leaves the ray out.
    #[inline(always)]
    pub fn occluded_packet(
        &self,
        o: &[[f32; PACKET]; 3],
        d: &[[f32; PACKET]; 3],
        tmax: &[f32; PACKET],
    ) -> u32 {
        let ray = |l: usize| (Vec3A::new(o[0][l], o[1][l], o[2][l]), Vec3A::new(d[0][l], d[1][l], d[2][l]));
        self.bvh.any_packet(o, d, tmax, |first, count, active| {
            let (mut m, mut hits) = (active, 0);
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let (ol, dl) = ray(l);
                let r = TriRay::new(ol, dl);
                let blocks = &self.blocks[first as usize..(first + count) as usize];
                if blocks.iter().any(|b| b.intersect(&r, ol, dl, tmax[l]).1 != 0) {
                    hits |= 1 << l;
                }
            }
            hits
        })
    }

    /// True when some triangle lies on the ray with `t` in `(0, tmax)`.
    #[inline]
    pub fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        let r = TriRay::new(o, d);
        self.bvh.any_prefetching(
            o,
            d,
            tmax,
            |first, count| {
                self.blocks[first as usize..(first + count) as usize]
                    .iter()
                    .any(|b| b.intersect(&r, o, d, tmax).1 != 0)
            },
            |first, count| self.prefetch(first, count),
        )
    }

    /// Asks for the cache lines of the first of the blocks `first..first + count`, as soon as
    /// the traversal finds that a ray enters their leaf: mesh.ron's closest hits 9% and shadow
    /// rays 7% faster; all of a leaf's blocks (up to 15 lines) gained less (benches/RESULTS.md).
    #[inline(always)]
    fn prefetch(&self, first: u32, _count: u32) {
        let p = self.blocks.as_ptr().wrapping_add(first as usize).cast::<i8>();
        #[cfg(target_arch = "x86_64")]
        for line in 0..5 {
            // SAFETY: a prefetch is only a hint; it does not fault on any address.
            unsafe {
                std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                    p.wrapping_add(64 * line),
                )
            };
        }
    }

    /// Appends the `t` of every hit of the ray `o + t d`, `t > 0` (unsorted).
    pub fn all_hits(&self, o: Vec3A, d: Vec3A, out: &mut Vec<f32>) {
        let r = TriRay::new(o, d);
        self.bvh.any(o, d, f32::INFINITY, |first, count| {
            for b in &self.blocks[first as usize..(first + count) as usize] {
                let (ts, hit) = b.intersect(&r, o, d, f32::INFINITY);
                out.extend((0..8).filter(|l| hit & 1 << l != 0).map(|l| ts[l]));
            }
            false
        });
    }

    /// Surface data on the triangle of `hit` at the object-space point `p`, and the height over the
    /// triangle (along `sp.n`) of the smooth surface that its vertex normals describe
    /// ([`terminator_lift`]; 0 without them). With vertex normals the shading normal
    /// interpolates them (and the geometric normal turns to its side); with vertex uvs, uv
    /// interpolates them. `on` names the triangle and the weights (the mesh is the caller's).
    #[inline]
    pub fn surface(&self, hit: &MeshHit, p: Vec3A) -> (SurfacePoint, f32) {
        let [a, b, c] = hit.p;
        let mut sp = Triangle { p: [a, b, c], uv: None }.surface(p);
        // The triangle's uv are its barycentric weights.
        sp.on = MeshPoint { mesh: u32::MAX, triangle: hit.id, b: sp.uv, instance: u32::MAX };
        if self.mesh.normals.is_none() && self.mesh.uvs.is_none() {
            return (sp, 0.0);
        }
        let (b1, b2) = (sp.uv.x, sp.uv.y);
        let b0 = 1.0 - b1 - b2;
        let [i, j, k] = self.mesh.triangles[hit.id as usize].map(|v| v as usize);
        let mut lift = 0.0;
        if let Some(n) = &self.mesh.normals
            && let Some(ns) = unit(b0 * n[i] + b1 * n[j] + b2 * n[k])
        {
            (sp.ns, sp.ns_base) = (ns, ns);
            if sp.n.dot(sp.ns) < 0.0 {
                sp.n = -sp.n;
            }
            lift = terminator_lift(sp.p, sp.n, [a, b, c], [n[i], n[j], n[k]], [b0, b1, b2]);
        }
        if let Some(uv) = &self.mesh.uvs {
            sp.uv = b0 * uv[i] + b1 * uv[j] + b2 * uv[k];
        }
        (sp, lift)
    }
}

/// The shadow-terminator offset of Hanika ("Hacking the Shadow Terminator", Ray Tracing Gems
/// II, chapter 4, 2021): how far above the point `x` of a smooth-shaded triangle (corners `p`,
/// unit normal `n`, vertex normals `vn`, barycentric weights `b`) rays should start.
///
/// A coarse mesh lies inside the smooth surface its vertex normals describe, so a ray that
/// leaves the flat triangle towards a light above the shading normal's horizon runs into the
/// triangle itself or its neighbours where the smooth surface would see the light: the dark
/// steps of the terminator. Hanika moves the ray origin to a point of a surface like Phong
/// tessellation's: `p' = sum_i b_i (x - min(0, (x - p_i) . n_i) n_i)`, `x` projected onto each
/// vertex's tangent plane where it lies below it (convex parts; concave ones are not moved),
/// blended by the barycentric weights. It meets the tangent planes at the vertices, is
/// continuous across edges and lies about the mesh's sagitta above the facets. Only its height
/// over the triangle, `(p' - x) . n` (at least 0), is returned: the instance's surface point
/// (in world space) moves by half of it along `n` and its error bound grows by as much, so
/// that [`crate::math::offset_ray_origin`] starts rays that leave on `n`'s side at this height
/// and the others exactly where they started without it (below the triangle and not above a
/// neighbour: a refracted ray enters once). The integrators need no second point. What it
/// trades, as Hanika's method does: rays on `n`'s side start up to the mesh's sagitta off the
/// facet, so an occluder closer to it than that is missed.
#[inline]
pub fn terminator_lift(x: Vec3A, n: Vec3A, p: [Vec3A; 3], vn: [Vec3A; 3], b: [f32; 3]) -> f32 {
    let mut d = Vec3A::ZERO;
    for i in 0..3 {
        let ni = vn[i].normalize_or_zero();
        d -= b[i] * (x - p[i]).dot(ni).min(0.0) * ni;
    }
    let h = d.dot(n);
    if h > 0.0 && h.is_finite() { h } else { 0.0 }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

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
