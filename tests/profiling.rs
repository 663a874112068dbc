//! Profiling that answers "why is this slow, and where is this noise from", on a scene built so
//! that the answers are known (`scenes/still-life.ron`): a white room, one small bright lamp and
//! a small glass ball, whose pixels cost the most and which focuses the lamp into a caustic.
//! - The costs per pixel (`--aov time,paths,bounces,rays`, `--stats`' heat map and slowest
//!   tiles) put the time on the ball and change nothing in the image.
//! - The noise by cause (`diagnose`, `--stats`' tables) names the ball's glass and the lamp as
//!   the outliers' source, and the shares of the variance add up.

mod common;
use common::root;
use pathwave::engine::render_scene::RenderScene;
use pathwave::engine::scene::load_with;
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::diagnose::{self, Event, Light, Vertex};
use pathwave::integrator::{oracle, path, wavefront};
use pathwave::io::read_exr_channels;
use std::path::PathBuf;
use std::sync::Arc;

/// Held by each test while it runs: the timed one runs alone.
static ALONE: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-profiling-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The still life at `size` x `size` with `spp` samples, its ball of material `ball`.
fn still_life(size: u32, spp: u32, ball: &str) -> (Arc<RenderScene>, Vec<String>) {
    let overrides = [("ball".to_string(), format!("{ball:?}"))];
    let mut desc = load_with(&root().join("scenes/still-life.ron"), &overrides).unwrap();
    desc.render.width = size.try_into().unwrap();
    desc.render.height = size.try_into().unwrap();
    desc.render.spp = spp.try_into().unwrap();
    let names = desc.materials.iter().map(|(n, _)| n.clone()).collect();
    (SceneWorld::render_scene(&desc), names)
}

/// Which pixels see the ball first (their centre's camera ray).
fn ball_pixels(scene: &RenderScene, ball: u32) -> Vec<bool> {
    let s = scene.settings;
    (0..s.height)
        .flat_map(|y| (0..s.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (ray, tmax, _) = path::camera_ray(scene, x, y, 0);
            scene.intersect(&ray, tmax).is_some_and(|h| h.material == ball)
        })
        .collect()
}

fn pathwave() -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"));
    c.current_dir(root());
    c
}

