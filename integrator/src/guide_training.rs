//! Path guiding's training: the render's first samples, in stages over the whole image, whose
//! paths record what came back at their Lambertian vertices; each stage learns a [`Guide`] from
//! its records and the next stage renders with it (Müller et al. 2017's iterations). Stage `k`
//! (below [`PASSES`]) takes the render's samples `2^k - 1 .. 2^(k+1) - 1` (1, 2, 4, ... a
//! pixel) with its seed, so its image is those samples of the render: a render over the whole
//! image keeps it, and a sample is rendered with its stage's guide whoever renders it (a crop,
//! a share of a farm, a resumed render). The guides are a function of the scene, the settings
//! and the seed.

use crate::film::Film;
use crate::wavefront::{self, Options};
use glam::Vec3A;
use pathwave_engine::guiding::{Guide, Record, Refine, SpatialRefine};
use pathwave_engine::render_scene::{PixelWindow, RenderScene};
use std::sync::Arc;

/// The training stages before the rest of the render (of 1, 2, 4, ... samples per pixel).
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

/// The most paths of a stage that record, about (a hash of pixel and sample picks them): a
/// 1024x1024 image's stage of 4 samples per pixel made 12.6 M records (Bitterli's
/// cornell-box: 13.8 M), which took about as long to learn from (serially, in good part) as to
/// render. On veach-bidir at 512x512, 16 spp (6 renders each), a quarter of its 1 M paths a
/// stage gave as low a variance (0.226 against 0.217), a sixteenth did not (0.262).
const PATHS_PER_STAGE: f64 = 524_288.0;

/// The first sample of stage `k` (`k <= PASSES`: stage [`PASSES`] is the rest of the render).
pub fn stage_start(k: u32) -> u32 {
    (1u32 << k.min(PASSES)) - 1
}

/// The stage of sample `s`.
pub fn stage_of(s: u32) -> u32 {
    s.saturating_add(1).ilog2().min(PASSES)
}

/// What training gives a render: the guide each stage renders with (`guides[k]`, stage 0
/// without one) and the images over the whole window of the stages it rendered, in order.
pub struct Training {
    /// Per stage, up to the last one asked for.
    pub guides: Vec<Option<Arc<Guide>>>,
    /// The stages rendered (all before the last one asked for), each its samples' film.
    pub films: Vec<Film>,
    /// What their passes counted (stage times with [`Options::timing`]).
    pub stats: wavefront::Stats,
}

/// Renders the training stages over the whole image of `scene` up to (not including) stage
/// `last` (at most [`PASSES`]), each with the guide of the stage before, and learns the guides
/// of stages 1 to `last`; a guide is `None` where no path brought light back to a Lambertian
/// vertex. `progress` hears how many tiles' samples are done (of the image's tiles times
/// `stage_start(last)`). Each stage is logged (info) with what it learned.
pub fn train(scene: &RenderScene, opts: Options, last: u32, progress: &(dyn Fn(usize) + Sync)) -> Training {
    let last = last.min(PASSES);
    let _span = tracing::info_span!("guide_training", stages = last).entered();
    let mut s = scene.clone();
    let (w, h) = (scene.settings.width, scene.settings.height);
    s.settings.window = PixelWindow { x0: 0, y0: 0, w, h };
    let opts = Options { guides: false, costs: false, ..opts };
    let (tiles_x, tiles_y) = crate::tile::Tile::grid_of(&s.settings.window);
    let tiles = (tiles_x * tiles_y) as usize;
    let mut t = Training { guides: vec![None], films: Vec::new(), stats: wavefront::Stats::default() };
    for k in 0..last {
        let samples = stage_start(k)..stage_start(k + 1);
        s.guide = t.guides[k as usize].clone();
        let (before, n) = (samples.start as usize * tiles, samples.len());
        let stage_progress = |done: usize, _| progress(before + done * n);
        let paths = w as f64 * h as f64 * n as f64;
        let opts = Options { train: Some((PATHS_PER_STAGE / paths).min(1.0) as f32), ..opts };
        let (film, stats, records) = wavefront::render_training(&s, opts, samples.clone(), &stage_progress);
        t.stats = std::mem::take(&mut t.stats).merge(stats);
        let guide = learn(&records, samples.len() as u32).map(Arc::new);
        if let Some(g) = &guide {
            let (cells, learned) = g.size();
            tracing::info!(
                "guide stage {k}: samples {samples:?}, {} records, {cells} cells, {learned} with directions",
                records.len()
            );
        }
        t.guides.push(guide);
        t.films.push(film);
    }
    t
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
