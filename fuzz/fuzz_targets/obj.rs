//! Arbitrary bytes, and mutations of the example meshes (the seed corpus), into the OBJ loader.
//! Whatever it accepts is placed as a scene object would be (refused beyond the scene's
//! coordinate bound), its BVH is built and rays from around it meet its surface: nothing may
//! panic, and every surface point met must be finite with unit normals.
#![no_main]

use glam::{Affine3A, Vec3A};
use libfuzzer_sys::fuzz_target;
use pathwave_engine::accel::mesh::MeshBlas;
use pathwave_engine::placement::{Form, primitives};
use pathwave_engine::scene::{open_edge, parse_obj};
use std::path::Path;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.obj");
    let Ok(mesh) = parse_obj(data, path) else { return };
    let mesh = Arc::new(mesh);
    let _ = open_edge(&mesh);
    if primitives(&Form::Mesh(mesh.clone()), &Affine3A::IDENTITY, &mut Vec::new()).is_err() {
        return;
    }
    let blas = MeshBlas::build(mesh);
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
    }
});