#[test]
fn the_time_goes_to_the_glass_ball_and_the_image_stays_the_same() {
    let dir = temp("costs");
    let (size, spp) = (64, 16);
    let render = |out: &PathBuf, extra: &[&str]| {
        let run = pathwave()
            .args(["render", "scenes/still-life.ron", "--width", "64", "--height", "64", "--spp", "16", "-o"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&run.stderr).into_owned();
        assert!(run.status.success(), "{log}");
        log
    };
    let (plain, measured) = (dir.join("plain.exr"), dir.join("measured.exr"));
    render(&plain, &["-q"]);
    // The clock: one thread, and no other test of this file beside it (the others hold the
    // lock too), so that preemption does not blur the stages' times.
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let log = render(&measured, &["--stats", "--aov", "time,paths,bounces,rays", "--threads", "1"]);
    let (a, b) = (read_exr_channels(&plain).unwrap(), read_exr_channels(&measured).unwrap());
    let channel = |c: &pathwave::io::ExrChannels, name: &str| {
        c.channels.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}")).1.clone()
    };
    for rgb in ["R", "G", "B"] {
        assert_eq!(channel(&a, rgb), channel(&b, rgb), "measuring changed the image ({rgb})");
    }
    let (time, paths, bounces, rays) =
        (channel(&b, "time.Y"), channel(&b, "paths.Y"), channel(&b, "bounces.Y"), channel(&b, "rays.Y"));
    assert!(paths.iter().all(|&n| n == spp as f32), "every pixel's samples counted");
    // A path casts a closest-hit ray per vertex and at most one shadow ray per bounce.
    for k in 0..time.len() {
        assert!(rays[k] >= paths[k] * (1.0 + bounces[k]) - 0.5, "pixel {k}: {} rays", rays[k]);
        assert!(rays[k] <= paths[k] * (1.0 + 2.0 * bounces[k]) + 0.5, "pixel {k}: {} rays", rays[k]);
    }
    // A pixel's time follows the work its paths did: its rays.
    let correlation = {
        let n = time.len() as f64;
        let (mt, mr) = (time.iter().sum::<f32>() as f64 / n, rays.iter().sum::<f32>() as f64 / n);
        let (mut c, mut vt, mut vr) = (0.0, 0.0, 0.0);
        for (&t, &r) in time.iter().zip(&rays) {
            let (dt, dr) = (t as f64 - mt, r as f64 - mr);
            (c, vt, vr) = (c + dt * dr, vt + dt * dt, vr + dr * dr);
        }
        c / (vt * vr).sqrt()
    };
    println!("correlation of time and rays over the pixels: {correlation:.3}");
    assert!(correlation > 0.8, "{correlation}");
    // The ball's pixels cost more than the room's, and their paths go on longer.
    let (scene, names) = still_life(size, spp, "glass");
    let glass = names.iter().position(|n| n == "glass").unwrap() as u32;
    let ball = ball_pixels(&scene, glass);
    let mean = |v: &[f32], on: bool| {
        let picked: Vec<f32> = v.iter().zip(&ball).filter(|(_, b)| **b == on).map(|(x, _)| *x).collect();
        picked.iter().sum::<f32>() / picked.len() as f32
    };
    println!(
        "time per pixel: ball {:.1} us, room {:.1} us",
        mean(&time, true) * 1e6,
        mean(&time, false) * 1e6
    );
    println!("bounces: ball {:.2}, room {:.2}", mean(&bounces, true), mean(&bounces, false));
    assert!(mean(&time, true) > 1.2 * mean(&time, false), "the ball's pixels are not the costly ones");
    assert!(mean(&bounces, true) > mean(&bounces, false));
    // `--stats` lists the slowest tiles: one of the three slowest lies on the ball (tiles
    // of the room near it take about as long; which one comes first is up to the clock).
    let slowest: Vec<&str> =
        log.lines().skip_while(|l| !l.starts_with("slowest tiles")).skip(1).take(3).collect();
    let on_ball = |line: &str| {
        let numbers: Vec<u32> = line
            .split(|c: char| !c.is_ascii_digit())
            .filter(|s| !s.is_empty())
            .take(4)
            .map(|s| s.parse().unwrap())
            .collect();
        let [x0, x1, y0, y1] = numbers[..] else { panic!("{line}") };
        (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).any(|(x, y)| ball[(y * size + x) as usize])
    };
    assert!(slowest.iter().any(|l| on_ball(l)), "the slowest tiles miss the ball: {slowest:#?}");
    let heat = image::open(dir.join("measured.time.png")).unwrap().to_rgb8();
    assert_eq!(heat.dimensions(), (size, size));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The diagnosis of all the samples of a render of `scene`.
fn diagnosis(scene: &RenderScene) -> diagnose::Diagnosis {
    let film = oracle::render(scene, &|_, _| {});
    let mean: Vec<f32> = film.mean().iter().map(|&c| pathwave::engine::math::luminance(c)).collect();
    diagnose::diagnose(scene, 0..film.spp, &mean, film.spp)
}

#[test]
fn the_noise_comes_from_the_lamp_through_the_glass() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let (scene, names) = still_life(48, 64, "glass");
    let id = |name: &str| names.iter().position(|n| n == name).unwrap() as u32;
    let d = diagnosis(&scene);
    assert_eq!((d.pixels, d.samples), (48 * 48, 48 * 48 * 64));
    // The parts of a sample add up to it, so the shares add up to the variance.
    let light_sum: f64 = d.by_light.values().sum();
    let vertex_sum: f64 = d.by_vertex.values().sum();
    assert!((light_sum / d.variance - 1.0).abs() < 1e-6, "{light_sum} vs {}", d.variance);
    assert!((vertex_sum / d.variance - 1.0).abs() < 1e-6, "{vertex_sum} vs {}", d.variance);
    assert_eq!(d.by_light.keys().collect::<Vec<_>>(), [&Light::Emitter(id("lamp"))]);
    let glass = d.by_vertex[&Vertex::Material(id("glass"))] / d.variance;
    println!("the glass's share of the variance: {:.1}%", 100.0 * glass);
    assert!(glass > 0.05, "{:?}", d.by_vertex);
    // The outliers: mostly caustics through the glass.
    let share = |f: &dyn Fn(&diagnose::Cause) -> bool| {
        d.outliers.iter().filter(|o| f(&o.cause)).map(|o| o.excess).sum::<f64>()
            / d.outliers.iter().map(|o| o.excess).sum::<f64>()
    };
    let through_glass = share(&|c| c.vertex == Vertex::Material(id("glass")));
    let caustics = share(&|c| c.event == Event::Caustic);
    println!(
        "outliers: {} at the glass {:.1}%, caustics {:.1}%",
        d.outliers.len(),
        100.0 * through_glass,
        100.0 * caustics
    );
    assert!(d.outliers.len() >= 30);
    assert!(through_glass > 0.5 && caustics > 0.5);
    // Rough glass: no caustic, the lamp found by light sampling.
    let (scene, names) = still_life(48, 64, "frosted");
    let d = diagnosis(&scene);
    assert!(d.outliers.iter().all(|o| o.cause.event != Event::Caustic));
    let frosted = names.iter().position(|n| n == "frosted").unwrap() as u32;
    assert!(d.by_vertex.contains_key(&Vertex::Material(frosted)));
}

