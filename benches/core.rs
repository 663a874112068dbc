//! Criterion benchmarks of the core: BVH build, closest-hit and any-hit traversal over fixed
//! rays, each wavefront stage on the queues it met in one iteration of a render, and a 16-spp
//! cornell with each integrator. `cargo bench --bench core` runs them (add `-- traverse` to
//! pick a group); `benches/results/wavefront-and-oracle.md` and `lanes-and-simd.md` record
//! what they measured, with the machine and the date. Whole-scene time against error is `pathwave bench`.

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3A;
use pathwave_engine::accel::mesh::{MeshBlas, MeshData};
use pathwave_engine::scene;
use pathwave_engine::world::SceneWorld;
use pathwave_integrator::{oracle, wavefront};
use std::hint::black_box;
use std::num::NonZeroU32;
use std::path::Path;
use std::sync::Arc;

/// The knot of `mesh.ron` (100,000 triangles), in its own space.
fn knot() -> Arc<MeshData> {
    Arc::new(MeshData::knot(400, 125))
}

/// `n` rays from a sphere around `blas` towards random points near its centre, as bounce rays
/// would meet it from outside: the same rays every run (xorshift from a fixed seed).
fn rays(blas: &MeshBlas, n: usize) -> Vec<(Vec3A, Vec3A)> {
    let b = blas.bounds();
    let (centre, reach) = ((b.min + b.max) * 0.5, (b.max - b.min).length());
    let mut s = 0x9e37_79b9u32;
    let mut u = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s as f32 / u32::MAX as f32 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            let o = centre + Vec3A::new(u(), u(), u()).normalize_or(Vec3A::X) * reach;
            let target = centre + Vec3A::new(u(), u(), u()) * 0.5 * reach;
            (o, target - o)
        })
        .collect()
}

fn bvh(c: &mut Criterion) {
    let mesh = knot();
    let mut g = c.benchmark_group("bvh_build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(mesh.triangles.len() as u64));
    g.bench_function("knot_100k", |b| {
        b.iter_batched(|| mesh.clone(), |m| black_box(MeshBlas::build(m)), BatchSize::SmallInput)
    });
    g.finish();
}

fn traverse(c: &mut Criterion) {
    let blas = MeshBlas::build(knot());
    let rays = rays(&blas, 4096);
    let mut g = c.benchmark_group("traverse");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest_knot_100k", |b| {
        b.iter(|| rays.iter().filter(|(o, d)| blas.intersect(*o, *d, f32::INFINITY).is_some()).count())
    });
    // Shadow rays end at the target: about half of them are blocked.
    g.bench_function("any_hit_knot_100k", |b| {
        b.iter(|| rays.iter().filter(|(o, d)| blas.occluded(*o, *d, 1.0)).count())
    });
    g.finish();
}

/// A scene of `scenes/` rendered at `side` x `side` pixels.
fn scene_at(name: &str, side: u32) -> Arc<pathwave_engine::render_scene::RenderScene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let mut desc = scene::load(&path).expect("the scenes of scenes/ load");
    let side = NonZeroU32::new(side).expect("not zero");
    (desc.render.width, desc.render.height) = (side, side);
    SceneWorld::render_scene(&desc)
}

/// Each stage of the wavefront on the paths and queues it met in the 20th iteration of a tile
/// near the image's centre (256 path slots, one thread): the time per item of each stage on
/// its own, without the rest of the render around it.
fn stages(c: &mut Criterion) {
    for name in ["cornell-diffuse", "cornell", "mesh", "spheres-sky"] {
        let scene = scene_at(&format!("{name}.ron"), 128);
        // Tile 36 of the 8 x 8 tiles: row 4, column 4.
        let inputs = wavefront::capture_stages(&scene, wavefront::Options::default(), 36, 20);
        let mut g = c.benchmark_group(format!("stage_{name}"));
        for input in inputs {
            g.throughput(Throughput::Elements(input.items as u64));
            g.bench_function(input.stage.name(), |b| {
                b.iter_batched_ref(|| input.clone(), |i| i.run(), BatchSize::SmallInput)
            });
        }
        g.finish();
    }
}

/// The numbers of a Lambertian vertex (light choice, light point, direction, roulette) for
/// groups of 16 paths at depths 0 to 7 (cornell-diffuse's settings: one light, roulette from
/// depth 5), as `shade_lambertian` draws them: the sampler's cost per path and vertex alone.
fn vertex_numbers(c: &mut Criterion) {
    use pathwave_integrator::lambert_vertex::{LANES, VertexSamples};
    use pathwave_integrator::sampler::SamplerLanes;
    let scene = scene_at("cornell-diffuse.ron", 128);
    let groups: Vec<(SamplerLanes<LANES>, [u32; LANES])> = (0..256u32)
        .map(|g| {
            let samplers: [_; LANES] = std::array::from_fn(|l| {
                let i = g * LANES as u32 + l as u32;
                pathwave_integrator::path::camera_sampler(&scene, i % 128, i / 128 % 128, i / 64 % 64)
            });
            (SamplerLanes::from(&samplers), std::array::from_fn(|l| (g + l as u32 / 4) % 8))
        })
        .collect();
    let mut g = c.benchmark_group("vertex_numbers");
    g.throughput(Throughput::Elements((groups.len() * LANES) as u64));
    g.bench_function("cornell_diffuse", |b| {
        b.iter(|| {
            for (s, d) in &groups {
                black_box(VertexSamples::draw_lanes(&scene, s, d));
            }
        })
    });
    g.finish();
}

fn render(c: &mut Criterion) {
    let scene = scene_at("cornell.ron", 128);
    let side = 128;
    let pixels = side * side;
    let mut g = c.benchmark_group("render_cornell_128px_16spp");
    g.sample_size(10);
    g.throughput(Throughput::Elements(pixels * 16));
    let none = |_: usize, _: usize| {};
    g.bench_function("wavefront", |b| {
        let opts = wavefront::Options::default();
        b.iter(|| black_box(wavefront::render_samples(&scene, opts, 0..16, &none)))
    });
    g.bench_function("oracle", |b| b.iter(|| black_box(oracle::render_samples(&scene, 0..16, &none))));
    g.finish();
}

criterion_group!(benches, bvh, traverse, stages, vertex_numbers, render);
criterion_main!(benches);
