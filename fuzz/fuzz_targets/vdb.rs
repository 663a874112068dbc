//! Bytes into the reader of OpenVDB files (`format::vdb`): the header and grid list, then the
//! grids "density" and "temperature" read into dense boxes, as a medium's grid file would be.
//! A grid the reader accepts must hold as many values as its box has voxels (within the
//! `.vol` reader's limit), all finite and not negative, and map its unit cube finitely; it
//! becomes a `VoxelGrid` whose lookups stay within [0, max]. Nothing may panic.
#![no_main]

use glam::Vec3A;
use libfuzzer_sys::fuzz_target;
use pathwave_engine::format::{vdb::VdbFile, vol::MAX_VALUES};
use pathwave_engine::media::grid::VoxelGrid;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(file) = VdbFile::parse(data.to_vec(), Path::new("fuzz.vdb")) else { return };
    for name in ["density", "temperature"] {
        let Ok(g) = file.grid(name) else { continue };
        let voxels: usize = g.size.iter().product();
        assert!(voxels == g.values.len() && voxels <= MAX_VALUES, "{:?}: {} values", g.size, g.values.len());
        assert!(g.values.iter().all(|v| v.is_finite() && *v >= 0.0));
        assert!(g.world_from_unit().is_finite(), "{:?}", g.world_from_unit());
        let grid = VoxelGrid::new(g.size, 1, g.values);
        let max = grid.max();
        for p in [Vec3A::splat(0.5), Vec3A::splat(-1e30), Vec3A::new(0.1, 0.9, 0.3)] {
            let v = grid.value(p);
            assert!(v.is_finite() && (0.0..=max).contains(&v), "{v} at {p}");
        }
    }
});
