//! Structure-of-arrays storage for the paths in flight and the queues between stages. Paths
//! live in slots; queues hold slot indices (or, for shadow rays, the rays themselves).

#![cfg_attr(
    target_arch = "x86_64",
    expect(unsafe_code, reason = "AVX-512 compress-stores that append picked lanes to the queues")
)]

use crate::aov::Guide;
use crate::guided::Trail;
use crate::lambert_vertex::LANES;
use crate::path::PathState;
use crate::sampler::{Sampler, SamplerLanes};
use glam::{Vec3, Vec3A};
use pathwave_engine::accel::flat::RayStream;
use pathwave_engine::accel::geometry::Hit;
use pathwave_engine::accel::queue::ClosestQuery;
use pathwave_engine::material::MaterialKind;
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::SamplerKind;

/// Paths in flight, one slot each, every field its own array.
#[derive(Clone, Default)]
pub struct Paths {
    /// Next ray to trace (for paths in the medium queue, `origin` is the scattering point).
    pub origin: Vec<Vec3A>,
    /// Its direction (unit).
    pub dir: Vec<Vec3A>,
    /// Its time.
    pub time: Vec<f32>,
    /// Radiance gathered.
    pub l: Vec<Vec3>,
    /// Throughput.
    pub beta: Vec<Vec3>,
    /// Squared IOR ratios crossed.
    pub eta_scale: Vec<f32>,
    /// Last scattering was a delta lobe.
    pub delta: Vec<bool>,
    /// Last scattering point.
    pub prev_p: Vec<Vec3A>,
    /// Its shading normal (zero in a medium).
    pub prev_n: Vec<Vec3A>,
    /// Last BSDF pdf.
    pub prev_pdf: Vec<f32>,
    /// Vertices so far (bounces and null crossings).
    pub depth: Vec<u32>,
    /// Null crossings so far.
    pub crossings: Vec<u32>,
    /// The path is a caustic's so far, for light tracing ([`PathState::caustic`]).
    pub caustic: Vec<bool>,
    /// Its punctual light samples here are the light tracer's ([`PathState::traced_here`]).
    pub traced_here: Vec<bool>,
    /// Spectral MIS ratios in coloured media (see [`crate::path::chromatic_flight`]).
    pub ratio: Vec<Vec3>,
    /// Random stream.
    pub sampler: Vec<Sampler>,
    /// Pixel (index within the worker's tile).
    pub pixel: Vec<u32>,
    /// Where in its pixel the sample lies, in [0, 1)^2 (written and read only where the film
    /// splats: `PixelFilter::splats`).
    pub within: Vec<[f32; 2]>,
    /// Closest hit of the last intersection.
    pub hit: Vec<Hit>,
    /// How far the next ray reaches: the camera ray's far clip distance until its first
    /// intersection, then infinity (written and read only when the camera has a far clip
    /// plane).
    pub far: Vec<f32>,
    /// Denoiser guides of the path's sample (only with [`super::Options::guides`]).
    pub guide: Vec<Guide>,
    /// The phase function's asymmetry where the path scatters in a medium, from free-flight
    /// sampling to `shade_medium` (written and read only in scenes with media).
    pub phase_g: Vec<f32>,
    /// The Lambertian vertices of training paths (only with [`super::Options::train`]; empty
    /// otherwise).
    pub trail: Vec<Trail>,
}

impl Paths {
    /// Storage for `n` slots.
    pub fn with_slots(n: usize) -> Self {
        let hit0 = Hit {
            t: 0.0,
            prim: 0,
            material: 0,
            surface: pathwave_engine::shape::SurfacePoint {
                p: Vec3A::ZERO,
                n: Vec3A::Z,
                ns: Vec3A::Z,
                ns_base: Vec3A::Z,
                uv: glam::Vec2::ZERO,
                err: 0.0,
                on: pathwave_engine::shape::MeshPoint::NONE,
            },
        };
        Self {
            origin: vec![Vec3A::ZERO; n],
            dir: vec![Vec3A::Z; n],
            time: vec![0.0; n],
            l: vec![Vec3::ZERO; n],
            beta: vec![Vec3::ONE; n],
            eta_scale: vec![1.0; n],
            delta: vec![true; n],
            prev_p: vec![Vec3A::ZERO; n],
            prev_n: vec![Vec3A::ZERO; n],
            prev_pdf: vec![0.0; n],
            depth: vec![0; n],
            crossings: vec![0; n],
            caustic: vec![false; n],
            traced_here: vec![false; n],
            ratio: vec![Vec3::ONE; n],
            sampler: vec![Sampler::new(SamplerKind::Sobol, 0, 0, 0, 1); n],
            pixel: vec![0; n],
            within: vec![[0.0; 2]; n],
            hit: vec![hit0; n],
            far: vec![f32::INFINITY; n],
            guide: vec![Guide::NEW; n],
            phase_g: vec![0.0; n],
            trail: Vec::new(),
        }
    }

