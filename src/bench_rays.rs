//! `pathwave bench-rays`: BVH build time and traversal rates on the rays that
//! `benches/embree/anchor.c` traces with Embree (primary, diffuse-bounce and shadow rays on the
//! 1M-triangle knot and on cornell-diffuse), so that our figures sit beside Embree's measured
//! the same way.

use crate::engine::accel::geometry::Geometry;
use crate::engine::accel::mesh::{MeshBlas, MeshData};
use crate::engine::shape::Primitive;
use crate::engine::shape::Triangle;
use glam::{Vec2, Vec3A};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// `pathwave bench-rays`'s flags.
#[derive(clap::Args, Debug)]
pub struct BenchRaysCommand {
    /// Knot rings (2 x rings x segments triangles).
    #[arg(long, default_value_t = 2000)]
    pub rings: u32,
    /// Knot ring vertices.
    #[arg(long, default_value_t = 250)]
    pub segments: u32,
    /// A scene whose geometry and first light also get primary, bounce and shadow rays.
    #[arg(long, default_value = "scenes/cornell-diffuse.ron")]
    pub scene: PathBuf,
    /// Also time per-frame updates of this scene of instances (one instance moving).
    #[arg(long, value_name = "SCENE.ron")]
    pub instances: Option<PathBuf>,
    /// Also build and trace knots of 10^3 up to 10^N triangles.
    #[arg(long, value_name = "N")]
    pub scaling: Option<u32>,
}

/// Runs what the flags ask for: the knot and the scene, then the instances and the scaling.
pub fn run(c: &BenchRaysCommand) -> Result<(), String> {
    knot_and_scene((c.rings, c.segments), Some(&c.scene))?;
    if let Some(p) = &c.instances {
        instance_update(p, 100)?;
    }
    c.scaling.map_or(Ok(()), scaling)
}

/// Rays with their extent.
#[derive(Default)]
pub struct Rays {
    /// Origins.
    pub o: Vec<Vec3A>,
    /// Directions.
    pub d: Vec<Vec3A>,
    /// Largest distances.
    pub tmax: Vec<f32>,
}

impl Rays {
    fn push(&mut self, o: Vec3A, d: Vec3A, tmax: f32) {
        self.o.push(o);
        self.d.push(d);
        self.tmax.push(tmax);
    }
}

/// Something rays can be traced against: closest hit `(t, geometric normal)` and occlusion.
pub trait Target: Sync {
    /// Closest hit.
    fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, Vec3A)>;
    /// Any hit.
    fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool;
}

impl Target for MeshBlas {
    fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, Vec3A)> {
        self.intersect(o, d, tmax).map(|h| (h.t, h.ng().normalize()))
    }
    fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        MeshBlas::occluded(self, o, d, tmax)
    }
}

impl Target for Geometry {
    fn closest(&self, o: Vec3A, d: Vec3A, tmax: f32) -> Option<(f32, Vec3A)> {
        let ray = crate::engine::math::Ray::new(o, d);
        self.intersect(&ray, tmax).map(|h| (h.t, h.surface.n))
    }
    fn occluded(&self, o: Vec3A, d: Vec3A, tmax: f32) -> bool {
        Geometry::occluded(self, &crate::engine::math::Ray::new(o, d), tmax)
    }
}

/// Rays through the pixel centres of a `size` x `size` pinhole camera, in 8x8 tiles.
pub fn primary(from: Vec3A, at: Vec3A, up: Vec3A, vfov_deg: f32, size: u32) -> Rays {
    let w = (from - at).normalize();
    let u = up.cross(w).normalize();
    let v = w.cross(u);
    let half = (vfov_deg.to_radians() / 2.0).tan();
    let mut rays = Rays::default();
    for ty in (0..size).step_by(8) {
        for tx in (0..size).step_by(8) {
            for y in ty..(ty + 8).min(size) {
                for x in tx..(tx + 8).min(size) {
                    let sx = (2.0 * (x as f32 + 0.5) / size as f32 - 1.0) * half;
                    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / size as f32) * half;
                    rays.push(from, (sx * u + sy * v - w).normalize(), f32::INFINITY);
                }
            }
        }
    }
    rays
}

