//! The shading stages of one wavefront iteration: one loop per material kind's queue, its
//! per-vertex math from [`crate::path`] and the lane kernels ([`crate::lambert_vertex`],
//! [`crate::glossy_lanes`]), so every sample equals the reference path tracer's.

use super::queues::{Paths, Queues};
use super::stages::route;
use crate::delta_lanes::{DeltaInLanes, DeltaLanes, DeltaOutLanes};
use crate::glossy_lanes::{EvalLanes, GlossyLanes, Kernel};
use crate::lambert_vertex;
use crate::light_lanes;
use crate::path;
use pathwave_engine::material::dielectric::Dielectric;
use pathwave_engine::material::metal::Metal;
use pathwave_engine::material::metallic_roughness::MetallicRoughness;
use pathwave_engine::material::plastic::Plastic;
use pathwave_engine::material::principled::Principled;
use pathwave_engine::material::principled_thin::PrincipledThin;
use pathwave_engine::material::rough_conductor::RoughConductor;
use pathwave_engine::material::rough_dielectric::RoughDielectric;
use pathwave_engine::material::rough_plastic::RoughPlastic;
use pathwave_engine::material::thin_dielectric::ThinDielectric;
use pathwave_engine::material::{Material, MaterialKind, Reads, Shading};
use pathwave_engine::math::Ray;
use pathwave_engine::render_scene::RenderScene;

/// One shading loop for the hits of one material kind: kinds shaded as
/// [`Shading::Diffuse`] go through the Lambertian lane kernel (light sampling into the shadow
/// queue, BSDF sampling into the next iteration's queue); [`Shading::Sampled`] kinds only sample
/// their BSDF; [`Shading::Glossy`] kinds sample a light and their BSDF, rough conductors,
/// dielectrics and plastics, the principled BSDFs (thin too) and glTF's metallic-roughness
/// with the BSDF's work across lanes, the other kinds path by path.
pub fn shade(scene: &RenderScene, p: &mut Paths, q: &mut Queues, kind: MaterialKind) {
    let mut queue = std::mem::take(&mut q.shade[kind as usize]);
    match kind.shading() {
        Shading::Diffuse => shade_lambertian_lanes(scene, p, q, &queue),
        Shading::Sampled => match kind {
            MaterialKind::Dielectric => shade_sampled::<Dielectric>(scene, p, q, &queue),
            MaterialKind::ThinDielectric => shade_sampled::<ThinDielectric>(scene, p, q, &queue),
            _ => shade_sampled::<NoLanes>(scene, p, q, &queue),
        },
        Shading::Glossy => match kind {
            MaterialKind::Metal => shade_in_lanes::<Metal>(scene, p, q, &queue),
            MaterialKind::RoughConductor => shade_in_lanes::<RoughConductor>(scene, p, q, &queue),
            MaterialKind::RoughDielectric => shade_in_lanes::<RoughDielectric>(scene, p, q, &queue),
            MaterialKind::Plastic => shade_in_lanes::<Plastic>(scene, p, q, &queue),
            MaterialKind::RoughPlastic => shade_in_lanes::<RoughPlastic>(scene, p, q, &queue),
            MaterialKind::Principled => shade_in_lanes::<Principled>(scene, p, q, &queue),
            MaterialKind::PrincipledThin => shade_in_lanes::<PrincipledThin>(scene, p, q, &queue),
            MaterialKind::MetallicRoughness => shade_in_lanes::<MetallicRoughness>(scene, p, q, &queue),
            _ => shade_glossy(scene, p, q, &queue),
        },
        Shading::Emitter => unreachable!("emitters have no shading queue"),
    }
    queue.clear();
    q.shade[kind as usize] = queue;
}

