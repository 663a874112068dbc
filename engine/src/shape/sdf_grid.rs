//! SdfGrid: Mitsuba 3's `sdfgrid` shape (`src/shapes/sdfgrid.cpp`), the zero set of signed
//! distances given on a grid of `nx x ny x nz` points spanning `[0, 1]^3` of object space,
//! interpolated trilinearly in each voxel between them.
//!
//! The grid comes from a file in Mitsuba's grid-volume format (`src/render/volumegrid.cpp`:
//! `VOL`, version 3, float32 data, sizes, one channel, a bounding box that Mitsuba ignores
//! here, then the values with x varying fastest). Every voxel whose corners do not all share
//! one strict sign becomes a primitive ([`SdfVoxel`]) of its own in the BVH, as in Mitsuba.
//! A ray meets a voxel where the trilinear interpolant along it, a cubic, first reaches zero
//! between the ray's entry into the voxel and its exit (Hansson-Söderlund, Evans and
//! Akenine-Möller, "Ray Tracing of Signed Distance Function Grids", JCGT 11(3), 2022): the
//! interval is cut where the cubic's derivative vanishes (Marmitt et al., "Fast and Accurate
//! Ray-Voxel Intersection Techniques for Iso-Surface Ray Tracing", VMV 2004) and the first
//! piece whose ends differ in sign holds the root, found by bisection and Newton steps.
//!
//! Normals are Mitsuba's. The geometric normal is the gradient of the voxel's interpolant.
//! The shading normal is the geometric one (`normals: Analytic`) or, by default (`Smooth`),
//! the JCGT paper's: the normalised gradients of the eight voxels around the grid point
//! nearest the hit, each taken at the hit's coordinates as Mitsuba's `voxel_grad` takes them
//! (differences of the grid's interpolant across the voxel's faces, clamped at the grid's
//! border), blended trilinearly; a voxel beyond the grid's low faces counts as a zero normal.
//! Each of those gradients' x component reads only the grid's values on four x lines at the
//! hit's (y, z) cell, so a voxel keeps its 8 corners and the 24 values of the layers beside
//! its six faces. The surface has no texture coordinates (Mitsuba gives uv (0, 0)) and emits
//! nothing (Mitsuba's cannot be an area emitter either): a scene is refused where it would.

use super::{LightSample, MeshPoint, Primitive, PrimitiveShape, ShapeError, ShapeModel, SurfacePoint};
use crate::format::context;
use crate::math::gamma;
use glam::{Affine3A, Vec2, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use serde::{Deserialize, Deserializer, de::Error};
use std::path::PathBuf;
use std::sync::Arc;

/// Signed distances at the points of a grid over `[0, 1]^3`, x varying fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGridData {
    /// Points along x, y and z (each at least 2).
    pub size: [usize; 3],
    /// The values, `size[0] * size[1] * size[2]` of them.
    pub values: Vec<f32>,
}

/// The most points along one axis.
const MAX_SIDE: usize = 1 << 16;

impl SdfGridData {
    /// Reads Mitsuba's grid-volume format ([`crate::format::vol`]): one channel, at least 2 and
    /// at most [`MAX_SIDE`] points along each axis; `path` names the file in errors.
    pub fn parse_vol(bytes: &[u8], path: &std::path::Path) -> Result<Self, String> {
        let what = "SDF grid";
        let h = crate::format::vol::VolHeader::parse(bytes, path, what)?;
        let fail = |why: String| format!("the {what} {}: {why}", path.display());
        if h.channels != 1 {
            return Err(fail(format!("{} channels: an SDF grid has one", h.channels)));
        }
        let [x, y, z] = h.size;
        if h.size.iter().any(|&s| !(2..=MAX_SIDE).contains(&s)) {
            return Err(fail(format!("size {x} x {y} x {z}: 2 to {MAX_SIDE} points along each axis")));
        }
        Ok(Self { size: h.size, values: h.values(bytes, path, what)? })
    }