/// Glowing media are a source of their own: where a glowing plume is the only light but a dim
/// sky (`scenes/smoke-glow.ron`), nearly all the variance and the outliers come from it, found
/// where paths scattered in it. (Before they were a source, their part was nobody's and the
/// shares went to the sky.)
#[test]
fn the_noise_of_a_glowing_plume_comes_from_its_glow() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let mut desc = load_with(&root().join("scenes/smoke-glow.ron"), &[]).unwrap();
    desc.render.width = 48.try_into().unwrap();
    desc.render.height = 48.try_into().unwrap();
    desc.render.spp = 16.try_into().unwrap();
    let d = diagnosis(&SceneWorld::render_scene(&desc));
    let glow = d.by_light.get(&Light::Media).copied().unwrap_or(0.0) / d.variance;
    assert!(glow > 0.95, "glowing media's share {glow}: {:?}", d.by_light);
    assert!(!d.outliers.is_empty() && d.outliers.iter().all(|o| o.cause.light == Light::Media));
}

#[test]
fn stats_name_the_glass_and_the_lamp() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let dir = temp("stats");
    let run = pathwave()
        .args([
            "render",
            "scenes/still-life.ron",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "512",
            "--stats",
            "-o",
        ])
        .arg(dir.join("s.png"))
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    let line = |start: &str| {
        log.lines().find(|l| l.trim_start().starts_with(start)).unwrap_or_else(|| panic!("{log}"))
    };
    assert!(line("from light:").contains("\"lamp\" 100.0%"), "{log}");
    assert!(line("at material:").trim_start().starts_with("at material: \"glass\""), "{log}");
    assert!(line("by:").trim_start().starts_with("by: a caustic"), "{log}");
    assert!(line("most of the outliers").contains("through \"glass\""), "{log}");
    assert!(line("shading time by material").contains('%'), "{log}");
    let by_light = log.lines().skip_while(|l| !l.starts_with("shadow rays' time by the light")).nth(1);
    assert!(by_light.is_some_and(|l| l.trim_start().starts_with("\"lamp\"")), "{log}");
    // The ball is the scene file's objects[7].
    assert!(line("the costliest per pixel:").contains("objects[7] (\"glass\")"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn animate_stats_say_what_each_frame_built_and_which_were_slow() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let dir = temp("animate");
    let run = pathwave()
        .args(["animate", "scenes/animation-bounce.ron", "--frames", "0..3", "--spp", "2", "--width", "32"])
        .args(["--height", "32", "--stats", "-o"])
        .arg(dir.join("f{frame}.png"))
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    for f in 0..3 {
        let line = log
            .lines()
            .find(|l| l.starts_with(&format!("frame {f}: scene update")))
            .unwrap_or_else(|| panic!("{log}"));
        assert!(line.contains("us per sample"), "{line}");
        // The first frame builds everything; the bouncing ball's frames after it rebuild the
        // primitives' BVH and keep the rest.
        match f {
            0 => assert!(line.contains("(BVH rebuilt, TLAS rebuilt, BLAS built"), "{line}"),
            _ => assert!(line.contains("BVH rebuilt") && line.contains("BLAS, media kept"), "{line}"),
        }
        let heat = image::open(dir.join(format!("f{f}.time.png"))).unwrap();
        assert_eq!((heat.width(), heat.height()), (32, 32));
    }
    let slowest = log.lines().skip_while(|l| !l.starts_with("slowest frames")).skip(1).count();
    assert_eq!(slowest, 3, "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// materials-env: its noise comes from the map's sun, and mostly through the frosted glass.
#[test]
fn materials_env_noise_comes_from_the_sun_through_the_frosted_glass() {
    let _alone = ALONE.lock().unwrap_or_else(|e| e.into_inner());
    let mut desc = common::scene("materials-env.ron");
    (desc.render.width, desc.render.height, desc.render.spp) =
        (96.try_into().unwrap(), 64.try_into().unwrap(), 32.try_into().unwrap());
    let names: Vec<String> = desc.materials.iter().map(|(n, _)| n.clone()).collect();
    let scene = SceneWorld::render_scene(&desc);
    let d = diagnosis(&scene);
    let top = |f: &dyn Fn(&diagnose::Cause) -> String| {
        let mut by: Vec<(String, f64)> = Vec::new();
        for o in &d.outliers {
            let k = f(&o.cause);
            match by.iter_mut().find(|(n, _)| *n == k) {
                Some((_, e)) => *e += o.excess,
                None => by.push((k, o.excess)),
            }
        }
        by.sort_by(|a, b| b.1.total_cmp(&a.1));
        println!("{by:?}");
        by[0].0.clone()
    };
    assert_eq!(top(&|c| format!("{:?}", c.light)), "BackgroundPeak");
    let material = |v: Vertex| match v {
        Vertex::Material(id) => names[id as usize].clone(),
        other => format!("{other:?}"),
    };
    assert_eq!(top(&|c| material(c.vertex)), "frosted");
    // The sun's share of the variance is the largest of the lights'.
    let sun = d.by_light[&Light::BackgroundPeak];
    assert!(d.by_light.values().all(|&v| v <= sun), "{:?}", d.by_light);
}

/// The shadow rays' time goes to the light each was aimed at. Of two equal lamps, the one
/// above a floor lights what the camera sees (the floor's top) and the one below it lights
/// nothing there (no shadow ray is cast through the floor), though light sampling picks each
/// half the time: every shadow ray, and so its time, is the upper lamp's. The lower lamp comes
/// first in the light table (charging every ray to the first entry fails), and a light read at
/// another depth than the vertex's (tried) splits the time evenly.
#[test]
fn shadow_rays_time_goes_to_the_lamp_they_aim_at() {
    let desc = common::inline(
        r#"Scene(
            camera: (look_from: (0, 3, 3), look_at: (0, 0, 0), vfov: 40),
            render: (width: 32, height: 32, spp: 16, max_depth: 4),
            materials: {
                "floor": Lambertian(albedo: (0.5, 0.5, 0.5)),
                "below": DiffuseLight(emit: (4, 4, 4)),
                "above": DiffuseLight(emit: (4, 4, 4)),
            },
            objects: [
                (shape: Quad(q: (-0.5, -1, -0.5), u: (1, 0, 0), v: (0, 0, 1)), material: "below"),
                (shape: Quad(q: (-5, 0, -5), u: (10, 0, 0), v: (0, 0, 10)), material: "floor"),
                (shape: Quad(q: (-0.5, 2, -0.5), u: (1, 0, 0), v: (0, 0, 1)), material: "above"),
            ],
        )"#,
    );
    let names: Vec<String> = desc.materials.iter().map(|(n, _)| n.clone()).collect();
    let scene = SceneWorld::render_scene(&desc);
    let opts = wavefront::Options { costs: true, ..Default::default() };
    let (_, stats) = wavefront::render(&scene, opts, &|_, _| {});
    let mut by = std::collections::HashMap::<Light, f64>::new();
    for (k, t) in stats.light_time.iter().enumerate() {
        *by.entry(Light::of(&scene, k)).or_default() += t.as_secs_f64();
    }
    let lamp = |name: &str| Light::Emitter(names.iter().position(|n| n == name).unwrap() as u32);
    let (above, below) = (by[&lamp("above")], by.get(&lamp("below")).copied().unwrap_or(0.0));
    println!("shadow rays' time: above {above:.2e} s, below {below:.2e} s");
    assert!(above > 0.0 && below <= 1e-3 * above, "above {above}, below {below}");
    assert!(Light::of(&scene, 0) == lamp("below"), "the lower lamp is the table's first");
}
