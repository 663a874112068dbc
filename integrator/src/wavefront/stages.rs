//! The stages of one wavefront iteration but shading ([`super::shading`]). Each is a tight loop
//! over one queue; per-vertex math comes from [`crate::path`], so every sample equals the
//! reference path tracer's.

use super::queues::{Paths, Queues};
use crate::lambert_vertex;
use crate::path;
use glam::{Vec3, Vec3A};
use pathwave_engine::accel::geometry::Hit;
use pathwave_engine::lighting::light_paths::LightPaths;
use pathwave_engine::material::Shading;
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;

/// `intersect_closest`: traces every active ray; misses go to `escaped`, hits to the queue of
/// their material kind (the engine chooses how the rays are traced:
/// [`Aggregate::trace_closest`](pathwave_engine::accel::queue::Aggregate::trace_closest)). With
/// a far clip plane, a camera ray's hit at or beyond its reach is a miss (as the reference's
/// `intersect(ray, tmax)`, which sees `t < tmax`).
pub fn intersect_closest(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    if scene.features.media {
        free_flight_numbers(p, &q.active, &mut q.stream.u_medium);
    }
    let surfaces = scene.aggregate();
    let active = &q.active;
    surfaces.trace_closest(&mut q.stream.query, active.len(), |k| {
        let i = active[k] as usize;
        (p.origin[i], p.dir[i])
    });
    if scene.features.wrappers {
        return bin_through_wrappers(scene, p, q);
    }
    let far_clip = scene.camera.has_far_clip();
    for k in 0..q.active.len() {
        let i = q.active[k] as usize;
        let mut hit = surfaces.closest_hit(&q.stream.query, k, &p.ray(i));
        if far_clip {
            let far = std::mem::replace(&mut p.far[i], f32::INFINITY);
            hit = hit.filter(|h| h.t < far);
        }
        bin::<false>(scene, p, q, k, hit);
    }
}

/// [`intersect_closest`]'s binning in scenes with wrappers, which [`bin`] resolves. Its own loop,
/// out of line: with the resolving branch in the one loop, cornell-diffuse ran 10% slower
/// (the same instructions; the hit went through memory).
#[inline(never)]
fn bin_through_wrappers(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    let surfaces = scene.aggregate();
    let far_clip = scene.camera.has_far_clip();
    for k in 0..q.active.len() {
        let i = q.active[k] as usize;
        let mut hit = surfaces.closest_hit(&q.stream.query, k, &p.ray(i));
        if far_clip {
            let far = std::mem::replace(&mut p.far[i], f32::INFINITY);
            hit = hit.filter(|h| h.t < far);
        }
        bin::<true>(scene, p, q, k, hit);
    }
}

/// The free-flight numbers of the paths `active` ([`path::medium_dim`] of each one's depth),
/// drawn [`LANES`](lambert_vertex::LANES) at a time across lanes: one by one they took a fifth
/// of cornell-smoke's time (`Sampler::get_1d`).
fn free_flight_numbers(p: &Paths, active: &[u32], u: &mut Vec<f32>) {
    use lambert_vertex::LANES;
    u.clear();
    for chunk in active.chunks(LANES) {
        let (samplers, depths) = p.sampler_lanes::<LANES>(chunk);
        let dims = depths.map(path::medium_dim);
        let numbers = pathwave_engine::simd::lanes(
            #[inline(always)]
            || crate::sampler::get_1d_lanes(&samplers, &dims),
        );
        u.extend_from_slice(&numbers[..chunk.len()]);
    }
}