    /// The ray of slot `i`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        Ray { origin: self.origin[i], dir: self.dir[i], time: self.time[i] }
    }

    /// Sets the ray of slot `i`.
    #[inline]
    pub fn set_ray(&mut self, i: usize, r: Ray) {
        self.origin[i] = r.origin;
        self.dir[i] = r.dir;
        self.time[i] = r.time;
    }

    /// The samplers and depths of the paths in `slots` (at most `N`), lane by lane; a short
    /// group repeats its last path in the remaining lanes.
    #[inline]
    pub fn sampler_lanes<const N: usize>(&self, slots: &[u32]) -> (SamplerLanes<N>, [u32; N]) {
        let last = slots[slots.len() - 1] as usize;
        let (mut samplers, mut depths) = ([self.sampler[last]; N], [self.depth[last]; N]);
        for (l, &i) in slots.iter().enumerate().take(N) {
            (samplers[l], depths[l]) = (self.sampler[i as usize], self.depth[i as usize]);
        }
        (SamplerLanes::from(&samplers), depths)
    }

    /// Gathers the path state of slot `i`.
    #[inline]
    pub fn state(&self, i: usize) -> PathState {
        PathState {
            l: self.l[i],
            beta: self.beta[i],
            eta_scale: self.eta_scale[i],
            delta: self.delta[i],
            prev_p: self.prev_p[i],
            prev_n: self.prev_n[i],
            prev_pdf: self.prev_pdf[i],
            depth: self.depth[i],
            crossings: self.crossings[i],
            caustic: self.caustic[i],
            traced_here: self.traced_here[i],
        }
    }

    /// Scatters the path state of slot `i` back. Always inlined: `generate_camera_rays` once
    /// called it out of line, a call per new path (1.2% more instructions on cornell-diffuse).
    #[inline(always)]
    pub fn set_state(&mut self, i: usize, s: &PathState) {
        self.l[i] = s.l;
        self.beta[i] = s.beta;
        self.eta_scale[i] = s.eta_scale;
        self.delta[i] = s.delta;
        self.prev_p[i] = s.prev_p;
        self.prev_n[i] = s.prev_n;
        self.prev_pdf[i] = s.prev_pdf;
        self.depth[i] = s.depth;
        self.crossings[i] = s.crossings;
        self.caustic[i] = s.caustic;
        self.traced_here[i] = s.traced_here;
    }
}

/// Shadow rays waiting for an occlusion test, as parallel arrays.
#[derive(Clone, Default)]
pub struct ShadowQueue {
    /// The rays (t = 1 at the light point).
    pub rays: RayStream,
    /// Their times.
    pub time: Vec<f32>,
    /// Contribution if unoccluded.
    pub contribution: Vec<Vec3>,
    /// Slot of the path it belongs to.
    pub slot: Vec<u32>,
    /// Occlusion results.
    pub occluded: Vec<bool>,
}

impl ShadowQueue {
    /// Appends a shadow ray of path `slot`.
    #[inline]
    pub fn push(&mut self, slot: u32, ray: &Ray, contribution: Vec3) {
        self.rays.push(ray.origin.to_array(), ray.dir.to_array());
        self.time.push(ray.time);
        self.contribution.push(contribution);
        self.slot.push(slot);
    }

    /// Appends the shadow rays of lanes `pick` (in order) of a group of paths: lane `l`
    /// belongs to path `slot[l]`, leaves at time `time[l]` from `o` along `d` (one array per
    /// coordinate) and adds `contribution` if unoccluded. With AVX-512 each array takes its
    /// lanes in one compress and one store (cornell-diffuse's Lambertian stage 6.8% faster on
    /// one thread, 1.3% on two); otherwise one capacity check per array, not one per ray.
    #[inline]
    pub fn extend_lanes(
        &mut self,
        pick: &[usize],
        slot: &[u32],
        time: &[f32; LANES],
        o: &[[f32; LANES]; 3],
        d: &[[f32; LANES]; 3],
        contribution: &[[f32; LANES]; 3],
    ) {
        let c = contribution;
        self.contribution.extend(pick.iter().map(|&l| Vec3::new(c[0][l], c[1][l], c[2][l])));
        #[cfg(target_arch = "x86_64")]
        if pathwave_engine::simd::avx512() {
            let mask = pick.iter().fold(0u16, |m, &l| m | 1 << l);
            let mut slots = [0u32; LANES];
            slots[..slot.len()].copy_from_slice(slot);
            // SAFETY: `avx512` checked at run time that the CPU has AVX-512 F.
            unsafe {
                for a in 0..3 {
                    compress::append(&mut self.rays.o[a], mask, &o[a]);
                    compress::append(&mut self.rays.d[a], mask, &d[a]);
                }
                compress::append(&mut self.time, mask, time);
                compress::append_u32(&mut self.slot, mask, &slots);
            }
            return;
        }
        for a in 0..3 {
            self.rays.o[a].extend(pick.iter().map(|&l| o[a][l]));
            self.rays.d[a].extend(pick.iter().map(|&l| d[a][l]));
        }
        self.time.extend(pick.iter().map(|&l| time[l]));
        self.slot.extend(pick.iter().map(|&l| slot[l]));
    }

