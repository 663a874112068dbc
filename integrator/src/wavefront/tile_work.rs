//! One tile's samples in progress ([`TileWork`]): the wavefront's iteration over the stages
//! (whose list, dispatch and item counts `stages!` in `wavefront/mod.rs` generates), and the two
//! stages that live here (camera rays and film accumulation) rather than in `stages`.

use super::queues::{Paths, Queues};
use super::{Stage, Stats};
use crate::aov::Guide;
use crate::film::{PixelAccumulator, clamp_sample};
use crate::lambert_vertex::LANES;
use crate::path;
use crate::sampler::{Sampler, SamplerLanes};
use crate::tile::Tile;
use glam::Vec3;
use pathwave_engine::camera::RayLanes;
use pathwave_engine::render_scene::RenderScene;
use std::ops::Range;
use std::time::Instant;

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
    pub(super) film: Vec<PixelAccumulator>,
    pub(super) guide_sums: Option<Vec<[Vec3; 3]>>,
    pub(super) stats: Stats,
    /// The stages each iteration runs, in order (`stages!` in `wavefront/mod.rs`): the
    /// scene's shading kinds only, guides only when asked for.
    pipeline: Vec<Stage>,
}

impl<'a> TileWork<'a> {
    pub(super) fn new(scene: &'a RenderScene, tile: &Tile, samples: Range<u32>, guides: bool) -> Self {
        let pixels = (tile.w * tile.h) as usize;
        let pipeline = super::pipeline(scene, guides);
        Self {
            scene,
            tile: *tile,
            work: pixels as u64 * samples.len() as u64,
            samples,
            next_sample: 0,
            film: vec![PixelAccumulator::default(); pixels],
            guide_sums: guides.then(|| vec![[Vec3::ZERO; 3]; pixels]),
            stats: Stats::default(),
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
        q.free.clear();
        q.free.extend((0..batch as u32).rev());
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
    }

    /// How many new paths `generate_camera_rays` would start now: a free slot each, while the
    /// tile has samples left.
    pub(super) fn fresh(&self, q: &Queues) -> usize {
        q.free.len().min((self.work - self.next_sample) as usize)
    }

    /// Runs `stage` if it has work (after `observe` has seen its input), recording its item
    /// count and, if `clock`, its time (traces get them once per tile, from [`trace_tile`]).
    #[inline]
    fn timed(
        &mut self,
        clock: bool,
        stage: Stage,
        p: &mut Paths,
        q: &mut Queues,
        observe: &mut dyn FnMut(&TileWork<'a>, Stage, &Paths, &Queues),
    ) {
        let items = self.items(stage, q);
        if items == 0 {
            return;
        }
        observe(self, stage, p, q);
        let k = stage.index();
        if clock {
            let start = Instant::now();
            self.stage(stage, p, q);
            self.stats.time[k] += start.elapsed();
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
            let rays = camera_rays(scene, &SamplerLanes::from(&samplers), &pixel);
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
                if far_clip {
                    p.far[s] = rays.tmax[l];
                }
                // Only what the denoiser reads is written (52 bytes per path otherwise).
                if guides {
                    p.guide[s] = Guide::NEW;
                }
                q.active.push(slot);
            }
            self.next_sample += m as u64;
        }
    }

    /// `accumulate_film`: finished paths add their radiance (and guides) to their pixels and
    /// free their slots.
    pub(super) fn accumulate_film(&mut self, p: &Paths, q: &mut Queues) {
        let clamp = self.scene.settings.clamp;
        for &i in &q.finished {
            self.film[p.pixel[i as usize] as usize].add(clamp_sample(p.l[i as usize], clamp));
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
        q.free.extend_from_slice(&q.finished);
    }
}

/// [`path::camera_rays`] for `LANES` samples, with AVX-512 where the CPU has it.
#[inline]
fn camera_rays(scene: &RenderScene, s: &SamplerLanes<LANES>, pixel: &[(u32, u32); LANES]) -> RayLanes<LANES> {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || path::camera_rays(scene, s, pixel),
    )
}