    /// The value at grid point `(x, y, z)`, each index clamped to the grid (Mitsuba's texture
    /// lookups clamp).
    fn at(&self, x: i64, y: i64, z: i64) -> f32 {
        let c = |i: i64, n: usize| i.clamp(0, n as i64 - 1) as usize;
        let (x, y, z) = (c(x, self.size[0]), c(y, self.size[1]), c(z, self.size[2]));
        self.values[x + self.size[0] * (y + self.size[1] * z)]
    }

    /// The voxel at `v` (its low corner) holds some surface: its corners are not all of one
    /// strict sign (Mitsuba's test).
    fn occupied(&self, v: [i64; 3]) -> bool {
        let f = corners(|x, y, z| self.at(v[0] + x, v[1] + y, v[2] + z));
        !(f.iter().all(|&s| s > 0.0) || f.iter().all(|&s| s < 0.0))
    }
}

/// The eight values `f(x, y, z)` for x, y, z in {0, 1}, at index `x + 2 y + 4 z`.
fn corners(f: impl Fn(i64, i64, i64) -> f32) -> [f32; 8] {
    std::array::from_fn(|i| f((i & 1) as i64, ((i >> 1) & 1) as i64, ((i >> 2) & 1) as i64))
}

/// An SDF grid file as `SdfGrid(file: ..)` names it (relative to the scene file), read in the
/// second parsing pass.
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGridFile {
    /// The path as written.
    pub path: PathBuf,
    /// The grid (`None` in the first pass, which reads no files).
    pub grid: Option<Arc<SdfGridData>>,
}

impl<'de> Deserialize<'de> for SdfGridFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let path = PathBuf::from(String::deserialize(d)?);
        let Some(dir) = context::scene_dir() else {
            return Ok(SdfGridFile { path, grid: None });
        };
        let full = dir.join(&path);
        let bytes =
            crate::format::files::read_bounded(&full, crate::format::files::MAX_ASSET_BYTES, "SDF grid")
                .map_err(D::Error::custom)?;
        let grid = SdfGridData::parse_vol(&bytes, &full).map_err(D::Error::custom)?;
        Ok(SdfGridFile { path, grid: Some(Arc::new(grid)) })
    }
}

/// Which shading normal an SDF grid has (Mitsuba's `normals`).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SdfNormals {
    /// The blend of the neighbouring voxels' gradients (Mitsuba's `smooth`, its default).
    #[default]
    Smooth,
    /// The geometric normal (Mitsuba's `analytic`).
    Analytic,
}

/// The zero set of the signed distances in `file` (Mitsuba's grid-volume `.vol`: version 3,
/// float32, one channel, at least 2 points per axis), a grid spanning [0, 1]^3 interpolated
/// trilinearly in each voxel: Mitsuba's `sdfgrid`. Each voxel with a surface is a primitive of the
/// BVH; a ray meets it at the first zero of the interpolant's cubic along it. `normals: Smooth`
/// (default) shades with Mitsuba's blend of the eight neighbouring voxels' gradients
/// (Hansson-Söderlund et al. 2022), `Analytic` with the voxel's gradient. No uv (Mitsuba's (0, 0));
/// any invertible transform; it does not emit (refused, as in Mitsuba).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub struct SdfGridDesc {
    /// The grid file (Mitsuba's `.vol` format, one channel), spanning `[0, 1]^3`.
    pub file: SdfGridFile,
    /// The shading normal (default `Smooth`).
    #[serde(default)]
    pub normals: SdfNormals,
}

/// An SDF grid in its own space, as a scene places it.
#[derive(Debug, Clone, PartialEq)]
pub struct SdfGridShape {
    /// The grid file.
    pub file: SdfGridFile,
    /// The shading normal.
    pub normals: SdfNormals,
}

impl ShapeModel for SdfGridShape {
    type Desc = SdfGridDesc;