/// Sends the path of `active[k]` to the medium queue if it scatters before the surface (scenes
/// with media), else to the escaped queue or, resolved through its wrappers if `WRAPPERS`
/// ([`resolve_wrapper`]), to its material's queue. Always inlined: as a call
/// it took the 80-byte hit through the stack, read back in wider pieces than it was written (no
/// store forwarding), and cornell-diffuse's closest hits ran 9% slower (benches/RESULTS.md).
#[inline(always)]
fn bin<const WRAPPERS: bool>(scene: &RenderScene, p: &mut Paths, q: &mut Queues, k: usize, hit: Option<Hit>) {
    let i = q.active[k];
    if scene.features.media
        && scatters_in_medium(
            scene,
            p,
            q,
            i,
            hit.as_ref().map_or(f32::INFINITY, |h| h.t),
            q.stream.u_medium[k],
        )
    {
        // The surface behind the medium (infinitely far when none), for `record_guides`.
        match hit {
            Some(h) => store_hit(&mut p.hit[i as usize], &h),
            None => p.hit[i as usize].t = f32::INFINITY,
        }
        return;
    }
    let Some(hit) = hit else {
        q.escaped.push(i);
        return;
    };
    let hit = match WRAPPERS {
        false => hit,
        true => match resolve_wrapper(scene, p, q, i, hit) {
            Some(resolved) => resolved,
            None => return,
        },
    };
    store_hit(&mut p.hit[i as usize], &hit);
    let kind = scene.materials[hit.material as usize].kind();
    match kind.shading() {
        Shading::Emitter => q.emissive.push(i),
        Shading::Diffuse | Shading::Sampled | Shading::Glossy => {
            // A surface that emits and reflects: `handle_emissive` adds its emission first
            // (with the last vertex's division for light tracing, then this one's).
            if scene.features.emitting_surfaces && scene.lights.emits(hit.material) {
                q.emissive.push(i);
            } else if let Some(lp) = &scene.light_paths {
                divide_for_light_paths(scene, lp, p, i as usize);
            }
            q.shade[kind as usize].push(i)
        }
    }
}

/// `*dst = *h` field by field: the hit is made on the stack piece by piece (a quad's `uv`
/// and `err` as an 8- and a 4-byte store), and a whole-struct copy read it back in 16- and
/// 32-byte pieces that no store forwards to. The patterns name every field, so that a field
/// added to either struct stops the build here.
#[inline(always)]
fn store_hit(dst: &mut Hit, h: &Hit) {
    let Hit { t, prim, material, surface } = h;
    let SurfacePoint { p, n, ns, ns_base, uv, err, on } = surface;
    (dst.t, dst.prim, dst.material) = (*t, *prim, *material);
    let d = &mut dst.surface;
    (d.p, d.n, d.ns, d.ns_base, d.uv, d.err, d.on) = (*p, *n, *ns, *ns_base, *uv, *err, *on);
}

/// [`path::divide_for_light_paths`] at the hit of path `i` (read from its slot: a reference to
/// `bin`'s own copy would keep that in memory, and the closest hits ran 20% slower), in scenes
/// where light tracing is on. Out of line: other scenes never call it.
#[inline(never)]
fn divide_for_light_paths(scene: &RenderScene, lp: &LightPaths, p: &mut Paths, i: usize) {
    let (mut st, hit) = (p.state(i), &p.hit[i]);
    let class = scene.with_material(hit.material, &hit.surface, |mat| lp.class(mat));
    path::divide_for_light_paths(&mut st, class, &hit.surface);
    (p.caustic[i], p.traced_here[i]) = (st.caustic, st.traced_here);
}

/// Resolves the wrapper path `i` met ([`path::resolve`]): the hit with the plain material that
/// shades it, or `None` (and the path queued for the next iteration) when it goes through a
/// mask's hole. Kept out of line: scenes without wrappers never call it.
#[inline(never)]
fn resolve_wrapper(scene: &RenderScene, p: &mut Paths, q: &mut Queues, i: u32, mut hit: Hit) -> Option<Hit> {
    let s = i as usize;
    let mut st = p.state(s);
    let Some(through) = path::resolve(scene, &mut st, &mut hit, p.dir[s], p.time[s], &p.sampler[s]) else {
        return Some(hit);
    };
    p.set_state(s, &st);
    p.set_ray(s, through);
    q.next.push(i);
    None
}

