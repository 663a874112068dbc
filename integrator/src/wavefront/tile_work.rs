//! One tile's samples in progress ([`TileWork`]): the wavefront's iteration over the stages
//! (whose list, dispatch and item counts `stages!` in `wavefront/mod.rs` generates), and the two
//! stages that live here (camera rays and film accumulation) rather than in `stages`.

use super::queues::{Paths, Queues};
use super::stage_clock::StageClock;
use super::{Stage, Stats};
use crate::aov::Guide;
use crate::costs::PixelCosts;
use crate::film::{PixelAccumulator, SplatFilm, TileSums, clamp_sample};
use crate::guided::Trail;
use crate::lambert_vertex::LANES;
use crate::oracle;
use crate::path;
use crate::sampler::{Sampler, SamplerLanes};
use crate::tile::Tile;
use glam::Vec3;
use pathwave_engine::camera::RayLanes;
use pathwave_engine::filter::Splat;
use pathwave_engine::guiding::Record;
use pathwave_engine::render_scene::{PixelWindow, RenderScene};
use std::ops::Range;
use std::time::Duration;

/// What [`TileWork::run`] calls before each stage: `(iteration, work, stage, paths, queues)`.
pub(super) type Observer<'o, 'a> = dyn FnMut(u64, &TileWork<'a>, Stage, &Paths, &Queues) + 'o;

/// One tile's samples in progress: which sample comes next, the pixels' and guides' sums,
/// the statistics, and the stages each iteration runs.
#[derive(Clone)]
pub(super) struct TileWork<'a> {
    pub(super) scene: &'a RenderScene,
    tile: Tile,
    samples: Range<u32>,
    /// Samples of the tile (pixels times samples per pixel) and how many have started.
    work: u64,
    next_sample: u64,
    /// The tile's pixels' sums, or where the film splats, those of the pixels its samples
    /// reach.
    pub(super) film: TileFilm,
    pub(super) guide_sums: Option<Vec<[Vec3; 3]>>,
    /// What the tile's pixels and materials cost (with [`super::Options::costs`]).
    charges: Option<Charges>,
    pub(super) stats: Stats,
    /// What training paths recorded, in the order they ended (with [`super::Options::train`]).
    pub(super) records: Option<Vec<Record>>,
    /// The share of paths that record.
    train: f32,
    /// Each stage's time in [`StageClock`] ticks while the tile runs (then added to
    /// [`Stats::time`]).
    ticks: [u64; Stage::SLOTS],
    /// The stages each iteration runs, in order (`stages!` in `wavefront/mod.rs`): the
    /// scene's shading kinds only, guides only when asked for.
    pipeline: Vec<Stage>,
}

impl<'a> TileWork<'a> {
    pub(super) fn new(
        scene: &'a RenderScene,
        tile: &Tile,
        samples: Range<u32>,
        splat: Option<(Splat, PixelWindow)>,
        guides: bool,
        costs: bool,
        train: Option<f32>,
    ) -> Self {
        let pixels = (tile.w * tile.h) as usize;
        let pipeline = super::pipeline(scene, guides);
        let film = match splat {
            Some((filter, rect)) => TileFilm::Splat(Box::new(SplatFilm::new(filter, rect))),
            None => TileFilm::Own(TileSums::new(pixels)),
        };
        Self {
            scene,
            tile: *tile,
            work: pixels as u64 * samples.len() as u64,
            samples,
            next_sample: 0,
            film,
            guide_sums: guides.then(|| vec![[Vec3::ZERO; 3]; pixels]),
            charges: costs
                .then(|| Charges::new(pixels, scene.materials.len(), scene.lights.len(), &pipeline)),
            stats: Stats::default(),
            records: train.map(|_| Vec::new()),
            train: train.unwrap_or(0.0),
            ticks: [0; Stage::SLOTS],
            pipeline,
        }
    }