/// A hash of `i` to two numbers in [0, 1).
fn rnd2(i: u32, salt: u32) -> Vec2 {
    let h = |mut x: u32| {
        x ^= x >> 16;
        x = x.wrapping_mul(0x7feb352d);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846ca68b);
        x ^ (x >> 16)
    };
    let a = h(i.wrapping_mul(2).wrapping_add(salt.wrapping_mul(0x9e3779b9)));
    let b = h(a ^ 0x5bd1e995);
    Vec2::new((a >> 8) as f32 / (1 << 24) as f32, (b >> 8) as f32 / (1 << 24) as f32)
}

/// The point of primary hit `i` (at `t`, normal `n`) moved `offset` along the normal turned
/// to face the camera, and that normal.
fn lifted(primary: &Rays, i: usize, t: f32, n: Vec3A, offset: f32) -> (Vec3A, Vec3A) {
    let d = primary.d[i];
    let n = if n.dot(d) > 0.0 { -n } else { n };
    (primary.o[i] + t * d + offset * n, n)
}

/// One cosine-distributed ray per primary hit about the geometric normal turned to face the
/// camera, its origin moved `offset` along that normal.
pub fn bounce(primary: &Rays, hits: &[Option<(f32, Vec3A)>], offset: f32) -> Rays {
    let mut rays = Rays::default();
    for (i, h) in hits.iter().enumerate() {
        let Some((t, n)) = *h else { continue };
        let (p, n) = lifted(primary, i, t, n, offset);
        let u = rnd2(i as u32, 1);
        let (r, phi) = (u.x.sqrt(), std::f32::consts::TAU * u.y);
        let (t1, t2) = n.any_orthonormal_pair();
        let dir = r * phi.cos() * t1 + r * phi.sin() * t2 + (1.0 - u.x).max(0.0).sqrt() * n;
        rays.push(p, dir, f32::INFINITY);
    }
    rays
}

/// Shadow rays from each primary hit to a uniform point of the one-sided light quad
/// `(q, eu, ev)` (normal along `eu x ev`), only where surface and light face each other.
pub fn shadow(primary: &Rays, hits: &[Option<(f32, Vec3A)>], light: [Vec3A; 3], offset: f32) -> Rays {
    let [q, eu, ev] = light;
    let ln = eu.cross(ev).normalize();
    let mut rays = Rays::default();
    for (i, h) in hits.iter().enumerate() {
        let Some((t, n)) = *h else { continue };
        let (p, n) = lifted(primary, i, t, n, offset);
        let u = rnd2(i as u32, 2);
        let target = q + u.x * eu + u.y * ev;
        let to = target - p;
        // On the light itself (same plane) or facing away: no ray.
        if to.dot(n) <= 0.0 || to.dot(ln) >= 0.0 || (p - q).dot(ln).abs() < 1e-3 {
            continue;
        }
        rays.push(p, to, 0.999);
    }
    rays
}

/// Traces `rays` on `threads` threads (closest or any hit); returns the hits and Mrays/s
/// (median of 3 runs).
fn trace(
    target: &dyn Target,
    rays: &Rays,
    threads: usize,
    occlusion: bool,
) -> (Vec<Option<(f32, Vec3A)>>, f64) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    let mut rates = Vec::new();
    let mut hits = Vec::new();
    for _ in 0..3 {
        let start = Instant::now();
        hits = pool.install(|| {
            (0..rays.o.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|i| {
                    let (o, d, tmax) = (rays.o[i], rays.d[i], rays.tmax[i]);
                    if occlusion {
                        target.occluded(o, d, tmax).then_some((0.0, Vec3A::ZERO))
                    } else {
                        target.closest(o, d, tmax)
                    }
                })
                .collect()
        });
        rates.push(rays.o.len() as f64 / start.elapsed().as_secs_f64() / 1e6);
    }
    rates.sort_by(f64::total_cmp);
    (hits, rates[1])
}