/// Free-flight sampling for path `i` up to the surface at `tmax` with the number `u`: true (and
/// the path queued for `shade_medium`) when it scatters first. Kept out of line: scenes without
/// media never call it.
#[inline(never)]
fn scatters_in_medium(scene: &RenderScene, p: &mut Paths, q: &mut Queues, i: u32, tmax: f32, u: f32) -> bool {
    let s = i as usize;
    let ray = p.ray(s);
    let sampler = &p.sampler[s];
    let u0 = || sampler.get_1d(path::medium_dim(0));
    let flight = path::Flight { l: &mut p.l[s], beta: &mut p.beta[s], ratio: &mut p.ratio[s] };
    let Some((at, g)) = path::sample_medium(scene, flight, &ray, tmax, u, p.depth[s], u0) else {
        return false;
    };
    // The path is now at the scattering point; `shade_medium` needs its direction and medium.
    (p.origin[s], p.phase_g[s]) = (at, g);
    q.medium.push(i);
    true
}

/// Queues path `i`'s shadow rays and its next ray, or ends the path.
#[inline]
pub(super) fn route(p: &mut Paths, q: &mut Queues, i: u32, shadows: path::Shadows, next: Option<Ray>) {
    for sh in shadows.iter() {
        q.shadow.push(i, &sh.ray, sh.contribution);
    }
    match next {
        Some(ray) => {
            p.set_ray(i as usize, ray);
            q.next.push(i);
        }
        None => q.finished.push(i),
    }
}

/// `record_guides` (only when the denoiser's guides are asked for): for the paths whose camera
/// ray has met only perfect mirrors and glass so far, the albedo and normal of what their ray
/// reached now, and at the first vertex the emission that `handle_escaped` and
/// `handle_emissive` are about to add (the same expression, so the same bits).
pub fn record_guides(scene: &RenderScene, p: &mut Paths, q: &Queues) {
    // Glass refracts in most paths and reflects in a few; the guides follow the refraction (as
    // the separate pass does): a path that came back off glass shows the glass.
    let queues = [&q.escaped, &q.emissive, &q.medium].into_iter().chain(&q.shade);
    for &i in queues.flatten() {
        let g = &mut p.guide[i as usize];
        if g.open && g.glass && p.dir[i as usize].dot(g.normal.into()) > 0.0 {
            let normal = g.normal;
            g.close(Vec3::ONE, normal);
        }
    }
    for &i in &q.escaped {
        let s = i as usize;
        let g = &mut p.guide[s];
        if g.open {
            let sky = scene.background.radiance(p.dir[s]);
            if p.depth[s] == 0 {
                g.emission = p.beta[s] * sky;
            }
            g.sky(sky);
        }
    }
    for &i in &q.emissive {
        let s = i as usize;
        if p.guide[s].open {
            let hit = p.hit[s];
            if p.depth[s] == 0 {
                let sp = &hit.surface;
                p.guide[s].emission = p.beta[s] * scene.emitted(hit.material, sp, sp.n.dot(-p.dir[s]));
            }
            // A surface that also reflects is in a shading queue, where the loop below sees it.
            let mat = scene.material_at(hit.material, &hit.surface);
            if mat.is_emissive() {
                p.guide[s].surface(&mat, facing(hit.surface.ns, p.dir[s]));
            }
        }
    }
    for queue in &q.shade {
        for &i in queue {
            let s = i as usize;
            if p.guide[s].open {
                let hit = p.hit[s];
                let m = scene.material_at(hit.material, &hit.surface);
                p.guide[s].surface(&m, facing(hit.surface.ns, p.dir[s]));
            }
        }
    }
    // Scattered in a medium: the guides show the surface behind it, or the sky, as the
    // separate pass does.
    for &i in &q.medium {
        let s = i as usize;
        if p.guide[s].open {
            let hit = p.hit[s];
            match hit.t.is_finite() {
                true => {
                    let m = scene.material_at(hit.material, &hit.surface);
                    p.guide[s].close(m.albedo(), facing(hit.surface.ns, p.dir[s]));
                }
                false => p.guide[s].sky(scene.background.radiance(p.dir[s])),
            }
        }
    }
}