    /// Runs the tile to its last sample with `batch` path slots, calling `observe(iteration,
    /// self, stage, paths, queues)` before each stage that has work.
    pub(super) fn run(
        &mut self,
        batch: usize,
        clock: bool,
        p: &mut Paths,
        q: &mut Queues,
        observe: &mut Observer<'_, 'a>,
    ) {
        let cpu = self.charges.is_some().then(cpu_time::ThreadTime::now);
        let clock = clock.then(StageClock::get);
        let span = clock.map(StageClock::span);
        q.free.clear();
        q.free.extend((0..batch as u32).rev());
        p.trail.clear();
        if self.records.is_some() {
            p.trail.resize(batch, Trail::default());
        }
        q.active.clear();
        let pipeline = std::mem::take(&mut self.pipeline);
        // The first stage fills free slots with new paths: none active after it, the tile is done.
        let (&refill, rest) = pipeline.split_first().expect("a pipeline starts with its camera rays");
        loop {
            let iteration = self.stats.iterations;
            let observe =
                &mut |w: &TileWork<'a>, stage, p: &Paths, q: &Queues| observe(iteration, w, stage, p, q);
            self.timed(clock, refill, p, q, observe);
            if q.active.is_empty() {
                break;
            }
            self.stats.iterations += 1;
            self.stats.occupancy_sum += q.active.len() as f64 / batch as f64;
            for &stage in rest {
                self.timed(clock, stage, p, q, observe);
            }
            self.stats.paths += q.finished.len() as u64;
            q.escaped.clear();
            q.emissive.clear();
            q.finished.clear();
            q.shadow.clear();
            std::mem::swap(&mut q.active, &mut q.next);
            q.next.clear();
        }
        self.pipeline = pipeline;
        if let Some(span) = span {
            let time = span.to_duration();
            for (t, ticks) in self.stats.time.iter_mut().zip(std::mem::take(&mut self.ticks)) {
                *t += time(ticks);
            }
        }
        if let (Some(c), Some(start)) = (&mut self.charges, cpu) {
            c.cpu += start.elapsed();
        }
    }

    /// How many new paths `generate_camera_rays` would start now: a free slot each, while the
    /// tile has samples left.
    pub(super) fn fresh(&self, q: &Queues) -> usize {
        q.free.len().min((self.work - self.next_sample) as usize)
    }

    /// The tile's results.
    pub(super) fn result(mut self) -> super::TileResult {
        if let Some(c) = &mut self.charges {
            c.finish(&self.stats.items);
        }
        super::TileResult {
            film: self.film,
            guides: self.guide_sums,
            charges: self.charges,
            stats: self.stats,
            records: self.records.unwrap_or_default(),
        }
    }