/// The paths of `queue` that may scatter again, in order (in the scratch list, to be handed
/// back); those at [`path::at_max_depth`] end here, but for hits on a material with a null lobe
/// where `null_lobes` (whose null samples go on).
#[inline]
fn below_max_depth(
    scene: &RenderScene,
    p: &Paths,
    q: &mut Queues,
    queue: &[u32],
    null_lobes: bool,
) -> Vec<u32> {
    let mut live = std::mem::take(&mut q.scratch);
    live.clear();
    for &i in queue {
        let s = i as usize;
        let ends = path::at_max_depth(scene, p.depth[s] - p.crossings[s])
            && !(null_lobes && scene.materials[p.hit[s].material as usize].has_null_lobe());
        match ends {
            true => q.finished.push(i),
            false => live.push(i),
        }
    }
    live
}

/// The numbers that some material of the hits of `chunk` reads: those of all lanes are drawn
/// at once.
fn reads_of(scene: &RenderScene, p: &Paths, chunk: &[u32]) -> Reads {
    chunk.iter().fold(Reads { dir: false, lobe: false }, |r, &i| {
        let m = scene.materials[p.hit[i as usize].material as usize].reads();
        Reads { dir: r.dir || m.dir, lobe: r.lobe || m.lobe }
    })
}

/// Hits on a [`Shading::Sampled`] kind (delta lobes alone): the numbers of
/// [`LANES`](lambert_vertex::LANES) paths drawn at once, the BSDF sampled across lanes for
/// those the kind `K` takes ([`DeltaLanes`]: smooth glass, thin panes), path by path for the
/// others, then the path's bookkeeping path by path.
fn shade_sampled<K: DeltaLanes>(scene: &RenderScene, p: &mut Paths, q: &mut Queues, queue: &[u32]) {
    use lambert_vertex::LANES;
    let live = below_max_depth(scene, p, q, queue, scene.features.null_surfaces);
    let (mut ins, mut outs) = (DeltaInLanes::default(), DeltaOutLanes::default());
    for chunk in live.chunks(LANES) {
        let (samplers, depths) = p.sampler_lanes::<LANES>(chunk);
        let reads = reads_of(scene, p, chunk);
        let u = pathwave_engine::simd::lanes(
            #[inline(always)]
            || path::ScatterSamples::draw_lanes(scene, &samplers, &depths, reads),
        );
        let mut in_lanes = [false; LANES];
        for (l, &i) in chunk.iter().enumerate() {
            let hit = &p.hit[i as usize];
            if let Some(m) = scene.with_material(hit.material, &hit.surface, K::lane_material) {
                K::set(&mut ins, l, &m, (-p.dir[i as usize]).into(), hit.surface.ns.into(), u[l].lobe);
                in_lanes[l] = true;
            }
        }
        if in_lanes.contains(&true) {
            K::run(&ins, &mut outs);
        }
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let mut st = p.state(s);
            let (hit, wo, time) = (&p.hit[s], -p.dir[s], p.time[s]);
            let next = match in_lanes[l] {
                true => outs.sample(l).and_then(|bs| {
                    path::scatter_sampled(scene, &mut st, &hit.surface, wo, bs, time, &u[l], false)
                }),
                false => scene.with_material(
                    hit.material,
                    &hit.surface,
                    #[inline(always)]
                    |mat| path::scatter_with(scene, &mut st, &hit.surface, wo, mat, time, &u[l], false),
                ),
            };
            route(p, q, i, path::Shadows::default(), next);
            p.set_state(s, &st);
        }
    }
    q.scratch = live;
}

/// The delta kinds no kernel takes (a test's fixtures): sampled path by path.
struct NoLanes;

impl DeltaLanes for NoLanes {
    fn lane_material(_: &Material) -> Option<Self> {
        None
    }

    fn set(_: &mut DeltaInLanes, _: usize, _: &Self, _: glam::Vec3, _: glam::Vec3, _: f32) {}

    fn run(_: &DeltaInLanes, _: &mut DeltaOutLanes) {}
}