/// The shading normal `ns` turned towards where the ray came from.
#[inline]
fn facing(ns: Vec3A, dir: Vec3A) -> Vec3 {
    (if ns.dot(dir) > 0.0 { -ns } else { ns }).into()
}

/// `handle_escaped`: adds the background; the paths end.
pub fn handle_escaped(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    for &i in &q.escaped {
        let s = i as usize;
        let mut st = p.state(s);
        path::escape(scene, &mut st, p.dir[s]);
        if !p.trail.is_empty() {
            p.trail[s].direct(p.depth[s], st.l - p.l[s]);
        }
        p.l[s] = st.l;
        q.finished.push(i);
    }
}

/// `handle_emissive`: adds MIS-weighted emission; the paths on emitters end (they do not
/// scatter), those on surfaces that also reflect go on in their material's shading queue.
pub fn handle_emissive(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    for &i in &q.emissive {
        let s = i as usize;
        let hit = p.hit[s];
        let mut st = p.state(s);
        path::emit(scene, &mut st, &hit, -p.dir[s], p.time[s]);
        if !p.trail.is_empty() {
            p.trail[s].direct(p.depth[s], st.l - p.l[s]);
        }
        p.l[s] = st.l;
        if scene.materials[hit.material as usize].is_emissive() {
            q.finished.push(i);
        } else if let Some(lp) = &scene.light_paths {
            divide_for_light_paths(scene, lp, p, s);
        }
    }
}

/// `shade_medium`: scattering in media: light sampling into the shadow queue, then phase
/// sampling into the next iteration's queue.
pub fn shade_medium(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    for k in 0..q.medium.len() {
        let (i, s) = (q.medium[k], q.medium[k] as usize);
        let mut st = p.state(s);
        if path::at_max_depth(scene, st.bounces()) {
            q.finished.push(i);
            continue;
        }
        let (shadow, next) = path::scatter_in_medium(
            scene,
            &mut st,
            p.origin[s],
            p.dir[s],
            p.phase_g[s],
            p.time[s],
            &p.sampler[s],
        );
        route(p, q, i, shadow, next);
        p.set_state(s, &st);
    }
    q.medium.clear();
}

/// `trace_shadow_rays`: occlusion tests (and transmittance through media); what gets through
/// is added to the paths.
pub fn trace_shadow_rays(scene: &RenderScene, p: &mut Paths, q: &mut Queues) {
    let sq = &mut q.shadow;
    let n = sq.len();
    // The first vertices' shadow rays, made from one pixel's camera rays, leave one spot for
    // one light.
    let first_vertex = |k: usize| p.depth[sq.slot[k] as usize] <= 1;
    scene.aggregate().trace_occluded(&sq.rays, &sq.time, first_vertex, &mut sq.occluded);
    if scene.features.null_surfaces {
        // Blocked rays may cross surfaces with a null lobe: look past them.
        for k in 0..n {
            if sq.occluded[k] {
                let tr = scene.null_transmittance(&sq.ray(k));
                if tr > 0.0 {
                    (sq.occluded[k], sq.contribution[k]) = (false, sq.contribution[k] * tr);
                }
            }
        }
    }
    if scene.features.media {
        for k in 0..n {
            if !sq.occluded[k] {
                let tr = path::media_transmittance(scene, &sq.ray(k));
                sq.contribution[k] *= tr;
            }
        }
    }
    for k in 0..n {
        if !sq.occluded[k] {
            p.l[sq.slot[k] as usize] += sq.contribution[k];
        }
    }
    if !p.trail.is_empty() {
        for k in (0..n).filter(|&k| !sq.occluded[k]) {
            let s = sq.slot[k] as usize;
            p.trail[s].direct(p.depth[s], sq.contribution[k]);
        }
    }
}