    /// Runs `stage` if it has work (after `observe` has seen its input), recording its item
    /// count and, with a `clock`, its time in ticks (traces get them once per tile, from [`trace_tile`]);
    /// with costs, counts its items by pixel and material (then `clock` must be on).
    #[inline]
    fn timed(
        &mut self,
        clock: Option<StageClock>,
        stage: Stage,
        p: &mut Paths,
        q: &mut Queues,
        observe: &mut dyn FnMut(&TileWork<'a>, Stage, &Paths, &Queues),
    ) {
        let slots = self.slots(stage, q);
        let items = slots.len();
        if items == 0 {
            return;
        }
        if let Some(charges) = &mut self.charges {
            charges.count(self.scene, stage, self.stats.iterations, slots, p);
        }
        observe(self, stage, p, q);
        let k = stage.index();
        if let Some(clock) = clock {
            let start = clock.now();
            self.stage(stage, p, q);
            self.ticks[k] += clock.now().wrapping_sub(start);
        } else {
            self.stage(stage, p, q);
        }
        self.stats.items[k] += items as u64;
        self.stats.calls[k] += 1;
    }

    /// `generate_camera_rays`: fills free slots with the tile's next samples, their numbers
    /// drawn across lanes a group at a time.
    pub(super) fn generate_camera_rays(&mut self, p: &mut Paths, q: &mut Queues) {
        let (scene, tile) = (self.scene, &self.tile);
        let spp = self.samples.len() as u64;
        let fresh = self.fresh(q);
        for group in (0..fresh).step_by(LANES) {
            let m = LANES.min(fresh - group);
            // Sample k of the tile is sample k % spp of pixel k / spp: one division per group,
            // then the lanes step through samples and pixels. Lanes past `m` repeat the last:
            // drawn, not used.
            let k = self.next_sample;
            let (mut i, mut j) = ((k / spp) as u32, (k % spp) as u32);
            let (mut x, mut y) = tile.pixel(i);
            let (mut which, mut pixel) = ([(0, 0); LANES], [(0, 0); LANES]);
            for l in 0..LANES {
                (which[l], pixel[l]) = ((i, self.samples.start + j), (x, y));
                if l + 1 < m {
                    j += 1;
                    if j as u64 == spp {
                        (i, j, x) = (i + 1, 0, x + 1);
                        if x == tile.x0 + tile.w {
                            (x, y) = (tile.x0, y + 1);
                        }
                    }
                }
            }
            let guides = self.guide_sums.is_some();
            let far_clip = scene.camera.has_far_clip();
            let chromatic = scene.features.media && scene.media.chromatic();
            let samplers: [Sampler; LANES] =
                std::array::from_fn(|l| path::camera_sampler(scene, pixel[l].0, pixel[l].1, which[l].1));
            let (rays, within) = camera_rays(scene, &SamplerLanes::from(&samplers), &pixel);
            let splat = matches!(self.film, TileFilm::Splat(_));
            for l in 0..m {
                let slot = q.free.pop().expect("a free slot for every new path");
                let ray = rays.ray(l);
                let s = slot as usize;
                p.set_ray(s, ray);
                p.set_state(s, &path::PathState::new(ray.origin));
                if chromatic {
                    p.ratio[s] = glam::Vec3::ONE;
                }
                p.sampler[s] = samplers[l];
                p.pixel[s] = which[l].0;
                if splat {
                    p.within[s] = within[l].to_array();
                }
                if far_clip {
                    p.far[s] = rays.tmax[l];
                }
                // Only what the denoiser reads is written (52 bytes per path otherwise).
                if guides {
                    p.guide[s] = Guide::NEW;
                }
                if self.records.is_some() {
                    p.trail[s].keep = crate::guided::Trail::records(pixel[l], which[l].1, self.train);
                }
                q.active.push(slot);
            }
            self.next_sample += m as u64;
        }
    }

    /// `accumulate_film`: finished paths add their radiance (and guides) to their pixels and
    /// free their slots.
    pub(super) fn accumulate_film(&mut self, p: &mut Paths, q: &mut Queues) {
        let clamp = self.scene.settings.clamp;
        match &mut self.film {
            TileFilm::Own(film) => {
                for &i in &q.finished {
                    film.add(p.pixel[i as usize] as usize, clamp_sample(p.l[i as usize], clamp));
                }
            }
            TileFilm::Splat(film) => {
                for &i in &q.finished {
                    let i = i as usize;
                    let own = self.tile.pixel(p.pixel[i]);
                    film.splat(own, p.within[i], clamp_sample(p.l[i], clamp));
                }
            }
        }
        if let Some(sums) = &mut self.guide_sums {
            for &i in &q.finished {
                // A path that ended among mirrors and glass shows their tint.
                let g = &p.guide[i as usize];
                let albedo = if g.open { g.tint } else { g.albedo };
                let sum = &mut sums[p.pixel[i as usize] as usize];
                (sum[0], sum[1], sum[2]) = (sum[0] + albedo, sum[1] + g.normal, sum[2] + g.emission);
            }
        }
        if let Some(records) = &mut self.records {
            for &i in &q.finished {
                p.trail[i as usize].finish(p.l[i as usize], records);
            }
        }
        q.free.extend_from_slice(&q.finished);
    }
}

/// What a tile's pixels and materials cost. The items each stage takes are counted by the
/// pixel of their path (and, for shading, by material) as the stage takes them; once every
/// tile is done, each item is charged its stage's mean time per item over the render
/// ([`Charges::settle`]), the stages' times scaled to the threads' CPU time (what the tiles
/// cost, less the pauses of a preempted thread, which a wall clock charges to the tile it was
/// in). Charging each call's time to its own items made single pixels look a thousand times
/// costlier than their neighbours (the few paths a tile has left at its end share a call's
/// fixed cost); charging each tile's own means made tiles stand out for no reason in the scene
/// (a thread's first tile, a cache disturbed). The CPU clock is read per tile, not per stage
/// call (a system call each).
#[derive(Clone)]
pub(super) struct Charges {
    /// Bounces of each pixel's finished paths (the pixels' [`PixelCosts`] are made when the
    /// tile is settled: until then, a tile holds only its counts).
    bounces: Vec<u64>,
    /// The stage slots ([`Stage::index`]) of the tile's pipeline: the columns of
    /// [`Self::pixel_items`], first the [`Self::counted`] stages whose items are counted one
    /// by one, then those counted per path, each in pipeline order.
    columns: Vec<usize>,
    /// Each stage slot's column (`usize::MAX` for a stage the tile does not run).
    column: [usize; Stage::SLOTS],
    /// The columns of the stages whose items are counted one by one, rounded up to a whole
    /// number of [`FOLD`]s: the width of [`Self::path_items`].
    counted: usize,
    /// Items per pixel and column: `[pixel * width + column]`, `width` the columns or
    /// [`Self::counted`] if more (the columns past the stages' stay zero).
    pixel_items: Vec<u32>,
    /// Items per path slot and column of the stages counted item by item,
    /// `[path * counted + column]`, added to the path's pixel when it finishes (the path's
    /// counts side by side, as its pixel's, [`FOLD`] at a time). Counted by path, the items of
    /// a queue go to different counters; counted by pixel, a pixel's samples in neighbouring
    /// path slots made each increment wait on the one before.
    path_items: Vec<u32>,
    /// Items per stage slot and material id, of one item in [`MATERIAL_STRIDE`] of each
    /// shading queue, in [`MATERIAL_LANES`] interleaved copies (for the same reason):
    /// `[(lane * SLOTS + slot) * materials + material]`.
    material_items: Vec<u32>,
    /// Once the tile is done, each material's estimated items of a shading stage where they are
    /// not zero, as `(stage slot, material, items)`: the stage's items shared in proportion to
    /// the counted ones.
    material_counts: Vec<(usize, usize, f64)>,
    /// The entry of the scene's light table a path slot's vertex sampled, and the iteration it
    /// was shaded in, for one shading item in [`MATERIAL_STRIDE`] (kept only where the table
    /// has more than one entry; finding the entry again draws the light sampler's number, 6%
    /// of materials-env's time when done for every vertex).
    path_light: Vec<(u64, u32)>,
    /// Shadow rays by the light table entry they were aimed at: all of them with one entry,
    /// else those of the vertices in `path_light`.
    light_items: Vec<u32>,
    /// Once the tile is done, each light table entry's estimated shadow rays: the tile's
    /// shadow rays shared in proportion to `light_items`.
    light_counts: Vec<f64>,
    /// The iteration each path slot's path started in: a path takes one item of
    /// `intersect_closest` (and `record_guides`) per iteration, counted when it finishes.
    born: Vec<u64>,
    /// The thread's CPU time in the tile's stages and between them.
    pub(super) cpu: Duration,
}

/// Counts a finished path adds to its pixel's at once (a vector register of them).
const FOLD: usize = 8;

/// Copies of the material counters, taken in turn by a queue's items.
const MATERIAL_LANES: usize = 4;

/// One item in this many of a shading queue is counted by material (reading its hit's
/// material was a third of the counting's cost on cornell): the shares of a stage's time by
/// material are estimates, from millions of items on most renders.
const MATERIAL_STRIDE: usize = 8;

impl Charges {
    fn new(pixels: usize, materials: usize, lights: usize, pipeline: &[Stage]) -> Self {
        let (counted, per_path): (Vec<Stage>, Vec<Stage>) =
            pipeline.iter().partition(|s| !Self::per_path(**s));
        let columns: Vec<usize> = counted.iter().chain(&per_path).map(|s| s.index()).collect();
        let mut column = [usize::MAX; Stage::SLOTS];
        for (c, &k) in columns.iter().enumerate() {
            column[k] = c;
        }
        Self {
            bounces: vec![0; pixels],
            pixel_items: vec![0; pixels * columns.len().max(counted.len().next_multiple_of(FOLD))],
            counted: counted.len().next_multiple_of(FOLD),
            columns,
            column,
            path_items: Vec::new(),
            material_items: vec![0; MATERIAL_LANES * Stage::SLOTS * materials],
            material_counts: Vec::new(),
            path_light: Vec::new(),
            light_items: vec![0; lights],
            light_counts: Vec::new(),
            born: Vec::new(),
            cpu: Duration::ZERO,
        }
    }