/// One table row per ray kind and thread count.
fn rows(name: &str, target: &dyn Target, primary_rays: &Rays, offset: f32, light: Option<[Vec3A; 3]>) {
    let (hits, _) = trace(target, primary_rays, 2, false);
    let frac =
        |h: &[Option<(f32, Vec3A)>]| h.iter().filter(|h| h.is_some()).count() as f64 / h.len().max(1) as f64;
    let bounce_rays = bounce(primary_rays, &hits, offset);
    let mut kinds = vec![("primary", primary_rays, false), ("diffuse bounce", &bounce_rays, false)];
    let shadow_rays = light.map(|l| shadow(primary_rays, &hits, l, offset));
    match &shadow_rays {
        Some(s) => kinds.push(("shadow (occlusion)", s, true)),
        // Without a light, occlusion on the bounce rays.
        None => kinds.push(("diffuse bounce (occlusion)", &bounce_rays, true)),
    }
    for (kind, rays, occlusion) in kinds {
        let (h1, r1) = trace(target, rays, 1, occlusion);
        let (_, r2) = trace(target, rays, 2, occlusion);
        println!("| {name} | {kind} | {} | {:.3} | {r1:.2} | {r2:.2} |", rays.o.len(), frac(&h1));
    }
}

/// Runs the benchmark, printing markdown tables as it goes; `knot` = (rings, segments) of the mesh (2000, 250 for 1M triangles).
pub fn knot_and_scene(knot: (u32, u32), cornell: Option<&std::path::Path>) -> Result<(), String> {
    let start = Instant::now();
    let mesh = Arc::new(MeshData::knot(knot.0, knot.1));
    let gen_s = start.elapsed().as_secs_f64();
    let n = mesh.triangles.len();
    println!("knot: {n} triangles (generated in {gen_s:.2} s)\n");
    println!("| BVH | build s (2 threads) | bytes | bytes/triangle |");
    println!("|---|---|---|---|");
    let start = Instant::now();
    let blas = MeshBlas::build(mesh.clone());
    let ours_s = start.elapsed().as_secs_f64();
    println!(
        "| pathwave BVH8 + 8-triangle blocks | {ours_s:.3} | {} | {:.1} |",
        blas.bytes(),
        blas.bytes() as f64 / n as f64
    );
    let tris: Vec<Primitive> = (0..n as u32)
        .filter_map(|i| {
            let [a, b, c] = mesh.triangle(i);
            Triangle::new(a, b, c).map(Primitive::Triangle)
        })
        .collect();
    let m = tris.len();
    let start = Instant::now();
    let prims = Geometry::build_bvh(tris, vec![0; m]);
    let prims_s = start.elapsed().as_secs_f64();
    println!(
        "| BVH8 over a Primitive list (scalar triangle tests) | {prims_s:.3} | | {} (primitive list) |",
        size_of::<Primitive>()
    );
    println!("\n| scene | rays | count | hit fraction | Mrays/s 1t | Mrays/s 2t |");
    println!("|---|---|---|---|---|---|");
    let cam = primary(Vec3A::new(0.0, -3.0, 7.5), Vec3A::ZERO, Vec3A::Y, 45.0, 1024);
    rows("knot (pathwave BVH8)", &blas, &cam, 1e-4, None);
    rows("knot (BVH8 over Primitives)", &prims, &cam, 1e-4, None);
    if let Some(path) = cornell {
        let desc = crate::engine::scene::load(path).map_err(|e| e.to_string())?;
        let scene = crate::engine::world::SceneWorld::render_scene(&desc);
        let crate::engine::scene::CameraView::LookAt { look_from, look_at, vup, vfov } = desc.camera.view
        else {
            return Err(format!("{}: bench-rays needs a look_from/look_at camera", path.display()));
        };
        let cam = primary(look_from.into(), look_at.into(), vup.into(), vfov, 1024);
        let light = scene.lights.prims.first().and_then(|&p| match scene.geometry.prims[p as usize] {
            Primitive::Quad(q) => Some([q.q, q.u, q.v]),
            _ => None,
        });
        rows("cornell-diffuse (BVH8 over quads)", &*scene.geometry, &cam, 1e-2, light);
    }
    Ok(())
}

