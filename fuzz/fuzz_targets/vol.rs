//! Bytes into the reader of Mitsuba's `.vol` grids, as a medium's grid (`VoxelGrid`) and as an
//! SDF grid shape's (`SdfGridData`). A grid the medium reader accepts is looked up inside,
//! outside and at infinite points (every value finite, within [0, max]), its majorant cells
//! walked along rays (every lookup within its cell's bound), and (if the scene loader would take
//! it) it fills a box of medium whose
//! free flights and transmittance are sampled: distances inside the box, transmittance in
//! [0, 1], albedo finite. Nothing may panic.
#![no_main]

use glam::{Affine3A, Vec3, Vec3A};
use libfuzzer_sys::fuzz_target;
use pathwave_engine::media::grid::VoxelGrid;
use pathwave_engine::math::Ray;
use pathwave_engine::media::{Boundary, Media, Medium, PlacedGrid, Volume, VolumeMotion};
use pathwave_engine::shape::Closed;
use std::path::Path;
use std::sync::Arc;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.vol");
    let _ = pathwave_engine::shape::SdfGridData::parse_vol(data, path);
    let Ok(grid) = VoxelGrid::parse_vol(data, path) else { return };
    let max = grid.max();
    assert!(max.is_finite() && max >= 0.0);

    // Points and rays from a hash of the input.
    let mut rnd = pathwave_fuzz::numbers(data);
    for p in [Vec3A::splat(-1e30), Vec3A::splat(f32::INFINITY), Vec3A::new(0.5, -3.0, 7.0)] {
        let v = grid.value(p);
        assert!(v.is_finite() && (0.0..=max).contains(&v), "{v} at {p}");
    }
    for _ in 0..16 {
        let o = Vec3A::new(rnd(), rnd(), rnd());
        let d = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        let c = grid.color(o);
        assert!(c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= max, "{c}");
        let exit = (0..3)
            .map(|a| if d[a] > 0.0 { (1.0 - o[a]) / d[a] } else if d[a] < 0.0 { -o[a] / d[a] } else { f32::INFINITY })
            .fold(f32::INFINITY, f32::min);
        grid.majorants().walk(o, d, 0.0, exit, |ta, tb, bound| {
            assert!(ta < tb && bound > 0.0);
            for k in 0..=4 {
                let v = grid.value(o + (ta + (tb - ta) * k as f32 / 4.0) * d);
                assert!(v <= bound, "{v} above its cell's bound {bound}");
            }
        });
    }

    // A unit box of medium on the grid, as dense as the scene loader allows.
    let sigma = 1.0 + 10.0 * rnd();
    if !(sigma * max <= pathwave_engine::scene::MAX_GRID_EXTINCTION) {
        return;
    }
    let grid = Arc::new(grid);
    let medium = Medium {
        density_grid: Some(PlacedGrid { grid: grid.clone(), grid_from_object: Affine3A::IDENTITY }),
        albedo_grid: (max <= 1.0).then(|| PlacedGrid { grid, grid_from_object: Affine3A::IDENTITY }),
        ..Medium::homogeneous(Vec3::splat(sigma), Vec3::splat(0.8))
    };
    let boundary = Boundary::Closed(Closed::Box { min: Vec3A::ZERO, max: Vec3A::ONE });
    let media = Media::new(vec![Volume {
        object_from_world: Affine3A::IDENTITY,
        boundary,
        medium,
        motion: VolumeMotion::Still,
    }]);
    for _ in 0..8 {
        let o = Vec3A::new(rnd(), rnd(), rnd()) * 3.0 - 1.0;
        let d = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
        if d == Vec3A::ZERO {
            continue;
        }
        let ray = Ray::new(o, d);
        let tr = media.transmittance(&ray, 10.0);
        assert!(tr.is_finite() && tr.min_element() >= 0.0 && tr.max_element() <= 1.0, "transmittance {tr}");
        if let Some(e) = media.sample(&ray, 10.0, rnd().min(0.999_999)) {
            let p = o + e.t * d;
            assert!((0.0..=10.0).contains(&e.t) && p.cmpge(Vec3A::splat(-1e-4)).all() && p.cmple(Vec3A::splat(1.0001)).all(), "scattered at {p}");
            assert!(e.albedo.is_finite() && e.albedo.min_element() >= 0.0, "albedo {}", e.albedo);
        }
    }
});