    /// Whether a path's items of `stage` are counted when it finishes rather than one by one:
    /// one each of its first and last stage, and one of the closest hits (and the guides) for
    /// every iteration it lived.
    fn per_path(stage: Stage) -> bool {
        matches!(
            stage,
            Stage::GenerateCameraRays | Stage::IntersectClosest | Stage::RecordGuides | Stage::AccumulateFilm
        )
    }

    /// Counts the items `stage` takes in wavefront iteration `iteration`, those of the paths in
    /// `slots`: by path, by material for a shading stage, by light for the shadow rays; the
    /// paths that finish add theirs to their pixel, with their bounces.
    fn count(&mut self, scene: &RenderScene, stage: Stage, iteration: u64, slots: &[u32], p: &Paths) {
        let (paths, counted) = (p.pixel.len(), self.counted);
        let width = self.columns.len().max(counted);
        self.path_items.resize(paths * counted, 0);
        self.born.resize(paths, 0);
        let many_lights = self.light_items.len() > 1;
        if many_lights && matches!(stage, Stage::Shade(_) | Stage::ShadeMedium) {
            // The light a vertex samples, as the stage is about to pick it, for one item in
            // MATERIAL_STRIDE (the start turning with the iteration): its shadow ray, if it
            // makes one, is traced later in the same iteration.
            self.path_light.resize(paths, (u64::MAX, 0));
            let start = (iteration % MATERIAL_STRIDE as u64) as usize;
            for &s in slots.iter().skip(start).step_by(MATERIAL_STRIDE) {
                let s = s as usize;
                // Where the vertex is: the medium's scattering point is the path's origin.
                let at = match stage {
                    Stage::ShadeMedium => [p.origin[s], glam::Vec3A::ZERO],
                    _ => [p.hit[s].surface.p, p.hit[s].surface.ns],
                };
                let light = oracle::sampled_light(scene, &p.sampler[s], p.depth[s], at) as u32;
                self.path_light[s] = (iteration, light);
            }
        }
        if !Self::per_path(stage) {
            let (counts, c) = (self.path_items.as_mut_slice(), self.column[stage.index()]);
            for &s in slots {
                counts[s as usize * counted + c] += 1;
            }
        }
        match stage {
            Stage::GenerateCameraRays => {
                for &s in slots {
                    self.born[s as usize] = iteration;
                }
            }
            Stage::AccumulateFilm => {
                // The iteration count moved on after the refill of the paths' first iteration.
                let column = |s: Stage| self.column[s.index()];
                let per_path = [Stage::IntersectClosest, Stage::RecordGuides].map(column);
                let once = [Stage::GenerateCameraRays, Stage::AccumulateFilm].map(column);
                for &s in slots {
                    let (s, px) = (s as usize, p.pixel[s as usize] as usize);
                    let to = &mut self.pixel_items[px * width..][..width];
                    let from = &mut self.path_items[s * counted..][..counted];
                    for (to, from) in to.as_chunks_mut::<FOLD>().0.iter_mut().zip(from.as_chunks_mut().0) {
                        for (to, from) in to.iter_mut().zip(*from) {
                            *to += from;
                        }
                        *from = [0; FOLD];
                    }
                    let lived = (iteration - self.born[s]) as u32;
                    for c in per_path.into_iter().filter(|&c| c != usize::MAX) {
                        to[c] += lived;
                    }
                    for c in once {
                        to[c] += 1;
                    }
                    self.bounces[px] += u64::from(p.depth[s] - p.crossings[s]);
                }
            }
            Stage::TraceShadowRays if many_lights => {
                // A vertex that samples a light apart queues its ray after the chosen light's:
                // a slot's second ray is the light apart's (its first, where the
                // chosen light made none, is counted as the chosen light's).
                const SECOND: u64 = 1 << 63;
                let apart = scene.lights.apart();
                for &s in slots {
                    let (shaded, light) = self.path_light[s as usize];
                    let light = match apart {
                        Some(a) if shaded == iteration | SECOND => a as u32,
                        _ if shaded == iteration => light,
                        _ => continue,
                    };
                    self.light_items[light as usize] += 1;
                    self.path_light[s as usize].0 = iteration | SECOND;
                }
            }
            Stage::TraceShadowRays => {
                if let Some(n) = self.light_items.first_mut() {
                    *n += slots.len() as u32;
                }
            }
            Stage::Shade(_) => {
                // One item in MATERIAL_STRIDE, starting at a place that turns with the iteration.
                let (k, m) = (stage.index(), self.material_items.len() / (MATERIAL_LANES * Stage::SLOTS));
                let start = (iteration % MATERIAL_STRIDE as u64) as usize;
                for (j, &s) in slots.iter().skip(start).step_by(MATERIAL_STRIDE).enumerate() {
                    let id = p.hit[s as usize].material as usize;
                    if id < m {
                        self.material_items[((j % MATERIAL_LANES) * Stage::SLOTS + k) * m + id] += 1;
                    }
                }
            }
            _ => {}
        }
    }
    /// The pixels' costs, each item charged its stage's `per_item` time (by
    /// [`Stage::index`]); the shading time of each material id and the shadow rays' time of
    /// each light added to `stats`.
    pub(super) fn settle(self, per_item: &[f64], stats: &mut Stats) -> PixelCosts {
        let width = self.columns.len().max(self.counted);
        let mut costs =
            PixelCosts { bounces: self.bounces, ..PixelCosts::new(self.pixel_items.len() / width) };
        let column = |s: Stage| self.column[s.index()];
        let (ic, sr, af) =
            (column(Stage::IntersectClosest), column(Stage::TraceShadowRays), column(Stage::AccumulateFilm));
        for (px, items) in self.pixel_items.chunks_exact(width).enumerate() {
            costs.time[px] = items.iter().zip(&self.columns).map(|(&n, &k)| n as f64 * per_item[k]).sum();
            // Rays cast: closest hits and shadow rays; paths: those that finished.
            costs.rays[px] = u64::from(items[ic] + items[sr]);
            costs.paths[px] = items[af];
        }
        let charge = |to: &mut Vec<Duration>, id: usize, n: f64, k: usize| {
            if to.len() <= id {
                to.resize(id + 1, Duration::ZERO);
            }
            to[id] += Duration::from_secs_f64(n * per_item[k]);
        };
        for &(k, id, n) in &self.material_counts {
            charge(&mut stats.material_time, id, n, k);
        }
        for (light, &n) in self.light_counts.iter().enumerate() {
            charge(&mut stats.light_time, light, n, Stage::TraceShadowRays.index());
        }
        costs
    }