    fn build(d: SdfGridDesc) -> Result<Self, String> {
        if let Some(grid) = &d.file.grid {
            let [nx, ny, nz] = grid.size.map(|n| n as i64 - 1);
            let any = (0..nz).any(|z| (0..ny).any(|y| (0..nx).any(|x| grid.occupied([x, y, z]))));
            if !any {
                return Err(format!(
                    "the SDF grid {} has no surface: no voxel has corners of both signs (or a zero)",
                    d.file.path.display()
                ));
            }
        }
        Ok(Self { file: d.file, normals: d.normals })
    }

    /// Every occupied voxel, placed by `m` (any invertible affine map).
    fn place(&self, m: &Affine3A, out: &mut Vec<Primitive>) -> Result<(), ShapeError> {
        let Some(grid) = &self.file.grid else {
            return Ok(());
        };
        let det = m.matrix3.determinant();
        if !(det.abs() > 0.0) || !det.is_finite() || !m.translation.is_finite() {
            return Err(ShapeError::Flattened);
        }
        let object_from_world = m.inverse();
        if !object_from_world.matrix3.is_finite() || !object_from_world.translation.is_finite() {
            return Err(ShapeError::Flattened);
        }
        let [nx, ny, nz] = grid.size.map(|n| n as i64 - 1);
        let cells = Vec3::new(nx as f32, ny as f32, nz as f32);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    if grid.occupied([x, y, z]) {
                        let v = SdfVoxel::new(grid, [x, y, z], cells, m, &object_from_world, self.normals);
                        out.push(Primitive::SdfVoxel(v));
                    }
                }
            }
        }
        Ok(())
    }
}

/// One occupied voxel of a placed SDF grid, in its own coordinates `[0, 1]^3` (its low corner
/// at 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfVoxel {
    /// World to the voxel's coordinates.
    local_from_world: Affine3A,
    /// The values at its corners (`x + 2 y + 4 z`, [`corners`]) and, four each, on the grid
    /// lines beside its faces: x = -1, x = 2 (index `y + 2 z`), y = -1, y = 2 (`x + 2 z`),
    /// z = -1, z = 2 (`x + 2 y`), clamped to the grid.
    values: [f32; 32],
    /// Voxels per unit of object space along each axis (points - 1): object-space gradients
    /// are the voxel's times these (16 bits keep a voxel within the size of a [`Primitive`]).
    cells: [u16; 3],
    /// Bit k: the voxel lies on the grid's low face along axis k (the voxels beyond count as
    /// zero normals in the smooth blend).
    low: u8,
    /// Smooth shading normals.
    smooth: bool,
    /// Bound on the error of a hit point's coordinates.
    err: f32,
}

impl SdfVoxel {
    fn new(
        grid: &SdfGridData,
        v: [i64; 3],
        cells: Vec3,
        world_from_object: &Affine3A,
        object_from_world: &Affine3A,
        normals: SdfNormals,
    ) -> Self {
        let at = |x: i64, y: i64, z: i64| grid.at(v[0] + x, v[1] + y, v[2] + z);
        let mut values = [0.0; 32];
        values[..8].copy_from_slice(&corners(at));
        for (k, side) in [-1i64, 2].into_iter().enumerate() {
            for i in 0..4i64 {
                let (a, b) = (i & 1, i >> 1);
                values[8 + 4 * k + i as usize] = at(side, a, b);
                values[16 + 4 * k + i as usize] = at(a, side, b);
                values[24 + 4 * k + i as usize] = at(a, b, side);
            }
        }
        // World to object, object to the grid's coordinates (x (points - 1)), to the voxel's.
        let offset = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        let local_from_object = Affine3A::from_translation(-offset) * Affine3A::from_scale(cells);
        let local_from_world = local_from_object * *object_from_world;
        // The world size of the voxel and its distance from the origin bound the error of a
        // hit: the root's tolerance below and the rounding of the transforms.
        let world_from_local = *world_from_object * local_from_object.inverse();
        let c = [
            world_from_local.matrix3.x_axis,
            world_from_local.matrix3.y_axis,
            world_from_local.matrix3.z_axis,
        ];
        let size = (c[0].abs() + c[1].abs() + c[2].abs()).max_element();
        let reach = world_from_local.translation.abs().max_element() + size;
        let low = (0..3).filter(|&k| v[k] == 0).fold(0u8, |b, k| b | 1 << k);
        Self {
            local_from_world,
            values,
            cells: cells.to_array().map(|c| c as u16),
            low,
            smooth: normals == SdfNormals::Smooth,
            err: 1e-4 * size + gamma(16) * reach,
        }
    }