/// Hits on a [`Shading::Glossy`] kind: the numbers of [`LANES`](lambert_vertex::LANES) paths
/// drawn at once, then [`path::shade_glossy`] path by path.
fn shade_glossy(scene: &RenderScene, p: &mut Paths, q: &mut Queues, queue: &[u32]) {
    use lambert_vertex::LANES;
    let live = below_max_depth(scene, p, q, queue, false);
    for chunk in live.chunks(LANES) {
        let (samplers, depths) = p.sampler_lanes::<LANES>(chunk);
        let reads = reads_of(scene, p, chunk);
        let u = pathwave_engine::simd::lanes(
            #[inline(always)]
            || path::GlossySamples::draw_lanes(scene, &samplers, &depths, reads),
        );
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let mut st = p.state(s);
            let hit = &p.hit[s];
            let (shadows, next) = scene.with_material(
                hit.material,
                &hit.surface,
                #[inline(always)]
                |mat| path::shade_glossy(scene, &mut st, &hit.surface, -p.dir[s], mat, p.time[s], &u[l]),
            );
            route(p, q, i, shadows, next);
            p.set_state(s, &st);
        }
    }
    q.scratch = live;
}

/// Hits on a kind shaded across lanes ([`GlossyLanes`]: rough conductors, dielectrics and
/// plastics, principled, thin principled and glTF's metallic-roughness):
/// the numbers of [`LANES`](lambert_vertex::LANES) paths drawn at once, the light sample path
/// by path, then the BSDF evaluated towards it and sampled across lanes for the hits the kernel
/// shades (anisotropic conductors and height-correlated shadowing by kernels of their own),
/// and the path's bookkeeping path by path; where a light is sampled apart, the BSDF
/// is evaluated towards its samples across lanes too. Smooth ones (delta lobes) are shaded as
/// the other glossy kinds.
fn shade_in_lanes<K: GlossyLanes>(scene: &RenderScene, p: &mut Paths, q: &mut Queues, queue: &[u32]) {
    use lambert_vertex::LANES;
    let live = below_max_depth(scene, p, q, queue, false);
    let mut ins = K::In::default();
    // Each kernel's outputs, by `Kernel::index`.
    let mut outs: [K::Out; Kernel::COUNT] = std::array::from_fn(|_| K::Out::default());
    let mut env_outs: [EvalLanes; Kernel::COUNT] = std::array::from_fn(|_| EvalLanes::default());
    for chunk in live.chunks(LANES) {
        let (samplers, depths) = p.sampler_lanes::<LANES>(chunk);
        let reads = reads_of(scene, p, chunk);
        let u = pathwave_engine::simd::lanes(
            #[inline(always)]
            || path::GlossySamples::draw_lanes(scene, &samplers, &depths, reads),
        );
        // Per lane: the material as its kernel takes it (none: shaded path by path), and the
        // point and normal the lights are picked for, all lanes at once (the bits of one
        // point's pick); then the light sample. The kernels that some lane takes, as bits by
        // `Kernel::index`.
        let mut materials: [Option<(K, Kernel)>; LANES] = std::array::from_fn(|_| None);
        let (mut from, mut normal, mut u_pick) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3], [0.0; LANES]);
        for (l, &i) in chunk.iter().enumerate() {
            let sp = &p.hit[i as usize].surface;
            materials[l] = scene.with_material(p.hit[i as usize].material, sp, K::lane_material);
            for a in 0..3 {
                (from[a][l], normal[a][l]) = (sp.p[a], sp.ns[a]);
            }
            u_pick[l] = u[l].light_pick;
        }
        let picks = (!scene.lights.is_empty()).then(|| scene.lights.pick_lanes(&u_pick, &from, &normal));
        let (mut kernel, mut used) = ([None; LANES], 0u32);
        let lights = match &picks {
            Some(picks) => {
                // The lanes the kernels shade (a material only for `chunk`'s hits).
                let active = std::array::from_fn(|l| materials[l].is_some());
                let times = std::array::from_fn(|l| chunk.get(l).map_or(0.0, |&i| p.time[i as usize]));
                let numbers = std::array::from_fn(|l| u[l].light);
                light_lanes::sample_lights_lanes(scene, picks, &active, &from, &times, &numbers)
            }
            None => std::array::from_fn(|_| None),
        };
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let Some((m, k)) = materials[l].take() else { continue };
            let sp = &p.hit[s].surface;
            let wi = lights[l].as_ref().map_or(sp.ns, |lp| lp.wi);
            K::set(&mut ins, l, &m, (-p.dir[s]).into(), sp.ns.into(), wi.into(), &u[l].bsdf);
            kernel[l] = Some(k);
            used |= 1 << k.index();
        }
        for k in Kernel::ALL {
            if used & 1 << k.index() != 0 {
                K::run(&ins, k, &mut outs[k.index()]);
            }
        }
        // The light sampled apart: the BSDF towards its samples, across lanes again.
        let mut apart: [Option<path::LightPick>; LANES] = std::array::from_fn(|_| None);
        if scene.lights.apart().is_some() {
            for (l, &i) in chunk.iter().enumerate() {
                if kernel[l].is_some() {
                    let sp = &p.hit[i as usize].surface;
                    apart[l] = path::apart_light(scene, sp.p, u[l].apart);
                    K::set_wi(&mut ins, l, apart[l].as_ref().map_or(sp.ns, |lp| lp.wi).into());
                }
            }
            for k in Kernel::ALL {
                if used & 1 << k.index() != 0 {
                    K::eval(&ins, k, &mut env_outs[k.index()]);
                }
            }
        }
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let mut st = p.state(s);
            let hit = &p.hit[s];
            let (sp, wo, time) = (&hit.surface, -p.dir[s], p.time[s]);
            let (shadows, next) = match kernel[l] {
                None => scene.with_material(
                    hit.material,
                    sp,
                    #[inline(always)]
                    |mat| path::shade_glossy(scene, &mut st, sp, wo, mat, time, &u[l]),
                ),
                Some(k) => {
                    let (e, bs) = K::result(&outs[k.index()], l);
                    let ours = |lp: &&path::LightPick| !path::light_traced(scene, &st, lp);
                    let light = (lights[l].as_ref().filter(ours))
                        .and_then(|lp| path::light_shadow(scene, &st, sp, wo, lp, || e, time));
                    let env_eval = &env_outs[k.index()];
                    let apart = (apart[l].as_ref().filter(ours))
                        .and_then(|lp| path::light_shadow(scene, &st, sp, wo, lp, || env_eval.eval(l), time));
                    let next = bs.and_then(|bs| {
                        path::scatter_sampled(scene, &mut st, sp, wo, bs, time, &u[l].bsdf, true)
                    });
                    (path::Shadows { light, apart }, next)
                }
            };
            route(p, q, i, shadows, next);
            p.set_state(s, &st);
        }
    }
    q.scratch = live;
}

