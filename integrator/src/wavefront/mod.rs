//! The wavefront integrator: paths advance stage by stage over structure-of-arrays queues.
//!
//! Each rayon task owns one image tile and a batch of path slots (sized to stay in cache). An
//! iteration runs `generate_camera_rays` (fill free slots with new pixel samples),
//! `intersect_closest` (which also samples free-flight distances in scenes with media),
//! `handle_escaped`, `handle_emissive`, `shade_medium`, one shading loop per material kind
//! present (`shade_lambertian`, `shade_metal`, ...: one per kind in the engine's material
//! registry that is not an emitter; each writes continuation rays, and those of kinds that
//! sample lights, Lambertian and glossy, also shadow rays), `trace_shadow_rays` and
//! `accumulate_film` (finished paths free their slot). Paths that end are replaced by new
//! camera samples until the tile's samples are done.
//!
//! Every sample is computed by the same per-vertex code as the reference path tracer and pixel
//! sums are exact, so the image does not depend on the batch size or the thread count, and
//! equals the reference's up to exact ties (two primitives at a hit's distance, on a shared
//! edge), which the two may break differently: `tests/wavefront.rs` allows 2 differing pixels.

mod queues;
mod shading;
mod stage_clock;
mod stages;
#[cfg(feature = "test-stage")]
pub mod test_stage;
mod tile_work;

use crate::aov::Aovs;
use crate::costs::PixelCosts;
use crate::film::{Film, PixelSums};
use crate::tile::{self, Tile};
use glam::Vec3;
use pathwave_engine::filter::Splat;
use pathwave_engine::guiding::Record;
use pathwave_engine::material::{MaterialKind, Shading};
use pathwave_engine::render_scene::{PixelWindow, RenderScene};
use queues::{Paths, Queues};
use std::ops::Range;
use std::time::Duration;
use tile_work::{TileFilm, TileWork};

/// Settings of the wavefront integrator.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Paths in flight per worker.
    pub batch: usize,
    /// Also record the denoiser's guides ([`Film::guides`]) from the paths' own camera rays.
    pub guides: bool,
    /// Time each stage ([`Stats::time`], for `--stats`); traces at `pathwave::stage`'s TRACE
    /// level turn it on too. Off, the stages are only counted: reading the clock twice per
    /// stage and iteration was 0.8-1.4% of cornell's profile (`__vdso_clock_gettime`).
    pub timing: bool,
    /// Measure what each pixel costs ([`Film::costs`]) and what shading each material took
    /// ([`Stats::material_time`]), in the thread's CPU time; times the stages too.
    pub costs: bool,
    /// Record what paths bring back at their Lambertian vertices, for path guiding to learn
    /// from ([`render_training`]): this share of the paths (by a hash of pixel and sample).
    pub train: Option<f32>,
}

impl Default for Options {
    fn default() -> Self {
        Self { batch: 256, guides: false, timing: false, costs: false, train: None }
    }
}

