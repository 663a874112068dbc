//! A mesh's bottom-level BVH: an [`Bvh8`] whose leaves are blocks of up to eight triangles
//! ([`TriBlock`]), its closest-hit, occlusion and packet queries, and the surface point of a hit.

#![cfg_attr(target_arch = "x86_64", expect(unsafe_code, reason = "prefetches of the next leaf's blocks"))]

use super::MeshData;
use super::block::{TriBlock, TriRay};
use crate::accel::bvh8::{Bvh8, PACKET};
use crate::math::unit;
use crate::shape::{MeshPoint, SurfacePoint, Triangle};
use glam::Vec3A;
use obvhs::aabb::Aabb;
use std::sync::Arc;

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
    pub(super) blocks: Vec<TriBlock>,
    /// The mesh's vertex normals shade it ([`smooth_normals`]): false without them, and where
    /// every triangle's three equal its own normal (a flat-shaded mesh, as exporters write
    /// boxes and walls), so that its hits skip the interpolation and the terminator's lift.
    smooth: bool,
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
        let smooth = smooth_normals(&mesh);
        Self { mesh, bvh, blocks, smooth }
    }

    /// The BVH of triangles given by their corners, without a mesh: a hit's `id` is the
    /// triangle's index in `triangles` (those without area are left out), and
    /// [`Self::surface`] is not for it (the caller's meshes hold the surfaces).
    pub fn over_triangles(triangles: &[[Vec3A; 3]]) -> Self {
        let mesh = MeshData {
            positions: triangles.iter().flatten().copied().collect(),
            triangles: (0..triangles.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
            ..MeshData::default()
        };
        // The blocks hold the corners: the mesh is not kept.
        Self { mesh: Arc::default(), ..Self::build(Arc::new(mesh)) }
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
        if !self.smooth && self.mesh.uvs.is_none() {
            return (sp, 0.0);
        }
        let (b1, b2) = (sp.uv.x, sp.uv.y);
        let b0 = 1.0 - b1 - b2;
        let [i, j, k] = self.mesh.triangles[hit.id as usize].map(|v| v as usize);
        let mut lift = 0.0;
        if self.smooth
            && let Some(n) = &self.mesh.normals
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

/// Whether `mesh`'s vertex normals shade it differently from its triangles' own normals: some
/// triangle (with area) has a vertex normal more than about 0.1 degree from its geometric
/// normal, or on its other side. Where none has, the shading normal they give is the geometric
/// one to within 1e-6, and the terminator's lift is 0 to within rounding: the mesh is shaded
/// flat, as one without normals.
fn smooth_normals(mesh: &MeshData) -> bool {
    let Some(normals) = &mesh.normals else { return false };
    const FLAT: f32 = 1.0 - 1e-6;
    mesh.triangles.iter().enumerate().any(|(i, t)| {
        let [a, b, c] = mesh.triangle(i as u32);
        let Some(ng) = unit((b - a).cross(c - a)) else { return false };
        t.iter().any(|&v| !(normals[v as usize].normalize_or_zero().dot(ng) >= FLAT))
    })
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
mod tests {
    use super::*;

    /// A unit square in z = 0 (two triangles, counter-clockwise seen from +z) with the given
    /// vertex normals and uvs.
    fn square(normals: Option<Vec<Vec3A>>) -> MeshData {
        MeshData {
            positions: vec![Vec3A::ZERO, Vec3A::X, Vec3A::new(1.0, 1.0, 0.0), Vec3A::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals,
            uvs: Some(vec![glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::ONE, glam::Vec2::Y]),
            ..MeshData::default()
        }
    }

    /// Vertex normals that equal the faces' own shade nothing: the mesh is shaded flat, with the
    /// bits of the same mesh without normals; a normal tilted by a degree, or one on the other
    /// side, still shades it (and turns the geometric normal to its side).
    #[test]
    fn flat_vertex_normals_shade_as_none() {
        let up = vec![Vec3A::Z; 4];
        let tilted = vec![Vec3A::Z, Vec3A::new(0.0175, 0.0, 1.0), Vec3A::Z, Vec3A::Z];
        let down = vec![Vec3A::NEG_Z; 4];
        let [bare, flat, tilted, down] =
            [None, Some(up), Some(tilted), Some(down)].map(|n| MeshBlas::build(Arc::new(square(n))));
        assert!(!bare.smooth && !flat.smooth && tilted.smooth && down.smooth);
        let (o, d) = (Vec3A::new(0.7, 0.2, 1.0), Vec3A::NEG_Z);
        let hit = bare.intersect(o, d, f32::INFINITY).expect("the ray meets the square");
        let p = o + hit.t * d;
        let (a, b) = (bare.surface(&hit, p), flat.surface(&hit, p));
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
        assert_eq!(a.0.ns, Vec3A::Z);
        let (t, lift) = tilted.surface(&hit, p);
        assert!(t.ns != t.n && t.ns.x > 0.0 && lift >= 0.0, "{t:?}");
        assert_eq!(down.surface(&hit, p).0.n, Vec3A::NEG_Z);
    }
}