/// Lambertian hits: inputs are gathered [`LANES`](lambert_vertex::LANES) paths at a time into lane arrays,
/// the branch-free kernel runs on all lanes at once (vectorised), and outputs are written
/// straight to the paths' arrays ([`lambert_vertex::scattered`], as the reference path
/// tracer's [`lambert_vertex::apply`] does) and the queues.
fn shade_lambertian_lanes(scene: &RenderScene, p: &mut Paths, q: &mut Queues, queue: &[u32]) {
    use lambert_vertex::{LANES, LambertInLanes, LambertOutLanes};
    let mut ins = LambertInLanes::default();
    let mut outs = LambertOutLanes::default();
    let mut lights = light_lanes::LightSampler::new(scene);
    let mut live = below_max_depth(scene, p, q, queue, false);
    if scene.features.one_sided {
        end_behind(scene, p, q, &mut live);
    }
    if scene.features.tilts {
        shade_tilted(scene, p, q, &mut live);
    }
    for chunk in live.chunks(LANES) {
        // The vertex's numbers for all lanes at once.
        let (samplers, depths) = p.sampler_lanes::<LANES>(chunk);
        let u = lambert_vertex::VertexSamples::draw_lanes(scene, &samplers, &depths);
        let mut times = [0.0; LANES];
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let hit = &p.hit[s];
            let albedo = scene.albedo_at(hit.material, &hit.surface);
            let path =
                lambert_vertex::PathIn { beta: p.beta[s], eta_scale: p.eta_scale[s], depth: p.depth[s] };
            ins.set_surface(l, path, &hit.surface, -p.dir[s], albedo);
            times[l] = p.time[s];
        }
        ins.set_numbers(scene, &u);
        // A short last chunk leaves its last lanes as the chunk before: their samples go unread.
        lights.sample(&times, &u, &mut ins);
        match scene.guide.as_deref() {
            // Where a guide was learned, the lanes it covers draw their directions from it.
            Some(g) => crate::guided::lambert_guided_lanes(g, &ins, &mut outs),
            None => lambert_vertex::lambert_lanes(&ins, &mut outs),
        }
        // The shadow rays, lanes that made one first.
        let (mut pick, mut n) = ([0; LANES], 0);
        for l in 0..chunk.len() {
            pick[n] = l;
            n += outs.shadow[l] as usize;
        }
        q.shadow.extend_lanes(&pick[..n], chunk, &times, &outs.so, &outs.sd, &outs.contribution);
        if scene.lights.apart().is_some() {
            // The light sampled apart: its light part of the kernel one path at a time.
            for (l, &i) in chunk.iter().enumerate() {
                let env = u.get(l).apart;
                if let Some(sh) = lambert_vertex::apart_shadow(scene, &ins.get(l), times[l], env) {
                    q.shadow.push(i, &sh.ray, sh.contribution);
                }
            }
        }
        let v3 = |a: &[[f32; LANES]; 3], l: usize| glam::Vec3::new(a[0][l], a[1][l], a[2][l]);
        for (l, &i) in chunk.iter().enumerate() {
            let s = i as usize;
            let st = lambert_vertex::Bounce {
                beta: &mut p.beta[s],
                delta: &mut p.delta[s],
                prev_pdf: &mut p.prev_pdf[s],
                prev_p: &mut p.prev_p[s],
                prev_n: &mut p.prev_n[s],
                depth: &mut p.depth[s],
            };
            let o = outs.get(l);
            if lambert_vertex::scattered(v3(&ins.p, l), v3(&ins.n, l), ins.depth_after[l], &o, st) && o.alive
            {
                if !p.trail.is_empty() {
                    p.trail[s].push(v3(&ins.p, l), o.d, o.pdf, o.mis_pdf, o.beta, p.l[s], p.depth[s]);
                }
                p.set_ray(
                    s,
                    Ray { origin: v3(&outs.o, l).into(), dir: v3(&outs.d, l).into(), time: times[l] },
                );
                q.next.push(i);
            } else {
                q.finished.push(i);
            }
        }
    }
    q.scratch = live;
}

/// Shades the hits of `live` whose normal a map tilted ([`path::tilted`]) path by path, as
/// glossy kinds are, and leaves the others to the lane kernel. Out of line: scenes without
/// maps never call it.
#[inline(never)]
fn shade_tilted(scene: &RenderScene, p: &mut Paths, q: &mut Queues, live: &mut Vec<u32>) {
    let mut tilted = Vec::new();
    live.retain(|&i| {
        let t = path::tilted(&p.hit[i as usize].surface);
        if t {
            tilted.push(i);
        }
        !t
    });
    shade_glossy(scene, p, q, &tilted);
}

/// Ends the paths of `live` that meet a one-sided Lambertian from behind
/// ([`path::black_behind`]). Out of line, so that the Lambertian stage's code is as it was for
/// scenes without one-sided materials (benches/RESULTS.md).
#[inline(never)]
fn end_behind(scene: &RenderScene, p: &Paths, q: &mut Queues, live: &mut Vec<u32>) {
    live.retain(|&i| {
        let hit = &p.hit[i as usize];
        let behind =
            path::black_behind(&scene.materials[hit.material as usize], &hit.surface, -p.dir[i as usize]);
        if behind {
            q.finished.push(i);
        }
        !behind
    });
}