    /// Drops what only the tile's run needed (the counts by path, the material and light
    /// counters), keeping the counts by pixel, the material counts that are not zero, those of
    /// each stage scaled to its `items` in the tile (by stage slot), and the lights' counts
    /// scaled to the shadow rays.
    fn finish(&mut self, items: &[u64; Stage::SLOTS]) {
        let m = self.material_items.len() / (MATERIAL_LANES * Stage::SLOTS);
        for k in 0..Stage::SLOTS {
            let counted = |id: usize| -> u32 {
                (0..MATERIAL_LANES).map(|l| self.material_items[(l * Stage::SLOTS + k) * m + id]).sum()
            };
            let sum: u32 = (0..m).map(counted).sum();
            for id in (0..m).filter(|&id| counted(id) > 0) {
                self.material_counts.push((k, id, items[k] as f64 * f64::from(counted(id)) / f64::from(sum)));
            }
        }
        let shadow_rays = items[Stage::TraceShadowRays.index()] as f64;
        let sum: u32 = self.light_items.iter().sum();
        if sum > 0 {
            self.light_counts =
                self.light_items.iter().map(|&n| shadow_rays * f64::from(n) / f64::from(sum)).collect();
        }
        (self.path_items, self.born, self.material_items, self.path_light, self.light_items) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    }
}

/// A tile's sums: of its own pixels, or where the film splats, of the pixels its samples reach.
#[derive(Clone)]
pub(super) enum TileFilm {
    /// Each sample in its own pixel (row-major within the tile).
    Own(TileSums),
    /// Each sample splatted over the pixels the filter reaches (boxed: the filter's tables
    /// are 2 KB).
    Splat(Box<SplatFilm>),
}

impl TileFilm {
    /// The sums: of the tile's pixels, or of the pixels its samples reach (row-major).
    pub(super) fn into_pixels(self) -> Vec<PixelAccumulator> {
        match self {
            TileFilm::Own(sums) => sums.into_pixels(),
            TileFilm::Splat(film) => film.into_pixels(),
        }
    }
}

/// [`path::camera_rays`] for `LANES` samples, with AVX-512 where the CPU has it.
#[inline]
fn camera_rays(
    scene: &RenderScene,
    s: &SamplerLanes<LANES>,
    pixel: &[(u32, u32); LANES],
) -> (RayLanes<LANES>, [glam::Vec2; LANES]) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || path::camera_rays(scene, s, pixel),
    )
}
