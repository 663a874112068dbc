//! The wavefront integrator against the reference path tracer: identical bits for the same seed
//! (same per-vertex code, exact pixel sums), whatever the batch size and thread count; agreement
//! in expectation with an independent seed; every sample reaches the film once.

mod common;
use common::*;
use pathwave::engine::scene::SceneDesc;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::film::Film;
use pathwave::integrator::oracle;
use pathwave::integrator::wavefront::{self, Options};
use pathwave::io::LinearImage;

fn small(name: &str, spp: u32) -> SceneDesc {
    let mut desc = scene(name);
    let aspect = desc.render.width.get() as f32 / desc.render.height.get() as f32;
    desc.render.width = 40.try_into().unwrap();
    desc.render.height = ((40.0 / aspect) as u32).try_into().unwrap();
    desc.render.spp = spp.try_into().unwrap();
    desc
}

fn wavefront(desc: &SceneDesc, batch: usize, threads: usize) -> (Film, wavefront::Stats) {
    let scene = SceneWorld::render_scene(desc);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| wavefront::render(&scene, Options { batch, ..Default::default() }, &|_, _| {}))
}

/// Same seed, same per-vertex code, exact pixel sums: the wavefront reproduces the oracle's
/// samples. Where both search the BVH (spheres-sky) the images are identical; small scenes are
/// traced as ray streams against flat primitive lists, which break exact ties between two
/// primitives at the same distance (a shared edge) differently from obvhs, so a handful of
/// pixels may differ there.
#[test]
fn reproduces_the_oracle_for_any_batch_and_thread_count() {
    for (name, max_differing) in [
        ("cornell.ron", 2),
        ("cornell-diffuse.ron", 2),
        ("cornell-smoke.ron", 2),
        ("transforms.ron", 2),
        ("spheres-sky.ron", 0),
        // Flat primitives and instances of a mesh.
        ("mesh.ron", 2),
        // Rough materials, an environment map and a point light.
        ("materials-env.ron", 2),
        // Every glossy kind across lanes, a map sampled apart from a lamp.
        ("rough-spheres.ron", 2),
        // Masks (camera, bounce and shadow rays through their holes) and blends.
        ("wrappers.ron", 2),
        // Bump and normal maps (Lambertians under them shaded path by path).
        ("maps.ron", 2),
        // 500 lights chosen by the light tree, each lane with its own point.
        ("many-lights.ron", 2),
        // Splatted filters: a sample that differs reaches 4 and 16 pixels.
        ("cornell.ron tent", 8),
        ("materials-env.ron gaussian", 32),
    ] {
        let (name, filter) = name.split_once(' ').unwrap_or((name, "box"));
        let mut desc = small(name, 6);
        desc.render.filter = filter.parse().unwrap();
        let oracle = render_threads(&desc, 2);
        let mut first: Option<Film> = None;
        for (batch, threads) in [(1, 1), (7, 2), (1024, 2), (100_000, 1)] {
            let (film, stats) = wavefront(&desc, batch, threads);
            let samples = (film.width * film.height * film.spp) as u64;
            assert_eq!(stats.paths, samples, "{name}: every sample finishes exactly once");
            let differing = film.pixels.iter().zip(&oracle.pixels).filter(|(a, b)| a != b).count();
            assert!(differing <= max_differing, "{name}: {differing} pixels differ from the oracle");
            match &first {
                None => first = Some(film),
                Some(f) => assert!(*f == film, "{name}: batch {batch}, {threads} threads changed the image"),
            }
        }
    }
}

