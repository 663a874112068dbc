//! What several fuzz targets check the same way: a scene rendered small, and a mesh placed,
//! built into a BLAS and met by rays.

use glam::{Affine3A, Vec3A};
use pathwave_engine::accel::mesh::{MeshBlas, MeshData};
use pathwave_engine::placement::{Form, primitives};
use pathwave_engine::scene::{SceneDesc, open_edge};
use pathwave_engine::world::SceneWorld;
use pathwave_integrator::wavefront;
use std::num::NonZeroU32;
use std::sync::Arc;

/// Spawns `desc` into the ECS world (BVH, light table and media built) and renders a 4x4 image
/// at 2 spp, at most 4 bounces, with the wavefront integrator: no pixel may be NaN or infinite.
pub fn render_and_check(mut desc: SceneDesc) {
    let r = &mut desc.render;
    let four = NonZeroU32::new(4).expect("4 is not zero");
    (r.width, r.height, r.spp) = (four, four, NonZeroU32::new(2).expect("2 is not zero"));
    r.max_depth = r.max_depth.min(4);
    let scene = SceneWorld::render_scene(&desc);
    let (film, _) = wavefront::render(&scene, wavefront::Options::default(), &|_, _| {});
    for p in film.mean() {
        assert!(p.is_finite(), "pixel {p} in a film of {:?}", desc.objects);
    }
}

/// A mesh a reader accepted, placed as a scene object would be (refused beyond the scene's
/// coordinate bound), its BLAS built and rays from four sides meeting its surface: its arrays
/// must agree in length, and every surface point met must be finite with unit normals and
/// finite attributes.
pub fn check_mesh(mesh: MeshData) {
    let n = mesh.positions.len();
    assert!(mesh.normals.as_ref().is_none_or(|v| v.len() == n), "normals beside {n} vertices");
    assert!(mesh.uvs.as_ref().is_none_or(|v| v.len() == n), "uvs beside {n} vertices");
    for a in &mesh.attributes {
        let per = if a.per_vertex() { n } else { mesh.triangles.len() };
        assert_eq!(a.values.len(), a.channels * per, "attribute {}", a.name);
    }
    let mesh = Arc::new(mesh);
    let _ = open_edge(&mesh);
    if primitives(&Form::Mesh(mesh.clone()), &Affine3A::IDENTITY, &mut Vec::new()).is_err() {
        return;
    }
    let blas = MeshBlas::build(mesh.clone());
    let b = blas.bounds();
    if !(b.min.is_finite() && b.max.is_finite()) {
        return; // no triangle with area
    }
    let (centre, reach) = ((b.min + b.max) * 0.5, (b.max - b.min).length() + 1.0);
    for d in [Vec3A::X, Vec3A::NEG_Y, Vec3A::Z, Vec3A::new(-0.48, 0.6, 0.64)] {
        let o = centre - d * reach;
        let Some(hit) = blas.intersect(o, d, f32::INFINITY) else { continue };
        let _ = blas.occluded(o, d, hit.t);
        let mut hits = Vec::new();
        blas.all_hits(o, d, &mut hits);
        let (sp, lift) = blas.surface(&hit, o + d * hit.t);
        assert!(sp.p.is_finite() && sp.err.is_finite() && lift.is_finite(), "{sp:?} lift {lift}");
        for n in [sp.n, sp.ns] {
            assert!((n.length() - 1.0).abs() < 1e-3, "normal {n} at {sp:?}");
        }
        let corners = mesh.triangles[hit.id as usize];
        for a in &mesh.attributes {
            let v = a.at(hit.id, corners, glam::Vec2::new(0.25, 0.5));
            assert!(v.is_finite(), "attribute {} is {v} on triangle {}", a.name, hit.id);
        }
    }
}

/// Numbers in [0, 1] from a hash of the input (FNV-1a, then xorshift32): the same input gives
/// the same rays, so a crash replays.
pub fn numbers(data: &[u8]) -> impl FnMut() -> f32 {
    let mut s = data.iter().fold(0x9e37_79b9u32, |h, &b| (h ^ b as u32).wrapping_mul(0x0100_0193)) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32
    }
}