    /// Empties the queue, keeping its storage.
    pub fn clear(&mut self) {
        self.rays.clear();
        self.time.clear();
        self.contribution.clear();
        self.slot.clear();
    }

    /// Number of rays queued.
    pub fn len(&self) -> usize {
        self.slot.len()
    }

    /// Shadow ray `k`.
    #[inline]
    pub fn ray(&self, k: usize) -> Ray {
        let ([ox, oy, oz], [dx, dy, dz]) = (&self.rays.o, &self.rays.d);
        Ray {
            origin: Vec3A::new(ox[k], oy[k], oz[k]),
            dir: Vec3A::new(dx[k], dy[k], dz[k]),
            time: self.time[k],
        }
    }
}

/// What the closest-hit stage keeps between iterations: the engine's query over the active
/// rays and the paths' free-flight numbers.
#[derive(Clone, Default)]
pub struct HitStream {
    /// The closest-hit query of the active queue's rays.
    pub query: ClosestQuery,
    /// The paths' free-flight numbers (scenes with media).
    pub u_medium: Vec<f32>,
}

/// The slot-index queues between stages.
#[derive(Clone, Default)]
pub struct Queues {
    /// Paths with a ray to trace this iteration.
    pub active: Vec<u32>,
    /// Paths with a ray for the next iteration.
    pub next: Vec<u32>,
    /// Rays that left the scene.
    pub escaped: Vec<u32>,
    /// Hits on emitters.
    pub emissive: Vec<u32>,
    /// Hits by material kind (indexed by [`MaterialKind`]; emitters' stay empty).
    pub shade: [Vec<u32>; MaterialKind::COUNT],
    /// Rays that scattered in a medium before reaching a surface.
    pub medium: Vec<u32>,
    /// Paths that ended; their radiance goes to the film.
    pub finished: Vec<u32>,
    /// Free slots.
    pub free: Vec<u32>,
    /// Shadow rays.
    pub shadow: ShadowQueue,
    /// Scratch list of slots.
    pub scratch: Vec<u32>,
    /// Stream storage for closest-hit queries on flat geometry.
    pub stream: HitStream,
}

impl Queues {
    /// Room for `slots` entries in every queue, as the queues of a running tile have after
    /// their first iterations (a clone holds only what it copied: pushing to it would grow
    /// its storage).
    pub fn reserve(&mut self, slots: usize) {
        let room = |v: &mut Vec<u32>| v.reserve(slots.saturating_sub(v.len()));
        [&mut self.active, &mut self.next, &mut self.escaped, &mut self.emissive, &mut self.medium]
            .into_iter()
            .chain([&mut self.finished, &mut self.free, &mut self.scratch])
            .chain(self.shade.iter_mut())
            .chain([&mut self.shadow.slot])
            .for_each(room);
        let sh = &mut self.shadow;
        let floats = sh.rays.o.iter_mut().chain(sh.rays.d.iter_mut()).chain([&mut sh.time]);
        floats.for_each(|v| v.reserve(slots.saturating_sub(v.len())));
        self.stream.query.reserve(slots);
        sh.contribution.reserve(slots.saturating_sub(sh.contribution.len()));
        sh.occluded.reserve(slots.saturating_sub(sh.occluded.len()));
    }
}

/// Appends to a vector the lanes of a group that a bit mask picks, in order, by AVX-512's
/// compress (to a register, then one store: Zen 4 runs a compressing store to memory slowly).
/// `tests/isa.rs` renders with and without it for the same bits.
#[cfg(target_arch = "x86_64")]
mod compress {
    use super::LANES;
    use std::arch::x86_64::*;

    const _: () = assert!(LANES == 16, "one 512-bit vector per group");

    /// Appends the lanes of `src` whose bits are set in `mask`.
    /// SAFETY: the CPU must have AVX-512 F.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn append(v: &mut Vec<f32>, mask: u16, src: &[f32; LANES]) {
        v.reserve(LANES);
        let len = v.len();
        // SAFETY: `reserve` made room for `LANES` values after `len`; the store writes all of
        // them, the first `mask.count_ones()` being the lanes picked, which `set_len` keeps.
        unsafe {
            let packed = _mm512_maskz_compress_ps(mask, _mm512_loadu_ps(src.as_ptr()));
            _mm512_storeu_ps(v.as_mut_ptr().add(len), packed);
            v.set_len(len + mask.count_ones() as usize);
        }
    }

    /// [`append`] for 32-bit integers.
    /// SAFETY: the CPU must have AVX-512 F.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn append_u32(v: &mut Vec<u32>, mask: u16, src: &[u32; LANES]) {
        v.reserve(LANES);
        let len = v.len();
        // SAFETY: as in `append`.
        unsafe {
            let packed = _mm512_maskz_compress_epi32(mask, _mm512_loadu_si512(src.as_ptr().cast()));
            _mm512_storeu_si512(v.as_mut_ptr().add(len).cast(), packed);
            v.set_len(len + mask.count_ones() as usize);
        }
    }
}