/// Every material kind that shades, each on a coarse sphere mesh (see
/// [`reproduces_the_oracle_on_smooth_shaded_meshes`]), as RON.
const SHADING_KINDS: [(&str, &str); 19] = [
    ("white", r#"Lambertian(albedo: (0.7, 0.7, 0.7))"#),
    ("metal", r#"Metal(albedo: (0.9, 0.8, 0.7), fuzz: 0.2)"#),
    ("gold", r#"RoughConductor(tint: (1, 0.8, 0.4), alpha: 0.3)"#),
    ("frost", r#"RoughDielectric(ior: 1.5, alpha: 0.2)"#),
    (
        "copper",
        r#"RoughConductor(tint: (1, 0.6, 0.4), alpha: 0.2, distribution: Beckmann, smith: HeightCorrelated)"#,
    ),
    ("etched", r#"RoughDielectric(ior: 1.5, alpha: 0.3, distribution: Beckmann, smith: HeightCorrelated)"#),
    ("glass", r#"Dielectric(ior: 1.5)"#),
    ("schlick", r#"Dielectric(ior: 1.7, fresnel: Schlick)"#),
    ("pane", r#"ThinDielectric(ior: 1.5)"#),
    ("plastic", r#"Plastic(albedo: (0.1, 0.27, 0.36), ior: 1.9)"#),
    (
        "rough_plastic",
        r#"RoughPlastic(albedo: "checks", alpha: 0.2, distribution: Beckmann, nonlinear: true)"#,
    ),
    (
        "principled",
        r#"Principled(base_color: "checks", roughness: 0.4, anisotropic: 0.7, metallic: "checks", spec_trans: 0.3, sheen: 0.5, clearcoat: 0.6)"#,
    ),
    ("brushed", r#"RoughConductor(tint: (0.9, 0.9, 0.9), alpha: 0.05, alpha_v: "checks")"#),
    (
        "gltf",
        r#"MetallicRoughness(base_color: "checks", metallic: 0.4, roughness: 0.5, clearcoat: 0.5, clearcoat_roughness: 0.2)"#,
    ),
    (
        "leaf",
        r#"PrincipledThin(base_color: "checks", roughness: 0.5, anisotropic: 0.4, spec_trans: 0.4, diff_trans: 0.8, sheen: 0.3, flatness: 0.5)"#,
    ),
    ("frost2", r#"RoughDielectric(ior: 1.3, alpha: 0.4)"#),
    ("fuzz", r#"Metal(albedo: (0.7, 0.8, 0.9), fuzz: 0.7)"#),
    ("mirror", r#"Metal(albedo: (0.9, 0.9, 0.8))"#),
    (
        "coated",
        r#"Plastic(albedo: "checks", tint: (0.9, 0.8, 0.7), ior: 1.5, nonlinear: true, two_sided: true)"#,
    ),
];

/// Loads a scene of `ball.obj` (a coarse smooth-shaded sphere) in every kind of
/// [`SHADING_KINDS`], laid out by `objects` (RON objects that name them), under `lights`, at
/// `spp` samples per pixel.
fn shading_kinds_scene(camera: &str, objects: &str, lights: &str, spp: u32) -> SceneDesc {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ball.obj"), sphere_obj(6, 12, true)).unwrap();
    let path = dir.path().join("smooth.ron");
    let materials: String = SHADING_KINDS.iter().map(|(name, m)| format!("\"{name}\": {m},\n")).collect();
    std::fs::write(
        &path,
        format!(
            r#"Scene(
            camera: {camera},
            render: (width: 48, height: 32, spp: {spp}, max_depth: 8, rr_depth: 3),
            background: Sky(bottom: (0.1, 0.1, 0.1), top: (0.4, 0.5, 0.7)),
            materials: {{
                {materials}
                "lamp": DiffuseLight(emit: (30, 30, 30), two_sided: true),
                "panel": DiffuseLight(emit: (2, 2, 2)),
            }},
            textures: {{"checks": UvChecker(u: 8, v: 4, even: (0.8, 0.3, 0.1), odd: (0.1, 0.3, 0.8))}},
            objects: [{objects}],
            lights: [{lights}],
        )"#
        ),
    )
    .unwrap();
    pathwave::engine::scene::load(&path).unwrap()
}

/// The wavefront integrator gives the oracle's bits on `desc` (but a pixel or two: see
/// [`reproduces_the_oracle_for_any_batch_and_thread_count`]), in batches of one path on one
/// thread, seven on two and all at once.
fn assert_oracle_bits(desc: &SceneDesc, what: &str) {
    let oracle = render_threads(desc, 2);
    for (batch, threads) in [(1, 1), (7, 2), (100_000, 2)] {
        let (film, stats) = wavefront(desc, batch, threads);
        assert_eq!(stats.paths, (film.width * film.height * film.spp) as u64);
        let differing = film.pixels.iter().zip(&oracle.pixels).filter(|(a, b)| a != b).count();
        assert!(
            differing <= 2,
            "{what}, batch {batch}, {threads} threads: {differing} pixels differ from the oracle"
        );
    }
}

/// Smooth-shaded meshes (vertex normals: adapted shading normals, lifted ray origins, and
/// directions the two normals disagree about) take the same shared code in both integrators:
/// a coarse sphere mesh in each material kind that shades ([`SHADING_KINDS`]: Lambertian,
/// fuzzy metals and a perfect mirror, both rough ones with either distribution, the Beckmann ones with
/// height-correlated shadowing, glass (exact and Schlick's Fresnel), a thin pane, plastics, textured rough plastic, a textured principled,
/// a textured thin principled, a textured glTF metallic-roughness and an anisotropic rough
/// conductor), one of them sheared, under a lamp, a point light and the sky, gives the
/// oracle's bits. Seen again close up under a bright panel, which the BSDFs' sampled
/// directions often meet: there the emitter's MIS weight reads each kernel's sampled density.
#[test]
fn reproduces_the_oracle_on_smooth_shaded_meshes() {
    let objects = r#"
        (shape: Quad(q: (-6, -1, -6), u: (0, 0, 12), v: (12, 0, 0)), material: "white"),
        (shape: Mesh(file: "ball.obj"), material: "plastic", transform: [UniformScale(0.7), Translate((-3.6, -0.3, 0.5))]),
        (shape: Mesh(file: "ball.obj"), material: "rough_plastic", transform: [UniformScale(0.7), Translate((3.6, -0.3, 0.5))]),
        (shape: Mesh(file: "ball.obj"), material: "white", transform: [Translate((-3, 0, 0))]),
        (shape: Mesh(file: "ball.obj"), material: "metal", transform: [Shear(xy: 0.3), Translate((-1.2, 0, 0))]),
        (shape: Mesh(file: "ball.obj"), material: "gold", transform: [Translate((0.6, 0, 0))]),
        (shape: Mesh(file: "ball.obj"), material: "frost", transform: [Translate((2.4, 0, 0))]),
        (shape: Mesh(file: "ball.obj"), material: "glass", transform: [UniformScale(0.7), Translate((0, 0.5, 2))]),
        (shape: Mesh(file: "ball.obj"), material: "copper", transform: [UniformScale(0.6), Translate((-2, 0.2, 2))]),
        (shape: Mesh(file: "ball.obj"), material: "etched", transform: [UniformScale(0.6), Translate((2, 0.2, 2))]),
        (shape: Quad(q: (4, 3, -1), u: (0, 0, 1), v: (-0.3, 1, 0)), material: "lamp"),
        (shape: Mesh(file: "ball.obj"), material: "principled", transform: [UniformScale(0.5), Translate((-0.8, 1.4, 1))]),
        (shape: Mesh(file: "ball.obj"), material: "brushed", transform: [UniformScale(0.5), Translate((0.8, 1.4, 1))]),
        (shape: Mesh(file: "ball.obj"), material: "leaf", transform: [UniformScale(0.4), Translate((0, 2.2, 0.5))]),
        (shape: Mesh(file: "ball.obj"), material: "gltf", transform: [UniformScale(0.4), Translate((-2.2, 1.6, 0.5))]),
    "#;
    let camera = "(look_from: (0, 2, 9), look_at: (0, 0.5, 0), vfov: 40)";
    let point = "Point(position: (-4, 4, 3), intensity: (20, 20, 20))";
    assert_oracle_bits(&shading_kinds_scene(camera, objects, point, 6), "the scene");
    // Each kind on a grid four wide, under a panel as large as the grid.
    let grid: String = SHADING_KINDS
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            let (x, z) = (((i % 4) as f32 - 1.5) * 1.1, ((i / 4) as f32 - 1.5) * 1.1);
            format!(r#"(shape: Mesh(file: "ball.obj"), material: "{name}", transform: [UniformScale(0.45), Translate(({x}, 0, {z}))]),"#)
        })
        .collect();
    let objects = format!(
        r#"(shape: Quad(q: (-2.5, 2.5, -2.5), u: (5, 0, 0), v: (0, 0, 6)), material: "panel"), {grid}"#
    );
    let camera = "(look_from: (0, 2.2, 5), look_at: (0, 0, 0), vfov: 40)";
    assert_oracle_bits(&shading_kinds_scene(camera, &objects, "", 16), "under a panel");
}

/// An SDF grid (a ball, smooth- and flat-shaded) and one-sided Lambertians (Mitsuba's
/// `diffuse`: paths that meet one from behind end there) take the same code in both
/// integrators: the oracle's bits. The backs of the one-sided quad and the inside of the
/// one-sided cylinder render black, where the two-sided ones do not.
#[test]
fn reproduces_the_oracle_on_sdf_grids_and_one_sided_lambertians() {
    let dir = tempfile::tempdir().unwrap();
    // A .vol grid (Mitsuba's format) of 12^3 distances to a ball of radius 0.35.
    let n = 12;
    let mut vol = b"VOL\x03".to_vec();
    for v in [1i32, n, n, n, 1] {
        vol.extend(v.to_le_bytes());
    }
    vol.extend([0u8; 24]);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = |i: i32| i as f32 / (n - 1) as f32 - 0.5;
                let d = (c(x) * c(x) + c(y) * c(y) + c(z) * c(z)).sqrt() - 0.35;
                vol.extend(d.to_le_bytes());
            }
        }
    }
    std::fs::write(dir.path().join("ball.vol"), vol).unwrap();
    let path = dir.path().join("sdf.ron");
    let scene = |one_sided: bool| {
        format!(
            r#"Scene(
            camera: (look_from: (0, 2, 9), look_at: (0, 0.5, 0), vfov: 40),
            render: (width: 48, height: 32, spp: 6, max_depth: 6, rr_depth: 3),
            background: Sky(bottom: (0.1, 0.1, 0.1), top: (0.4, 0.5, 0.7)),
            materials: {{
                "white": Lambertian(albedo: (0.7, 0.7, 0.7)),
                "front": Lambertian(albedo: (0.6, 0.5, 0.4), two_sided: {}),
                "lamp": DiffuseLight(emit: (30, 30, 30), two_sided: true),
                "panel": DiffuseLight(emit: (2, 2, 2)),
            }},
            objects: [
                (shape: Quad(q: (-6, -1, -6), u: (0, 0, 12), v: (12, 0, 0)), material: "white"),
                (shape: SdfGrid(file: "ball.vol"), material: "front", transform: [UniformScale(2), Translate((-3, -0.5, 0))]),
                (shape: SdfGrid(file: "ball.vol", normals: Analytic), material: "white", transform: [Scale((2, 1.5, 2)), Translate((-0.5, -0.5, 1))]),
                (shape: Quad(q: (1, -1, 0), u: (0, 2, 0), v: (1, 0, 1)), material: "front"),
                (shape: Cylinder(p0: (3, -1, 0), p1: (3.5, 1, 1), radius: 0.8), material: "front"),
                (shape: Quad(q: (4, 3, -1), u: (0, 0, 1), v: (-0.3, 1, 0)), material: "lamp"),
            ],
            lights: [Point(position: (-4, 4, 3), intensity: (20, 20, 20))],
        )"#,
            !one_sided
        )
    };
    let mut images = Vec::new();
    for one_sided in [true, false] {
        std::fs::write(&path, scene(one_sided)).unwrap();
        let desc = pathwave::engine::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let oracle = render_threads(&desc, 2);
        for (batch, threads) in [(1, 1), (7, 2), (100_000, 2)] {
            let (film, stats) = wavefront(&desc, batch, threads);
            assert_eq!(stats.paths, (film.width * film.height * film.spp) as u64);
            let differing = film.pixels.iter().zip(&oracle.pixels).filter(|(a, b)| a != b).count();
            assert!(
                differing <= 2,
                "one-sided {one_sided}, batch {batch}, {threads} threads: {differing} pixels differ from the oracle"
            );
        }
        images.push(oracle.mean());
    }
    // The one-sided image is darker where backs are seen, and only there.
    let darker =
        images[0].iter().zip(&images[1]).filter(|(a, b)| a.element_sum() < 0.5 * b.element_sum()).count();
    let brighter = images[0]
        .iter()
        .zip(&images[1])
        .filter(|(a, b)| a.element_sum() > 1.5 * b.element_sum() + 0.05)
        .count();
    assert!(darker > 20 && brighter == 0, "{darker} pixels darker, {brighter} brighter");
}

/// Exact pixel sums: rendering the samples in passes and merging the films gives the bits of
/// one render, with either integrator (what checkpoints and resumed renders rely on).
#[test]
fn sample_ranges_merge_into_the_whole_render() {
    for name in ["cornell.ron", "spheres-sky.ron"] {
        let desc = small(name, 7);
        let scene = SceneWorld::render_scene(&desc);
        let whole = wavefront::render(&scene, Options::default(), &|_, _| {}).0;
        let mut parts = Film::new(whole.width, whole.height);
        for range in [0..1, 1..4, 4..7] {
            parts.merge(&wavefront::render_samples(&scene, Options::default(), range, &|_, _| {}).0);
        }
        assert!(parts == whole, "{name}: wavefront passes differ from one render");
        let mut oracle_parts = oracle::render_samples(&scene, 0..3, &|_, _| {});
        oracle_parts.merge(&oracle::render_samples(&scene, 3..7, &|_, _| {}));
        assert!(oracle_parts == oracle::render(&scene, &|_, _| {}), "{name}: oracle passes differ");
        // A pass is not a copy of another: the split can fail.
        let mut twice = wavefront::render_samples(&scene, Options::default(), 0..3, &|_, _| {}).0;
        twice.merge(&wavefront::render_samples(&scene, Options::default(), 0..4, &|_, _| {}).0);
        assert!(twice != whole, "{name}");
    }
}

#[test]
fn agrees_with_the_oracle_in_expectation_and_detects_a_5_percent_error() {
    let mut desc = scene("cornell-diffuse.ron");
    desc.render.width = 64.try_into().unwrap();
    desc.render.height = 64.try_into().unwrap();
    desc.render.spp = 64.try_into().unwrap();
    let oracle = render(&desc);
    let reference = LinearImage { width: 64, height: 64, pixels: oracle.mean() };
    desc.render.seed = 12345;
    let stats = block_z(&wavefront(&desc, 1024, 2).0, &reference, 8, 64);
    assert!(stats.agrees(), "{stats:?}");
    scale_albedo(&mut desc, "white", 1.05);
    let stats = block_z(&wavefront(&desc, 1024, 2).0, &reference, 8, 64);
    assert!(!stats.agrees(), "a 5% albedo error went unnoticed: {stats:?}");
}

#[test]
fn trace_file_names_the_stages_and_stats_print_a_table() {
    let dir = std::env::temp_dir().join(format!("pathwave-trace-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (trace, image) = (dir.join("t.json"), dir.join("c.png"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args([
            "render",
            "scenes/cornell.ron",
            "--spp",
            "2",
            "--width",
            "32",
            "--height",
            "32",
            "-q",
            "--stats",
        ])
        .arg("-o")
        .arg(&image)
        .arg("--trace")
        .arg(&trace)
        .current_dir(root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    for stage in ["generate_camera_rays", "intersect_closest", "shade_lambertian", "trace_shadow_rays"] {
        assert!(stderr.contains(stage), "--stats lacks {stage}:\n{stderr}");
    }
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).unwrap();
    let events = json["traceEvents"].as_array().expect("a trace-event file");
    let named = |name: &str| events.iter().filter(move |e| e["name"] == name).collect::<Vec<_>>();
    let interval = |e: &serde_json::Value| {
        let ts = e["ts"].as_f64().unwrap();
        (ts, ts + e["dur"].as_f64().unwrap())
    };
    // Outer spans with their fields as args.
    for span in ["load_scene", "rebuild_geometry", "pass", "wavefront_render"] {
        assert_eq!(named(span).len(), 1, "one {span} span");
    }
    assert_eq!(named("pass")[0]["args"]["samples"], 2);
    assert!(named("load_scene")[0]["args"]["file"].as_str().unwrap().ends_with("cornell.ron"));
    // One tile span per 16x16 tile, inside the pass; each stage once per tile, inside its
    // tile on the same thread, with its items.
    let tiles = named("tile");
    assert_eq!(tiles.len(), 4, "32x32 is four tiles");
    let pass = interval(named("pass")[0]);
    for t in &tiles {
        let (a, b) = interval(t);
        assert!(a >= pass.0 && b <= pass.1, "a tile outside its pass");
    }
    for stage in
        ["generate_camera_rays", "intersect_closest", "shade_lambertian", "shade_metal", "accumulate_film"]
    {
        let list = named(stage);
        assert_eq!(list.len(), 4, "{stage}: once per tile");
        for e in list {
            assert!(e["args"]["items"].as_u64().unwrap() > 0, "{stage} has items");
            let (a, b) = interval(e);
            let inside = tiles.iter().any(|t| {
                let (ta, tb) = interval(t);
                t["tid"] == e["tid"] && a >= ta - 1e-3 && b <= tb + 1e-3
            });
            assert!(inside, "{stage} at {a}..{b} lies in no tile of its thread");
        }
    }
    // Counter tracks.
    let counters = events.iter().filter(|e| e["ph"] == "C").count();
    assert_eq!(counters, 3 * 4, "three counters per tile");
    assert_eq!(named("queue occupancy %").len(), 4);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Shading loops exist only for material kinds that some object uses.
#[test]
fn unused_materials_add_no_shading_loop() {
    use pathwave::engine::material::MaterialKind;
    use pathwave::integrator::wavefront::material_kinds;
    let diffuse = SceneWorld::render_scene(&scene("cornell-diffuse.ron"));
    assert_eq!(material_kinds(&diffuse), vec![MaterialKind::Lambertian]);
    let with_unused = inline(
        r#"Scene(
            camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
            materials: {
                "glass": Dielectric(ior: 1.5),
                "steel": Metal(albedo: (0.8, 0.8, 0.8)),
                "white": Lambertian(albedo: (0.7, 0.7, 0.7)),
            },
            objects: [(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white")],
        )"#,
    );
    assert_eq!(material_kinds(&SceneWorld::render_scene(&with_unused)), vec![MaterialKind::Lambertian]);
    let cornell = SceneWorld::render_scene(&scene("cornell.ron"));
    assert_eq!(material_kinds(&cornell).len(), 3);
}

/// `clamp` bounds every sample, so every pixel mean; without it the light (radiance 15) shows.
#[test]
fn clamping_bounds_samples_and_is_off_by_default() {
    let mut desc = scene("cornell.ron");
    desc.render.width = 32.try_into().unwrap();
    desc.render.height = 32.try_into().unwrap();
    desc.render.spp = 8.try_into().unwrap();
    let brightest =
        |d: &SceneDesc| wavefront(d, 1024, 2).0.mean().iter().map(|p| p.max_element()).fold(0.0, f32::max);
    assert!(brightest(&desc) > 10.0, "unclamped, the light is seen at radiance 15");
    desc.render.clamp = Some(pathwave::engine::scene::Positive(1.0));
    assert!(brightest(&desc) <= 1.0);
}

/// The stage inputs that `benches/core.rs` times: captured in pipeline order before each stage
/// of one iteration, and each stage run on its copy hands the next stages what they met in
/// the render (every active ray binned once; shading fills the shadow queue the shadow stage
/// took).
#[test]
fn captured_stage_inputs_feed_the_next_stages_as_in_the_render() {
    use pathwave::integrator::wavefront::{Stage, capture_stages};
    let scene = SceneWorld::render_scene(&small("cornell.ron", 16));
    let inputs = capture_stages(&scene, Options::default(), 0, 5);
    let stages: Vec<Stage> = inputs.iter().map(|i| i.stage).collect();
    let order = |s: Stage| Stage::ALL.iter().position(|&a| a == s).unwrap();
    assert!(stages.windows(2).all(|w| order(w[0]) < order(w[1])), "{stages:?}");
    for s in [Stage::IntersectClosest, Stage::TraceShadowRays, Stage::AccumulateFilm] {
        assert!(stages.contains(&s), "{s:?} has work in iteration 5: {stages:?}");
    }
    let input = |s: Stage| inputs.iter().find(|i| i.stage == s);
    let after = |s: Stage| {
        let mut i = input(s).unwrap().clone();
        i.run();
        i
    };
    let items = |s: Stage| input(s).map_or(0, |i| i.items);
    let traced = after(Stage::IntersectClosest);
    let binned: usize =
        Stage::ALL.iter().filter(|s| matches!(s, Stage::Shade(_))).map(|&s| traced.items_of(s)).sum();
    let active = items(Stage::IntersectClosest);
    assert_eq!(
        traced.items_of(Stage::HandleEscaped) + traced.items_of(Stage::HandleEmissive) + binned,
        active
    );
    for s in [Stage::HandleEscaped, Stage::HandleEmissive] {
        assert_eq!(traced.items_of(s), items(s), "{s:?}");
    }
    // The last shading stage leaves the shadow queue the shadow stage took.
    let last_shade = *stages.iter().rfind(|s| matches!(s, Stage::Shade(_))).unwrap();
    assert_eq!(after(last_shade).items_of(Stage::TraceShadowRays), items(Stage::TraceShadowRays));
    assert!(capture_stages(&scene, Options::default(), 0, 1 << 40).is_empty(), "no such iteration");
}
