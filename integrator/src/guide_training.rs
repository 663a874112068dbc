//! Path guiding's training phase: passes over the whole image whose paths record what came back
//! at their Lambertian vertices, each pass learning a [`Guide`] from its records and rendering
//! with the guide of the pass before (Müller et al. 2017's iterations, their images set aside).
//! Passes draw their numbers from seeds of their own, derived from the render's, so the guide is
//! a function of the scene, the settings and the seed, and shares no numbers with the render.

use crate::wavefront::{self, Options};
use glam::Vec3A;
use pathwave_engine::guiding::{Guide, Record, Refine, SpatialRefine};
use pathwave_engine::render_scene::{PixelWindow, RenderScene};
use std::sync::Arc;

/// The training passes a render runs (of 1, 2, 4, ... samples per pixel).
pub const PASSES: u32 = 3;

/// Records a spatial cell keeps at most, times the square root of the pass's samples per pixel
/// (Müller et al.'s `c`).
const RECORDS_PER_CELL: f64 = 12_000.0;

/// The spatial cells a pass aims at, and the fewest records a cell splits with. Measured on
/// `scenes/lit-ceiling.ron` at 160x120 (32 spp, relative variance against unguided): Müller et
/// al.'s bound alone left 5 cells and 1.2x the noise; 500 records a cell 0.75x, 150 0.84x; on
/// Bitterli's veach-bidir (1024x1024, 8 spp), 500 records a cell gave 0.59x, the bound 0.47x.
const CELLS: usize = 256;
const MIN_RECORDS: usize = 500;

/// The guide learned by `passes` passes of 1, 2, 4, ... samples per pixel over the whole image
/// of `scene` (`None` without a pass, or where no path brought light back to a Lambertian
/// vertex). Each pass is logged (info) with what it learned.
pub fn train(scene: &RenderScene, opts: Options, passes: u32) -> Option<Arc<Guide>> {
    let _span = tracing::info_span!("guide_training", passes).entered();
    let mut s = scene.clone();
    let (w, h) = (scene.settings.width, scene.settings.height);
    s.settings.window = PixelWindow { x0: 0, y0: 0, w, h };
    let opts = Options { train: true, guides: false, costs: false, ..opts };
    let mut guide = None;
    for k in 0..passes {
        let spp = 1u32 << k.min(16);
        s.settings.spp = spp;
        s.settings.seed = pass_seed(scene.settings.seed, k);
        s.guide = guide;
        let (_, _, records) = wavefront::render_training(&s, opts, 0..spp, &|_, _| {});
        guide = learn(&records, spp).map(Arc::new);
        if let Some(g) = &guide {
            let (cells, learned) = g.size();
            tracing::info!(
                "guide pass {k}: {spp} spp, {} records, {cells} cells, {learned} with directions",
                records.len()
            );
        }
    }
    guide
}

/// The seed of training pass `k` of a render seeded `seed` (SplitMix64's finaliser, so that
/// neighbouring seeds and passes share nothing).
fn pass_seed(seed: u64, k: u32) -> u64 {
    let mut z = seed ^ 0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k as u64 + 1);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The guide of one pass's `records` (made at `spp` samples per pixel), over their box; `None`
/// where none brought light back.
fn learn(records: &[Record], spp: u32) -> Option<Guide> {
    if !records.iter().any(|r| r.energy > 0.0) {
        return None;
    }
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for r in records {
        let p = Vec3A::from(r.p);
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    // About CELLS cells, no fewer records in one than MIN_RECORDS (small images: the directions'
    // noise), no more than Müller et al.'s bound (large ones).
    let bound = (RECORDS_PER_CELL * (spp as f64).sqrt()) as usize;
    let max_records = (records.len() / CELLS).clamp(MIN_RECORDS, bound.max(MIN_RECORDS));
    let spatial = SpatialRefine { max_records, max_depth: 48 };
    Some(Guide::build(records, lo, hi, spatial, Refine::DEFAULT))
}