    /// The voxel's interpolant at the voxel point `p`.
    #[inline]
    fn f(&self, p: Vec3A) -> f32 {
        let s = &self.values;
        let (x, y, z) = (p.x, p.y, p.z);
        let x00 = s[0] + x * (s[1] - s[0]);
        let x10 = s[2] + x * (s[3] - s[2]);
        let x01 = s[4] + x * (s[5] - s[4]);
        let x11 = s[6] + x * (s[7] - s[6]);
        let y0 = x00 + y * (x10 - x00);
        let y1 = x01 + y * (x11 - x01);
        y0 + z * (y1 - y0)
    }

    /// The bilinear interpolant at `(a, b)` of four values at index `i + 2 j` of `(i, j)`.
    #[inline]
    fn bilinear(v: [f32; 4], a: f32, b: f32) -> f32 {
        let l0 = v[0] + a * (v[1] - v[0]);
        let l1 = v[2] + a * (v[3] - v[2]);
        l0 + b * (l1 - l0)
    }

    /// The four values on the grid line at voxel offset `line` (-1 to 2) along `axis`, indexed
    /// by the other two axes in order.
    #[inline]
    fn line(&self, axis: usize, line: i32) -> [f32; 4] {
        let s = &self.values;
        let corner = |i: usize, j: usize| {
            let bit = line as usize;
            match axis {
                0 => s[bit + 2 * i + 4 * j],
                1 => s[i + 2 * bit + 4 * j],
                _ => s[i + 2 * j + 4 * bit],
            }
        };
        match line {
            -1 => std::array::from_fn(|i| s[8 + 8 * axis + i]),
            2 => std::array::from_fn(|i| s[12 + 8 * axis + i]),
            _ => [corner(0, 0), corner(1, 0), corner(0, 1), corner(1, 1)],
        }
    }

    /// Mitsuba's `voxel_grad` along `axis` for the voxel `offset` (-1, 0 or 1) voxels away on
    /// that axis, at the voxel point `p`: the grid's interpolant on its far face minus on its
    /// near face, in voxel units.
    #[inline]
    fn gradient(&self, axis: usize, offset: i32, p: Vec3A) -> f32 {
        let (a, b) = match axis {
            0 => (p.y, p.z),
            1 => (p.x, p.z),
            _ => (p.x, p.y),
        };
        Self::bilinear(self.line(axis, offset + 1), a, b) - Self::bilinear(self.line(axis, offset), a, b)
    }

    /// A voxel-space gradient `g` as a unit world-space normal.
    #[inline]
    fn world_normal(&self, g: Vec3A) -> Vec3A {
        (self.local_from_world.matrix3.transpose() * g).normalize()
    }

    /// The smooth normal at the voxel point `p` (in object units, not normalised), after
    /// Mitsuba's `smooth_sh`.
    fn smooth_normal(&self, p: Vec3A) -> Vec3A {
        // Per axis: the grid point nearest p is at voxel offset h (0 or 1); the voxels
        // blended lie at offsets h - 1 and h, with weight w on the second.
        let mut g = [[0.0f32; 2]; 3];
        let mut w = [0.0f32; 3];
        let mut valid = [[true; 2]; 3];
        for k in 0..3 {
            let h = (p[k] >= 0.5) as i32;
            for (j, o) in [h - 1, h].into_iter().enumerate() {
                g[k][j] = self.gradient(k, o, p) * self.cells[k] as f32;
            }
            valid[k][0] = !(h == 0 && self.low & (1 << k) != 0);
            // Beyond the grid's low face the blend leans on the voxels inside.
            w[k] = if valid[k][0] { p[k] - h as f32 + 0.5 } else { 1.0 };
        }
        let mut n = Vec3A::ZERO;
        for i in 0..8 {
            let j = [i & 1, (i >> 1) & 1, (i >> 2) & 1];
            if (0..3).any(|k| !valid[k][j[k]]) {
                continue;
            }
            let weight = (0..3).map(|k| if j[k] == 1 { w[k] } else { 1.0 - w[k] }).product::<f32>();
            let nk = Vec3A::new(g[0][j[0]], g[1][j[1]], g[2][j[2]]).normalize_or_zero();
            n += weight * nk;
        }
        n
    }
}