/// The wavefront's stages, each once, in pipeline order: its variant (with its doc), its name
/// (also its tracing span's), when a tile runs it (`when`, from the tile's [`Setup`]), the path
/// slots whose items (rays or paths) it takes from the queues (`slots`) and what runs it (`run`,
/// on the tile's [`TileWork`] and its
/// paths and queues). A stage with a field (`Shade(kind: T in LIST)`) is one stage per value
/// of `LIST` (a const array of `T`, whose `T::COUNT` values each get a statistics slot), bound
/// as `kind` in its expressions. The table generates [`Stage`], [`Stage::ALL`],
/// [`Stage::index`], [`Stage::SLOTS`], [`Stage::name`], and the tile's pipeline, item counts and
/// dispatch ([`TileWork::new`], [`TileWork::slots`], [`TileWork::stage`]); the first stage must
/// be one without a field (it refills the slots, and the tile ends when it leaves none active).
/// A row after `@cfg(predicate)` exists only where the predicate holds (as `#[cfg]`).
macro_rules! stages {
    (@first $(#[$doc:meta])* $v:ident : $($rest:tt)*) => { Stage::$v };
    (@width) => { 1 };
    (@width $t:ident) => { $t::COUNT };
    (@gen [$first:expr] $(
        $(#[$doc:meta])*
        $(@cfg($cfg:meta))?
        $v:ident $(($kind:ident : $t:ident in $list:expr))? :
            $name:expr, when $when:expr, slots $slots:expr, run $run:expr;
    )*) => {
        /// The stages (see `stages!` in `wavefront/mod.rs`, which lists them).
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Stage { $($(#[$doc])* $(#[cfg($cfg)])? $v $(($t))?,)* }

        /// The table's rows, in order.
        enum Row { $($(#[cfg($cfg)])? $v,)* }

        /// Statistics slots per row.
        const WIDTHS: &[usize] = &[$($(#[cfg($cfg)])? stages!(@width $($t)?)),*];

        /// Stages per row.
        const COUNTS: &[usize] = &[$($(#[cfg($cfg)])? 1 $(- 1 + $list.len())?),*];

        /// The sum of `a[..n]`.
        const fn sum(a: &[usize], n: usize) -> usize {
            let (mut s, mut k) = (0, 0);
            while k < n {
                s += a[k];
                k += 1;
            }
            s
        }

        impl Stage {
            /// Slots in per-stage arrays ([`Stage::index`]); some may stay unused.
            pub const SLOTS: usize = sum(WIDTHS, WIDTHS.len());

            /// All stages in pipeline order.
            pub const ALL: [Stage; sum(COUNTS, COUNTS.len())] = {
                let mut all = [$first; sum(COUNTS, COUNTS.len())];
                let mut n = 0;
                $($(#[cfg($cfg)])? stages!(@push all n $v $(($list))?);)*
                assert!(n == all.len(), "every stage in its place");
                all
            };

            /// Where the stage's figures are in [`Stats`]' arrays.
            pub const fn index(self) -> usize {
                match self {
                    $($(#[cfg($cfg)])? Stage::$v $(($kind))? => sum(WIDTHS, Row::$v as usize) $(+ $kind as usize)?,)*
                }
            }

            /// The stage's name (also its tracing span's).
            pub const fn name(self) -> &'static str {
                match self {
                    $($(#[cfg($cfg)])? Stage::$v $(($kind))? => $name,)*
                }
            }

            /// Whether a tile set up as `setup` runs the stage.
            fn runs(self, setup: &Setup) -> bool {
                match self {
                    $($(#[cfg($cfg)])? Stage::$v $(($kind))? => when(setup, $when),)*
                }
            }
        }

        impl TileWork<'_> {
            /// The path slots of the items (rays or paths) `stage` would take from the queues
            /// now, one per item.
            pub(super) fn slots<'q>(&self, stage: Stage, q: &'q Queues) -> &'q [u32] {
                match stage {
                    $($(#[cfg($cfg)])? Stage::$v $(($kind))? => slots(self, q, $slots),)*
                }
            }

            /// Runs one stage.
            pub(super) fn stage(&mut self, stage: Stage, p: &mut Paths, q: &mut Queues) {
                match stage {
                    $($(#[cfg($cfg)])? Stage::$v $(($kind))? => run(self, p, q, $run),)*
                }
            }
        }
    };
    (@push $all:ident $n:ident $v:ident) => {
        $all[$n] = Stage::$v;
        $n += 1;
    };
    (@push $all:ident $n:ident $v:ident ($list:expr)) => {
        let list = $list;
        let mut k = 0;
        while k < list.len() {
            $all[$n] = Stage::$v(list[k]);
            ($n, k) = ($n + 1, k + 1);
        }
    };
    ($($rows:tt)*) => { stages!(@gen [stages!(@first $($rows)*)] $($rows)*); };
}

stages! {
    /// New camera rays.
    GenerateCameraRays: "generate_camera_rays", when |_| true,
        slots |w, q| &q.free[q.free.len() - w.fresh(q)..], run |w, p, q| w.generate_camera_rays(p, q);
    /// Closest-hit traversal.
    IntersectClosest: "intersect_closest", when |_| true,
        slots |_, q| &q.active, run |w, p, q| stages::intersect_closest(w.scene, p, q);
    /// The denoiser's guides.
    RecordGuides: "record_guides", when |s| s.guides,
        slots |_, q| &q.active, run |w, p, q| stages::record_guides(w.scene, p, q);
    /// Background for rays that left.
    HandleEscaped: "handle_escaped", when |_| true,
        slots |_, q| &q.escaped, run |w, p, q| stages::handle_escaped(w.scene, p, q);
    /// Emitter hits.
    HandleEmissive: "handle_emissive", when |_| true,
        slots |_, q| &q.emissive, run |w, p, q| stages::handle_emissive(w.scene, p, q);
    /// Scattering in media.
    ShadeMedium: "shade_medium", when |_| true,
        slots |_, q| &q.medium, run |w, p, q| stages::shade_medium(w.scene, p, q);
    /// The shading loop of one material kind (not an emitter).
    Shade(kind: MaterialKind in SHADED_KINDS): kind.stage_name(), when |s| s.kinds.contains(&kind),
        slots |_, q| &q.shade[kind as usize], run |w, p, q| shading::shade(w.scene, p, q, kind);
    /// Occlusion tests.
    TraceShadowRays: "trace_shadow_rays", when |_| true,
        slots |_, q| &q.shadow.slot, run |w, p, q| stages::trace_shadow_rays(w.scene, p, q);
    /// A stage that exists to test this table (see `test_stage`).
    @cfg(feature = "test-stage")
    TestExposure: "test_exposure", when |_| true,
        slots |_, q| &q.finished, run |_, p, q| test_stage::expose(p, q);
    /// Finished paths into the film.
    AccumulateFilm: "accumulate_film", when |_| true,
        slots |_, q| &q.finished, run |w, p, q| w.accumulate_film(p, q);
}

/// How many material kinds have a shading loop.
const SHADED_COUNT: usize = {
    let (mut n, mut k) = (0, 0);
    while k < MaterialKind::COUNT {
        n += !matches!(MaterialKind::ALL[k].shading(), Shading::Emitter) as usize;
        k += 1;
    }
    n
};

/// The material kinds that have a shading loop (every kind but the emitters), in registry
/// order.
const SHADED_KINDS: [MaterialKind; SHADED_COUNT] = {
    let mut kinds = [MaterialKind::ALL[0]; SHADED_COUNT];
    let (mut n, mut k) = (0, 0);
    while k < MaterialKind::COUNT {
        if !matches!(MaterialKind::ALL[k].shading(), Shading::Emitter) {
            kinds[n] = MaterialKind::ALL[k];
            n += 1;
        }
        k += 1;
    }
    kinds
};

/// What decides which stages a tile runs: whether the denoiser's guides are asked for, and the
/// material kinds with a shading loop that the scene uses.
struct Setup {
    guides: bool,
    kinds: Vec<MaterialKind>,
}

/// Calls a table row's `when` (typing its closure).
#[inline(always)]
fn when(setup: &Setup, f: impl FnOnce(&Setup) -> bool) -> bool {
    f(setup)
}

/// Calls a table row's `slots` (typing its closure).
#[inline(always)]
fn slots<'a, 'q>(
    w: &TileWork<'a>,
    q: &'q Queues,
    f: impl FnOnce(&TileWork<'a>, &'q Queues) -> &'q [u32],
) -> &'q [u32] {
    f(w, q)
}

/// Calls a table row's `run` (typing its closure).
#[inline(always)]
fn run<'a>(
    w: &mut TileWork<'a>,
    p: &mut Paths,
    q: &mut Queues,
    f: impl FnOnce(&mut TileWork<'a>, &mut Paths, &mut Queues),
) {
    f(w, p, q)
}

/// The stages a tile runs, in order: those whose `when` holds for a tile of `scene`, with the
/// denoiser's `guides` if asked for.
fn pipeline(scene: &RenderScene, guides: bool) -> Vec<Stage> {
    let setup = Setup { guides, kinds: material_kinds(scene) };
    Stage::ALL.into_iter().filter(|s| s.runs(&setup)).collect()
}

/// Per-stage time and item counts, summed over workers.
#[derive(Clone, Debug, Default)]
pub struct Stats {
    /// Time spent in each stage (summed over threads), indexed by [`Stage::index`]; zero
    /// unless [`Options::timing`] (or a trace) asked for it.
    pub time: [Duration; Stage::SLOTS],
    /// Items (rays or paths) each stage consumed.
    pub items: [u64; Stage::SLOTS],
    /// Stage invocations with a non-empty queue.
    pub calls: [u64; Stage::SLOTS],
    /// Wavefront iterations.
    pub iterations: u64,
    /// Sum over iterations of the fraction of slots that held a live path.
    pub occupancy_sum: f64,
    /// Samples (paths) completed.
    pub paths: u64,
    /// Time the shading stages spent on each material id (their time shared out evenly among
    /// the paths they shaded), only with [`Options::costs`].
    pub material_time: Vec<Duration>,
    /// Time the shadow rays aimed at each entry of the scene's light table took (the occlusion
    /// stage's time shared out evenly among its rays), only with [`Options::costs`]. Sampling
    /// a light is part of the shading stages' time.
    pub light_time: Vec<Duration>,
}

impl Stats {
    /// The sums of two sets of statistics.
    pub fn merge(mut self, o: Stats) -> Stats {
        for k in 0..Stage::SLOTS {
            self.time[k] += o.time[k];
            self.items[k] += o.items[k];
            self.calls[k] += o.calls[k];
        }
        self.iterations += o.iterations;
        self.occupancy_sum += o.occupancy_sum;
        self.paths += o.paths;
        add_up(&mut self.material_time, o.material_time);
        add_up(&mut self.light_time, o.light_time);
        self
    }
}

/// Renders the image; `progress(done, total)` is called after each tile.
pub fn render(scene: &RenderScene, opts: Options, progress: &(dyn Fn(usize, usize) + Sync)) -> (Film, Stats) {
    render_samples(scene, opts, 0..scene.settings.spp, progress)
}

/// Renders the samples `samples` (indices into the scene's `spp` per pixel) of every pixel:
/// films of disjoint ranges merge into the film of their union, bit for bit.
pub fn render_samples(
    scene: &RenderScene,
    opts: Options,
    samples: Range<u32>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Film, Stats) {
    let (film, stats, _) = render_training(scene, Options { train: None, ..opts }, samples, progress);
    (film, stats)
}

/// [`render_samples`], and with [`Options::train`] what the paths recorded at their Lambertian
/// vertices for path guiding to learn from, tile by tile in the window's order and path by path
/// in the order they ended (the same records whatever the thread count).
pub fn render_training(
    scene: &RenderScene,
    opts: Options,
    samples: Range<u32>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Film, Stats, Vec<Record>) {
    let s = scene.settings;
    let _span =
        tracing::info_span!("wavefront_render", width = s.width, height = s.height, spp = s.spp).entered();
    let batch = opts.batch.max(1);
    let mut film = Film::new(s.window.w, s.window.h);
    film.spp = samples.len() as u32;
    if let Some(plan) = &scene.light_paths {
        film.light = Some(crate::light_tracer::trace(scene, plan, samples.clone()));
    }
    let run = |(paths, queues): &mut (Paths, Queues), tile: &Tile, splat: Option<(Splat, PixelWindow)>| {
        let _span =
            tracing::trace_span!("tile", x0 = tile.x0, y0 = tile.y0, samples = samples.len()).entered();
        let tracing = tracing::enabled!(target: "pathwave::stage", tracing::Level::TRACE);
        let clock = opts.timing || opts.costs || tracing;
        let out = render_tile(scene, tile, samples.clone(), splat, opts, clock, paths, queues);
        if tracing {
            trace_tile(&out.stats, batch);
        }
        out
    };
    let init = || (Paths::with_slots(batch), Queues::default());
    let results = match s.filter.splat() {
        Some(filter) => tile::splat_tiles(
            &s.window,
            (s.width, s.height),
            s.filter.margin(),
            &mut film.pixels,
            progress,
            init,
            |state, tile, rect| {
                let out = run(state, tile, Some((filter, *rect)));
                (out.film.into_pixels(), (out.guides, out.charges, out.stats, out.records))
            },
            PixelSums::add,
        ),
        None => tile::render_tiles(&s.window, &mut film.pixels, progress, init, |state, tile, mut rows| {
            let out = run(state, tile, None);
            rows.copy_from(&out.film.into_pixels(), |a| PixelSums::from(a));
            (out.guides, out.charges, out.stats, out.records)
        }),
    };
    let n = s.window.len();
    let mut guides = opts.guides.then(|| Aovs {
        width: s.window.w,
        height: s.window.h,
        albedo: vec![Vec3::ZERO; n],
        normal: vec![Vec3::ZERO; n],
        emission: vec![Vec3::ZERO; n],
    });
    let per_sample = 1.0 / samples.len().max(1) as f32;
    let mut stats = Stats::default();
    let mut charges = Vec::new();
    let mut records = Vec::with_capacity(results.iter().map(|(_, r)| r.3.len()).sum());
    for (tile, (tile_guides, tile_charges, tile_stats, tile_records)) in results {
        records.extend(tile_records);
        if let (Some(g), Some(sums)) = (&mut guides, &tile_guides) {
            for (i, k) in tile.window_indices(&s.window) {
                let [a, n, e] = sums[i];
                (g.albedo[k], g.normal[k], g.emission[k]) = (a * per_sample, n * per_sample, e * per_sample);
            }
        }
        charges.extend(tile_charges.map(|c| (tile, c)));
        stats = stats.merge(tile_stats);
    }
    film.guides = guides;
    if opts.costs {
        // Each stage's mean time per item over the render, in CPU time.
        let cpu: f64 = charges.iter().map(|(_, c)| c.cpu.as_secs_f64()).sum();
        let wall: f64 = stats.time.iter().map(Duration::as_secs_f64).sum();
        let scale = if wall > 0.0 { cpu / wall } else { 0.0 };
        let per_item: Vec<f64> = (0..Stage::SLOTS)
            .map(|k| match stats.items[k] {
                0 => 0.0,
                items => stats.time[k].as_secs_f64() * scale / items as f64,
            })
            .collect();
        let mut costs = PixelCosts::new(n);
        for (tile, c) in charges {
            let tile_costs = c.settle(&per_item, &mut stats);
            for (i, k) in tile.window_indices(&s.window) {
                costs.set(k, &tile_costs, i);
            }
        }
        film.costs = Some(costs);
    }
    (film, stats, records)
}

/// Adds `b` to `a` entry by entry, `a` lengthened as needed.
fn add_up(a: &mut Vec<Duration>, b: Vec<Duration>) {
    if a.len() < b.len() {
        a.resize(b.len(), Duration::ZERO);
    }
    a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
}

/// Reports a tile's stages to the trace: each stage's time summed over the tile's iterations,
/// laid out in pipeline order from the tile's start (target `pathwave::stage`, see the CLI's
/// `trace` module), with its items and calls; then the tile's counters (target
/// `pathwave::counter`): mean queue occupancy, rays per second and paths in flight.
fn trace_tile(st: &Stats, batch: usize) {
    let total: f64 = st.time.iter().map(Duration::as_secs_f64).sum::<f64>() * 1e6;
    let mut ago = total;
    for stage in Stage::ALL {
        let k = stage.index();
        if st.calls[k] == 0 {
            continue;
        }
        let dur = st.time[k].as_secs_f64() * 1e6;
        tracing::trace!(
            target: "pathwave::stage",
            name = stage.name(),
            ago_us = ago,
            dur_us = dur,
            items = st.items[k],
            calls = st.calls[k]
        );
        ago -= dur;
    }
    let occupancy = st.occupancy_sum / st.iterations.max(1) as f64;
    let rays = st.items[Stage::IntersectClosest.index()] + st.items[Stage::TraceShadowRays.index()];
    let counter = |name: &str, value: f64| tracing::trace!(target: "pathwave::counter", name, value);
    counter("queue occupancy %", 100.0 * occupancy);
    counter("paths in flight", occupancy * batch as f64);
    counter("Mrays/s (one thread)", rays as f64 / total.max(1e-9));
}

/// Runs the wavefront over samples `samples` of every pixel of one tile (timing the stages if
/// `clock`).
#[expect(clippy::too_many_arguments, reason = "the tile's work, and where it runs")]
fn render_tile(
    scene: &RenderScene,
    tile: &Tile,
    samples: Range<u32>,
    splat: Option<(Splat, PixelWindow)>,
    opts: Options,
    clock: bool,
    p: &mut Paths,
    q: &mut Queues,
) -> TileResult {
    let mut work = TileWork::new(scene, tile, samples, splat, opts.guides, opts.costs, opts.train);
    work.run(opts.batch.max(1), clock, p, q, &mut |_, _, _, _, _| {});
    work.result()
}

/// What one tile's worker hands back: the pixels' sums, the guides' sums (albedo, normal,
/// emission) and what its pixels cost when asked for, and statistics.
struct TileResult {
    film: TileFilm,
    guides: Option<Vec<[Vec3; 3]>>,
    charges: Option<tile_work::Charges>,
    stats: Stats,
    records: Vec<Record>,
}

/// One stage's input as the wavefront met it: the paths and queues of one tile just before
/// that stage ran, in one iteration. For benchmarks of each stage on a fixed queue
/// (`benches/core.rs`): [`Self::run`] runs the stage on them, so run it on a clone (which
/// has room in its queues, as a running tile's have).
pub struct StageInput<'a> {
    /// The stage.
    pub stage: Stage,
    /// Items (rays or paths) it takes.
    pub items: usize,
    work: TileWork<'a>,
    paths: Paths,
    queues: Queues,
}

impl Clone for StageInput<'_> {
    fn clone(&self) -> Self {
        let mut queues = self.queues.clone();
        queues.reserve(self.paths.dir.len());
        Self {
            stage: self.stage,
            items: self.items,
            work: self.work.clone(),
            paths: self.paths.clone(),
            queues,
        }
    }
}

impl StageInput<'_> {
    /// Runs the stage on its input (as the wavefront would have, same bits).
    pub fn run(&mut self) {
        self.work.stage(self.stage, &mut self.paths, &mut self.queues);
    }

    /// The items `stage` would take from these queues now: after [`Self::run`], what the
    /// stages after this one get from it.
    pub fn items_of(&self, stage: Stage) -> usize {
        self.work.slots(stage, &self.queues).len()
    }
}

/// The input of every stage that has work in iteration `iteration` of tile `tile` (row-major
/// in the render window) with `opts`' batch size and guides, in pipeline order; empty past the
/// tile's last iteration.
pub fn capture_stages<'a>(
    scene: &'a RenderScene,
    opts: Options,
    tile: u32,
    iteration: u64,
) -> Vec<StageInput<'a>> {
    let s = scene.settings;
    let tile = Tile::in_window(tile, &s.window);
    let batch = opts.batch.max(1);
    let (mut p, mut q) = (Paths::with_slots(batch), Queues::default());
    let splat = s.filter.splat().map(|f| (f, tile.reach(s.filter.margin(), &s.window)));
    let mut work = TileWork::new(scene, &tile, 0..s.spp, splat, opts.guides, opts.costs, opts.train);
    let mut out = Vec::new();
    work.run(batch, false, &mut p, &mut q, &mut |i, work, stage, p, q| {
        if i == iteration {
            let (work, items) = (work.clone(), work.slots(stage, q).len());
            out.push(StageInput { stage, items, work, paths: p.clone(), queues: q.clone() });
        }
    });
    out
}

/// The material kinds that have a shading loop and that some primitive uses (or a wrapper that
/// one uses names), in registry order: queues of kinds the scene does not use (even if it
/// defines such materials) are never visited.
pub fn material_kinds(scene: &RenderScene) -> Vec<MaterialKind> {
    let mut ids = vec![false; scene.materials.len()];
    for &m in scene.geometry.material.iter().chain(scene.instances.list.iter().map(|i| &i.material)) {
        ids[m as usize] = true;
    }
    scene.wrappers.mark_wrapped(&mut ids);
    let mut used = [false; MaterialKind::COUNT];
    for (id, _) in ids.iter().enumerate().filter(|(_, u)| **u) {
        used[scene.materials[id].kind() as usize] = true;
    }
    MaterialKind::ALL.into_iter().filter(|&k| used[k as usize] && k.shading() != Shading::Emitter).collect()
}