/// Per-frame update of a scene of instances: one instance moves each frame (the ECS refits the
/// TLAS) against rebuilding the TLAS from scratch; prints a markdown table.
pub fn instance_update(path: &std::path::Path, frames: usize) -> Result<(), String> {
    use crate::engine::world::{Instanced, MeshLibrary, SceneInstances, Transform};
    let desc = crate::engine::scene::load(path).map_err(|e| e.to_string())?;
    let mut w = crate::engine::world::SceneWorld::new(&desc);
    let start = Instant::now();
    let scene = w.update();
    let first = start.elapsed().as_secs_f64();
    let n = scene.instances.list.len();
    let e = w
        .world
        .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<Instanced>>()
        .iter(&w.world)
        .next()
        .ok_or("the scene has no instances")?;
    let base = w.world.get::<Transform>(e).ok_or("no transform")?.0;
    let mut refit = Vec::new();
    for f in 0..frames {
        let m = glam::Affine3A::from_translation(glam::Vec3::new(0.0, 0.01 * f as f32, 0.0)) * base;
        w.world.entity_mut(e).insert(Transform(m));
        let start = Instant::now();
        w.update();
        refit.push(start.elapsed().as_secs_f64());
    }
    let mut rebuild = Vec::new();
    let inst = w.world.resource::<SceneInstances>().instances.clone();
    for _ in 0..frames.min(20) {
        let start = Instant::now();
        let rebuilt = crate::engine::accel::instances::Instances::build(
            inst.blas.clone(),
            inst.list.clone(),
            desc.camera.shutter,
        );
        rebuild.push(start.elapsed().as_secs_f64());
        drop(rebuilt);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2] * 1e3
    };
    let s = w.world.resource::<SceneInstances>();
    let blas = w.world.resource::<MeshLibrary>().builds;
    println!(
        "{}: {n} instances, {} BLAS ({} triangles each)",
        path.display(),
        inst.blas.len(),
        inst.blas[0].mesh.triangles.len()
    );
    println!("first update (BLAS + TLAS build, extraction): {:.1} ms", first * 1e3);
    println!(
        "after {frames} frames moving one instance: {blas} BLAS builds, {} TLAS builds, {} refits",
        s.builds, s.refits
    );
    println!("| per-frame update | median ms |\n|---|---|");
    println!("| move one instance: ECS update (refit TLAS, extract) | {:.3} |", median(&mut refit));
    println!("| rebuild the TLAS from scratch | {:.3} |", median(&mut rebuild));
    println!("instance records + TLAS: {} bytes; BLAS: {} bytes", inst.bytes(), inst.blas[0].bytes());
    Ok(())
}

/// BVH build time, size and traversal rates as the triangle count grows (knots of 10^3..10^max
/// triangles).
pub fn scaling(max_exp: u32) -> Result<(), String> {
    println!("| triangles | build s (2t) | bytes/triangle | primary Mrays/s (2t) | bounce Mrays/s (2t) |");
    println!("|---|---|---|---|---|");
    for e in 3..=max_exp {
        let n = 10f64.powi(e as i32);
        // rings = 8 segments: 2 * 8 s^2 = n.
        let segments = ((n / 16.0).sqrt().round() as u32).max(3);
        let mesh = Arc::new(MeshData::knot(8 * segments, segments));
        let start = Instant::now();
        let blas = MeshBlas::build(mesh.clone());
        let build = start.elapsed().as_secs_f64();
        let cam = primary(Vec3A::new(0.0, -3.0, 7.5), Vec3A::ZERO, Vec3A::Y, 45.0, 512);
        let (hits, p) = trace(&blas, &cam, 2, false);
        let (_, b) = trace(&blas, &bounce(&cam, &hits, 1e-4), 2, false);
        let t = mesh.triangles.len();
        println!("| {t} | {build:.3} | {:.1} | {p:.2} | {b:.2} |", blas.bytes() as f64 / t as f64);
    }
    Ok(())
}