/// The roots of `a t^2 + b t + c` in increasing order (NaN where there are none).
#[inline]
fn quadratic(a: f32, b: f32, c: f32) -> (f32, f32) {
    if a == 0.0 {
        let t = if b != 0.0 { -c / b } else { f32::NAN };
        return (t, f32::NAN);
    }
    let disc = b * b - 4.0 * a * c;
    if !(disc >= 0.0) {
        return (f32::NAN, f32::NAN);
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, if q != 0.0 { c / q } else { q / a });
    (t0.min(t1), t0.max(t1))
}

impl PrimitiveShape for SdfVoxel {
    fn aabb(&self) -> Aabb {
        let m = self.local_from_world.inverse();
        let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for i in 0..8 {
            let c = Vec3A::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
            let p = m.transform_point3a(c);
            (min, max) = (min.min(p), max.max(p));
        }
        Aabb { min: min - self.err, max: max + self.err }
    }

    /// The first zero of the interpolant along the ray inside the voxel.
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
        let lo = self.local_from_world.transform_point3a(o);
        let ld = self.local_from_world.transform_vector3a(d);
        // Where the ray is inside [0, 1]^3 (an axis it runs along bounds nothing unless it lies
        // outside the slab).
        let (mut t0, mut t1) = (0.0f32, tmax);
        for k in 0..3 {
            if ld[k] == 0.0 {
                if !(0.0..=1.0).contains(&lo[k]) {
                    return f32::INFINITY;
                }
                continue;
            }
            let (a, b) = (-lo[k] / ld[k], (1.0 - lo[k]) / ld[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        if !(t0 <= t1) {
            return f32::INFINITY;
        }
        // The interpolant along the ray from its entry q: c3 s^3 + c2 s^2 + c1 s + c0.
        let q = lo + t0 * ld;
        let s = &self.values;
        let a1 = s[1] - s[0];
        let a2 = s[2] - s[0];
        let a3 = s[4] - s[0];
        let a4 = s[3] - s[1] - s[2] + s[0];
        let a5 = s[5] - s[1] - s[4] + s[0];
        let a6 = s[6] - s[2] - s[4] + s[0];
        let a7 = s[7] - s[3] - s[5] - s[6] + s[1] + s[2] + s[4] - s[0];
        let (dx, dy, dz) = (ld.x, ld.y, ld.z);
        let (qx, qy, qz) = (q.x, q.y, q.z);
        let c3 = a7 * dx * dy * dz;
        let c2 =
            a4 * dx * dy + a5 * dx * dz + a6 * dy * dz + a7 * (qx * dy * dz + qy * dx * dz + qz * dx * dy);
        let c1 = a1 * dx
            + a2 * dy
            + a3 * dz
            + a4 * (qx * dy + qy * dx)
            + a5 * (qx * dz + qz * dx)
            + a6 * (qy * dz + qz * dy)
            + a7 * (qx * qy * dz + qx * qz * dy + qy * qz * dx);
        let c0 = self.f(q);
        let f = |t: f32| ((c3 * t + c2) * t + c1) * t + c0;
        let df = |t: f32| (3.0 * c3 * t + 2.0 * c2) * t + c1;
        // The monotonic pieces of [0, span] between the derivative's roots: the first whose
        // ends differ in sign (or meet zero) holds the first root.
        let span = t1 - t0;
        let (r0, r1) = quadratic(3.0 * c3, 2.0 * c2, c1);
        let mut cuts = [0.0, span, span, span];
        let mut n = 1;
        for r in [r0, r1] {
            if r > 0.0 && r < span {
                cuts[n] = r;
                n += 1;
            }
        }
        cuts[n] = span;
        let mut fa = f(0.0);
        for i in 0..n {
            let (mut a, mut b) = (cuts[i], cuts[i + 1]);
            let fb = f(b);
            if fa * fb > 0.0 {
                fa = fb;
                continue;
            }
            // Bisection, with a Newton step wherever it stays inside the bracket.
            let up = fa < fb;
            let mut t = if fa == fb { a } else { a + (b - a) * (fa / (fa - fb)) };
            for _ in 0..64 {
                if !(t > a && t < b) {
                    t = 0.5 * (a + b);
                }
                let ft = f(t);
                if ft == 0.0 {
                    break;
                }
                if (ft < 0.0) == up {
                    a = t;
                } else {
                    b = t;
                }
                if b - a <= 4.0 * f32::EPSILON * (t0 + b) {
                    break;
                }
                let slope = df(t);
                t = if slope != 0.0 { t - ft / slope } else { 0.5 * (a + b) };
            }
            let t = (t0 + t.clamp(a, b)).min(t1);
            return if t > 0.0 && t < tmax { t } else { f32::INFINITY };
        }
        f32::INFINITY
    }

    /// The normals at `p` (a point found by [`Self::intersect`]); uv (0, 1), Mitsuba's (0, 0).
    fn surface(&self, p: Vec3A, _uv: bool) -> SurfacePoint {
        let l = self.local_from_world.transform_point3a(p).clamp(Vec3A::ZERO, Vec3A::ONE);
        let g = Vec3A::new(self.gradient(0, 0, l), self.gradient(1, 0, l), self.gradient(2, 0, l));
        let n = self.world_normal(g);
        // A gradient of zero (a flat spot of the interpolant) leaves no normal: +z then.
        let n = if n.is_finite() { n } else { Vec3A::Z };
        let ns = match self.smooth {
            true => {
                let cells = Vec3A::from_array(self.cells.map(f32::from));
                let s = self.world_normal(self.smooth_normal(l) / cells);
                if s.is_finite() { s } else { n }
            }
            false => n,
        };
        SurfacePoint { p, n, ns, ns_base: ns, uv: Vec2::new(0.0, 1.0), err: self.err, on: MeshPoint::NONE }
    }

    /// No area: an SDF grid does not emit (scenes are refused where it would).
    fn area(&self) -> f32 {
        0.0
    }

    fn sample_solid_angle(&self, from: Vec3A, _u: Vec2) -> LightSample {
        LightSample { p: from, n: Vec3A::Z, pdf: 0.0, err: 0.0 }
    }

    fn pdf_solid_angle(&self, _from: Vec3A, _p: Vec3A, _n: Vec3A) -> f32 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `.vol` file of `size` points with values `f(x, y, z)` (object coordinates in [0, 1]).
    fn vol(size: [i32; 3], f: impl Fn(Vec3) -> f32) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, size[0], size[1], size[2], 1] {
            b.extend(v.to_le_bytes());
        }
        b.extend([0.0f32; 6].iter().flat_map(|v| v.to_le_bytes()));
        let c = |i: i32, n: i32| i as f32 / (n - 1) as f32;
        for z in 0..size[2] {
            for y in 0..size[1] {
                for x in 0..size[0] {
                    b.extend(f(Vec3::new(c(x, size[0]), c(y, size[1]), c(z, size[2]))).to_le_bytes());
                }
            }
        }
        b
    }

    /// The ball of radius 0.3 about the grid's centre, placed by `m`, as primitives.
    fn ball(n: i32, m: Affine3A, normals: SdfNormals) -> Vec<Primitive> {
        let bytes = vol([n, n + 2, n + 1], |p| (p - Vec3::splat(0.5)).length() - 0.3);
        let grid = SdfGridData::parse_vol(&bytes, std::path::Path::new("ball.vol")).unwrap();
        let file = SdfGridFile { path: "ball.vol".into(), grid: Some(Arc::new(grid)) };
        let shape = SdfGridShape::build(SdfGridDesc { file, normals }).unwrap();
        let mut out = Vec::new();
        shape.place(&m, &mut out).unwrap();
        out
    }

    fn closest(prims: &[Primitive], o: Vec3A, d: Vec3A) -> Option<(f32, usize)> {
        let hits = prims.iter().enumerate().map(|(i, p)| (p.intersect(o, d, f32::INFINITY), i));
        hits.filter(|h| h.0 < f32::INFINITY).min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// A voxel makes no primitive bigger than the largest other kind (224 bytes: the
    /// transformed sphere's matrices).
    #[test]
    fn a_voxel_fits_in_a_primitive() {
        assert!(size_of::<Primitive>() <= 224, "{} {}", size_of::<Primitive>(), size_of::<SdfVoxel>());
    }

    #[test]
    fn malformed_files_are_refused() {
        let good = vol([2, 2, 2], |p| p.x - 0.5);
        let path = std::path::Path::new("g.vol");
        assert!(SdfGridData::parse_vol(&good, path).is_ok());
        let mut short = good.clone();
        short.pop();
        let mut nan = good.clone();
        nan[48..52].copy_from_slice(&f32::NAN.to_le_bytes());
        let mut flat = good.clone();
        flat[8..12].copy_from_slice(&1i32.to_le_bytes());
        let mut two = good.clone();
        two[20..24].copy_from_slice(&2i32.to_le_bytes());
        for (bad, why) in [
            (&short[..], "bytes"),
            (&nan, "finite"),
            (&flat, "2 to"),
            (&two, "channels"),
            (&good[..30], "short"),
        ] {
            let e = SdfGridData::parse_vol(bad, path).unwrap_err();
            assert!(e.contains(why) && e.contains("g.vol"), "{e}");
        }
        let empty = vol([3, 3, 3], |_| 1.0);
        let grid = SdfGridData::parse_vol(&empty, path).unwrap();
        let file = SdfGridFile { path: path.into(), grid: Some(Arc::new(grid)) };
        let e = SdfGridShape::build(SdfGridDesc { file, normals: SdfNormals::Smooth }).unwrap_err();
        assert!(e.contains("no surface"), "{e}");
    }

    /// Rays at a ball meet it where the trilinear interpolant vanishes (within the grid's
    /// error of the true ball), placed by a rotation, a non-uniform scale and a translation,
    /// with normals close to the ball's.
    #[test]
    fn rays_meet_a_ball_with_its_normals() {
        let m = Affine3A::from_translation(glam::Vec3::new(1.0, -2.0, 0.5))
            * Affine3A::from_rotation_z(0.7)
            * Affine3A::from_scale(glam::Vec3::new(2.0, 2.0, 2.0));
        for normals in [SdfNormals::Smooth, SdfNormals::Analytic] {
            let prims = ball(24, m, normals);
            let centre = m.transform_point3a(Vec3A::splat(0.5));
            let mut rnd = crate::testing::signed(3);
            for _ in 0..500 {
                let dir = Vec3A::new(rnd(), rnd(), rnd()).normalize();
                let o = centre - 3.0 * dir + 0.4 * Vec3A::new(rnd(), rnd(), rnd()).reject_from(dir);
                let Some((t, i)) = closest(&prims, o, dir) else {
                    // Misses only pass outside the ball (radius 0.6 in the world).
                    let miss = (centre - o).reject_from(dir).length();
                    assert!(miss > 0.58, "missed at {miss} from the centre");
                    continue;
                };
                let p = o + t * dir;
                assert!(((p - centre).length() - 0.6).abs() < 0.01, "{}", (p - centre).length());
                let sp = prims[i].surface(p, false);
                let radial = (p - centre).normalize();
                assert!(sp.n.dot(radial) > 0.99 && sp.ns.dot(radial) > 0.99, "{} {} {radial}", sp.n, sp.ns);
                // A ray leaving the point outwards meets nothing of the ball.
                let off = p + sp.err * 3.0 * sp.n;
                assert!(closest(&prims, off, sp.n).is_none());
            }
        }
    }

    /// Both normals vary continuously (nearly, for the analytic one) across voxel faces along a
    /// sweep of rays over a coarse grid (three voxels across).
    #[test]
    fn normals_are_continuous_across_voxels() {
        let prims = ball(4, Affine3A::IDENTITY, SdfNormals::Smooth);
        let analytic = ball(4, Affine3A::IDENTITY, SdfNormals::Analytic);
        let (mut smooth_jump, mut analytic_jump) = (0.0f32, 0.0f32);
        for k in 0..200 {
            let a = 0.3 + 0.4 * k as f32 / 200.0;
            let o = Vec3A::new(a, 0.47, -1.0);
            let eps = Vec3A::new(1e-4, 0.0, 0.0);
            let normal = |prims: &[Primitive], o: Vec3A| {
                closest(prims, o, Vec3A::Z).map(|(t, i)| prims[i].surface(o + t * Vec3A::Z, false).ns)
            };
            if let (Some(a0), Some(a1), Some(b0), Some(b1)) =
                (normal(&prims, o), normal(&prims, o + eps), normal(&analytic, o), normal(&analytic, o + eps))
            {
                smooth_jump = smooth_jump.max((a1 - a0).length());
                analytic_jump = analytic_jump.max((b1 - b0).length());
            }
        }
        // Steps of 1e-4 on a ball of radius 0.3 turn its normal by about 3e-4.
        assert!(smooth_jump < 2e-3 && analytic_jump < 2e-3, "{smooth_jump} {analytic_jump}");
    }

    /// The root is the first zero of the interpolant along the ray inside the voxel, found by
    /// marching for a voxel whose interpolant crosses zero three times along the ray.
    #[test]
    fn the_first_of_several_roots() {
        let mut values = [0.0f32; 32];
        let corners = [1.0, -1.0, -1.0, 1.0, -1.0, 1.0, 1.0, -1.0];
        values[..8].copy_from_slice(&corners);
        let v = SdfVoxel {
            local_from_world: Affine3A::IDENTITY,
            values,
            cells: [1, 1, 1],
            low: 0,
            smooth: false,
            err: 0.0,
        };
        let mut rnd = crate::testing::signed(5);
        for _ in 0..2000 {
            let o = Vec3A::new(rnd(), rnd(), rnd()) * 0.5 + 0.5 - Vec3A::new(0.0, 0.0, 2.0);
            let d = (Vec3A::new(rnd(), rnd(), 4.0) * 0.25).normalize();
            let t = v.intersect(o, d, f32::INFINITY);
            // March from the entry (z = 0) to the exit.
            let inside = |p: Vec3A| p.cmpge(Vec3A::ZERO).all() && p.cmple(Vec3A::ONE).all();
            let (mut prev, mut want) = (None, f32::INFINITY);
            for k in 0..200_000 {
                let s = k as f32 * 2e-5;
                let p = o + s * d;
                if !inside(p) {
                    continue;
                }
                let f = v.f(p);
                if let Some(fp) = prev
                    && fp * f <= 0.0
                {
                    want = s;
                    break;
                }
                prev = Some(f);
            }
            // Where the interpolant only grazes zero the root is ill-conditioned: a few 1e-4.
            if want.is_finite() {
                assert!((t - want).abs() < 5e-4 && v.f(o + t * d).abs() < 1e-4, "{t} {want}");
            } else {
                assert!(t == f32::INFINITY || v.f(o + t * d).abs() < 1e-4, "{t}");
            }
        }
    }
}
