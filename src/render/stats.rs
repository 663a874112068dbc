//! The `--stats` report: per-stage time shares, items and rates; where the time went (a heat
//! map of time per pixel, the slowest tiles, time by material); where the noise comes from.

use crate::engine::render_scene::{PixelWindow, RenderScene};
use crate::integrator::costs::PixelCosts;
use crate::integrator::diagnose::{self, Cause, Event, Light, Vertex};
use crate::integrator::tile::Tile;
use crate::integrator::wavefront;
use crate::io;
use std::path::Path;

/// Each stage's share of the time, `name 12.3%`, largest first.
pub fn stage_shares(st: &wavefront::Stats) -> String {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    let mut shares: Vec<(f64, &str)> = wavefront::Stage::ALL
        .iter()
        .filter(|s| st.calls[s.index()] > 0)
        .map(|s| (st.time[s.index()].as_secs_f64() / total.max(1e-12), s.name()))
        .collect();
    shares.sort_by(|a, b| b.0.total_cmp(&a.0));
    let list: Vec<String> = shares.iter().map(|(f, n)| format!("{n} {:.1}%", 100.0 * f)).collect();
    list.join(", ")
}

/// The `--stats` table on stderr.
pub fn print_stats(st: &wavefront::Stats, wall: f64, non_finite: u64) {
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    eprintln!("{:<22} {:>7} {:>12} {:>10} {:>9}", "stage", "time %", "items", "M items/s", "calls");
    for stage in wavefront::Stage::ALL {
        let k = stage.index();
        if st.calls[k] == 0 {
            continue;
        }
        let t = st.time[k].as_secs_f64();
        eprintln!(
            "{:<22} {:>6.1}% {:>12} {:>10.2} {:>9}",
            stage.name(),
            100.0 * t / total,
            st.items[k],
            st.items[k] as f64 / t / 1e6,
            st.calls[k]
        );
    }
    let ix = wavefront::Stage::IntersectClosest.index();
    let sh = wavefront::Stage::TraceShadowRays.index();
    let rays = st.items[ix] + st.items[sh];
    eprintln!(
        "{} iterations, mean queue occupancy {:.1}%; {} rays ({} closest, {} shadow): {:.2} Mrays/s; {:.3} M samples/s; {} NaN/Inf discarded; lanes {}",
        st.iterations,
        100.0 * st.occupancy_sum / st.iterations.max(1) as f64,
        rays,
        st.items[ix],
        st.items[sh],
        rays as f64 / wall / 1e6,
        st.paths as f64 / wall / 1e6,
        non_finite,
        crate::engine::simd::isa_name()
    );
}

/// How many of the slowest tiles and costliest materials `--stats` lists.
const LISTED: usize = 5;

/// `--stats`' places: writes the heat map of time per pixel to `heat_map`
/// ([`write_heat_map`]), then prints the slowest tiles (their pixels and `--crop` fractions, against the
/// median tile) and the shading time of each material (`names`, by material id).
pub fn report_costs(
    scene: &RenderScene,
    costs: &PixelCosts,
    st: &wavefront::Stats,
    names: &[String],
    heat_map: &Path,
) -> Result<(), String> {
    let s = &scene.settings;
    let window = &s.window;
    let top = write_heat_map(costs, (window.w, window.h), heat_map)?;
    eprintln!(
        "{}: time per pixel, black 0 to yellow {:.1} us and above (the 99.5th percentile); {:.1} us per pixel on average",
        heat_map.display(),
        top * 1e6,
        costs.total_time() / costs.len() as f64 * 1e6
    );
    let mut tiles = tile_times(costs, window);
    let median = {
        let mut t: Vec<f64> = tiles.iter().map(|(_, t)| *t).collect();
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    tiles.sort_by(|a, b| b.1.total_cmp(&a.1));
    eprintln!("slowest tiles (of {}, median {:.2} ms):", tiles.len(), median * 1e3);
    for (tile, t) in tiles.iter().take(LISTED) {
        let [a, b, c, d] = crop_of(tile, s.width, s.height);
        eprintln!(
            "  x {}..{}, y {}..{} {:>9.2} ms {:>5.1}x the median  (--crop {a},{b},{c},{d})",
            tile.x0,
            tile.x0 + tile.w,
            tile.y0,
            tile.y0 + tile.h,
            t * 1e3,
            t / median.max(1e-12),
        );
    }
    by_object(scene, costs, names);
    let shading: f64 = st.material_time.iter().map(|t| t.as_secs_f64()).sum();
    let mut by_material: Vec<(usize, f64)> =
        st.material_time.iter().map(|t| t.as_secs_f64()).enumerate().filter(|(_, t)| *t > 0.0).collect();
    by_material.sort_by(|a, b| b.1.total_cmp(&a.1));
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    eprintln!("shading time by material ({:.1}% of the stages' time):", 100.0 * shading / total.max(1e-12));
    for &(id, t) in by_material.iter().take(LISTED) {
        let name = material_name(names, id as u32);
        eprintln!("  {name:<24} {:>5.1}%", 100.0 * t / shading.max(1e-12));
    }
    by_light(scene, st, names);
    Ok(())
}

/// Prints the shadow rays' time by the light they were aimed at (sampling a light is part of
/// the shading time), largest first.
fn by_light(scene: &RenderScene, st: &wavefront::Stats, names: &[String]) {
    let mut by: Vec<(Light, f64)> = Vec::new();
    for (k, t) in st.light_time.iter().enumerate().filter(|(_, t)| !t.is_zero()) {
        let light = Light::of(scene, k);
        match by.iter_mut().find(|(l, _)| *l == light) {
            Some((_, sum)) => *sum += t.as_secs_f64(),
            None => by.push((light, t.as_secs_f64())),
        }
    }
    by.sort_by(|a, b| b.1.total_cmp(&a.1));
    let shadow: f64 = by.iter().map(|(_, t)| t).sum();
    let total: f64 = st.time.iter().map(|t| t.as_secs_f64()).sum();
    eprintln!(
        "shadow rays' time by the light they were aimed at ({:.1}% of the stages' time; sampling a light is in the shading time above):",
        100.0 * shadow / total.max(1e-12)
    );
    for (light, t) in by.iter().take(LISTED) {
        eprintln!("  {:<40} {:>5.1}%", light_name(names, *light), 100.0 * t / shadow.max(1e-12));
    }
}

/// A material's name (its id where it has none).
fn material_name(names: &[String], id: u32) -> String {
    names.get(id as usize).map_or_else(|| format!("material #{id}"), |n| format!("{n:?}"))
}

/// A light's name: its emitting material's, or what it is.
fn light_name(names: &[String], light: Light) -> String {
    match light {
        Light::Emitter(id) => material_name(names, id),
        Light::Punctual(k) => format!("point, spot or directional light #{k}"),
        Light::Background => "the background".into(),
        Light::BackgroundPeak => {
            format!("the background's sun (its directions {}x its mean or more)", diagnose::PEAK)
        }
        Light::Media => "glowing media".into(),
    }
}

/// The `--crop` fractions of `tile` in an image `width` x `height`: half a pixel before each
/// edge, which [`PixelWindow::crop`]'s `ceil` takes to the edge.
fn crop_of(tile: &Tile, width: u32, height: u32) -> [f32; 4] {
    let f = |p: u32, n: u32| if p == 0 { 0.0 } else { (p as f32 - 0.5) / n as f32 };
    [f(tile.x0, width), f(tile.x0 + tile.w, width), f(tile.y0, height), f(tile.y0 + tile.h, height)]
}

/// Prints the pixels' time by the object their centre sees first (the scene file's
/// `objects[i]`, with its material; instanced meshes together; the background), largest first.
fn by_object(scene: &RenderScene, costs: &PixelCosts, names: &[String]) {
    /// What a pixel's centre sees first: an object of the file (its place and material), one
    /// without a place or an instanced mesh (their material), or the background.
    #[derive(Clone, Copy, PartialEq, Eq, Hash)]
    enum Seen {
        Object(u32, u32),
        Unplaced(u32),
        Instanced(u32),
        Background,
    }
    let w = scene.settings.window;
    // Each one's time and pixels.
    let mut by: std::collections::HashMap<Seen, (f64, usize)> = std::collections::HashMap::new();
    for (k, &t) in costs.time.iter().enumerate() {
        let (x, y) = (w.x0 + k as u32 % w.w, w.y0 + k as u32 / w.w);
        let (ray, tmax, _) = crate::integrator::path::camera_ray(scene, x, y, 0);
        let seen = match scene.intersect(&ray, tmax) {
            None => Seen::Background,
            Some(h) => match scene.objects.get(h.prim as usize) {
                Some(&i) if i != u32::MAX => Seen::Object(i, h.material),
                Some(_) => Seen::Unplaced(h.material),
                None => Seen::Instanced(h.material),
            },
        };
        let e = by.entry(seen).or_default();
        (e.0, e.1) = (e.0 + t, e.1 + 1);
    }
    let material = |id: u32| material_name(names, id);
    let mut time: Vec<(String, f64, usize)> = by
        .into_iter()
        .map(|(seen, (t, n))| {
            let name = match seen {
                Seen::Object(i, m) => format!("objects[{i}] ({})", material(m)),
                Seen::Unplaced(m) => format!("an object without a place in the file ({})", material(m)),
                Seen::Instanced(m) => format!("instanced meshes ({})", material(m)),
                Seen::Background => "the background".into(),
            };
            (name, t, n)
        })
        .collect();
    time.sort_by(|a, b| b.1.total_cmp(&a.1));
    let total = costs.total_time().max(1e-12);
    eprintln!("time by the object each pixel sees first:");
    for (what, t, n) in time.iter().take(LISTED) {
        let share = 100.0 * *n as f64 / costs.len() as f64;
        eprintln!("  {what:<40} {:>5.1}% of the time on {share:>5.1}% of the pixels", 100.0 * t / total);
    }
    // The hot spot: the costliest per pixel, of those that cover some pixels (one in a thousand).
    let mean = total / costs.len() as f64;
    let covers = |n: usize| n * 1000 >= costs.len();
    let hot =
        time.iter().filter(|o| covers(o.2)).max_by(|a, b| (a.1 / a.2 as f64).total_cmp(&(b.1 / b.2 as f64)));
    if let Some((what, t, n)) = hot {
        eprintln!("  the costliest per pixel: {what}, {:.2}x the image's mean", t / *n as f64 / mean);
    }
}

/// Writes the heat map of time per pixel of an image `w` x `h` to `path` (the inferno colour
/// map, from black at no time to yellow at the 99.5th percentile of the pixels' times and
/// above); returns that percentile.
pub fn write_heat_map(costs: &PixelCosts, (w, h): (u32, u32), path: &Path) -> Result<f64, String> {
    let mut sorted: Vec<f64> = costs.time.clone();
    sorted.sort_by(f64::total_cmp);
    let top = sorted[((sorted.len() - 1) as f64 * 0.995) as usize].max(1e-12);
    let mut png = image::RgbImage::new(w, h);
    for (px, &t) in png.pixels_mut().zip(&costs.time) {
        let c = colorous::INFERNO.eval_continuous((t / top).clamp(0.0, 1.0));
        *px = image::Rgb([c.r, c.g, c.b]);
    }
    let mut bytes = std::io::Cursor::new(Vec::new());
    png.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("{}: {e}", path.display()))?;
    io::atomically(path, bytes.get_ref())?;
    Ok(top)
}

/// Each tile's time (in image coordinates) from the pixels' times over `window`.
fn tile_times(costs: &PixelCosts, window: &PixelWindow) -> Vec<(Tile, f64)> {
    let (nx, ny) = Tile::grid_of(window);
    (0..nx * ny)
        .map(|t| {
            let tile = Tile::in_window(t, window);
            let time = tile.window_indices(window).map(|(_, k)| costs.time[k]).sum();
            (tile, time)
        })
        .collect()
}

/// The samples of each pixel that `--stats` diagnoses out of `spp`: one in 16, at least 2
/// (none with fewer).
pub fn diagnosed(spp: u32) -> u32 {
    if spp < 2 { 0 } else { (spp / 16).max(2) }
}

/// The `--stats` tables of where the noise comes from: `samples` of every pixel re-run by the
/// reference path tracer with a witness ([`diagnose`], `luminance` the render's mean of each
/// pixel over its `spp` samples), each light's and each material's share of the variance, and
/// the outliers by light, material, bounce and event. `names` are the material names by id.
pub fn report_noise(
    scene: &RenderScene,
    samples: std::ops::Range<u32>,
    (luminance, spp): (&[f32], u32),
    names: &[String],
) {
    if samples.len() < 2 {
        eprintln!("noise by cause: needs 2 samples per pixel or more");
        return;
    }
    let start = std::time::Instant::now();
    let d = diagnose::diagnose(scene, samples.clone(), luminance, spp);
    let material = |id: u32| material_name(names, id);
    let light = |l: Light| light_name(names, l);
    let vertex = |v: Vertex| match v {
        Vertex::Camera => "the camera".into(),
        Vertex::Material(id) => material(id),
        Vertex::Medium => "a medium".into(),
    };
    eprintln!(
        "noise by cause ({} samples of each pixel as rendered, again by the reference path tracer in {:.2} s): \
         a sample's relative variance {:.4} on average",
        samples.len(),
        start.elapsed().as_secs_f64(),
        d.variance / d.pixels.max(1) as f64
    );
    if !(d.variance > 0.0) {
        eprintln!("  no noise: every diagnosed pixel's samples agree");
        return;
    }
    let shares = |parts: Vec<(String, f64)>, total: f64| -> String {
        let mut parts = parts;
        parts.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let list: Vec<String> =
            parts.iter().take(LISTED).map(|(n, v)| format!("{n} {:.1}%", 100.0 * v / total)).collect();
        list.join(", ")
    };
    let by = |f: &dyn Fn(&Cause) -> String| {
        let mut m: std::collections::HashMap<String, f64> = std::collections::HashMap::new();
        for o in &d.outliers {
            *m.entry(f(&o.cause)).or_default() += o.excess;
        }
        m.into_iter().collect::<Vec<_>>()
    };
    eprintln!(
        "  share of the variance by light: {}",
        shares(d.by_light.iter().map(|(&l, &v)| (light(l), v)).collect(), d.variance)
    );
    eprintln!(
        "  share of the variance by material: {}",
        shares(d.by_vertex.iter().map(|(&v, &x)| (vertex(v), x)).collect(), d.variance)
    );
    let excess: f64 = d.outliers.iter().map(|o| o.excess).sum();
    eprintln!(
        "  outliers, the {} samples ({}%) furthest above their pixel's mean, {:.1}% of the variance; their largest parts came",
        d.outliers.len(),
        100.0 * diagnose::OUTLIER_FRACTION,
        100.0 * d.outliers.iter().map(|o| o.variance).sum::<f64>() / d.variance
    );
    eprintln!("    from light: {}", shares(by(&|c| light(c.light)), excess));
    eprintln!("    at material: {}", shares(by(&|c| vertex(c.vertex)), excess));
    eprintln!("    after bounces: {}", shares(by(&|c| c.bounces.to_string()), excess));
    eprintln!("    by: {}", shares(by(&|c| c.event.describe().to_string()), excess));
    // The outliers' commonest cause (by excess): event, material and light together.
    let mut causes: Vec<((Event, Vertex, Light), f64)> = Vec::new();
    for o in &d.outliers {
        let key = (o.cause.event, o.cause.vertex, o.cause.light);
        match causes.iter_mut().find(|(k, _)| *k == key) {
            Some((_, e)) => *e += o.excess,
            None => causes.push((key, o.excess)),
        }
    }
    if let Some(&((event, at, from), e)) = causes.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        let glow = from == Light::Media;
        let (at, from) = (vertex(at), light(from));
        let lever = match event {
            _ if glow => format!(
                "{from}, which are not sampled as lights, found where paths scattered in them after {at}: \
                 more samples, or --clamp"
            ),
            Event::Caustic => format!(
                "light reaches the eye through {at} after a rough bounce, where light sampling cannot find it: \
                 more samples, a rougher {at}, or --clamp"
            ),
            Event::BsdfSampling => format!(
                "directions sampled at {at} met {from}, small or bright for them: more samples, a rougher \
                 material, or --clamp"
            ),
            Event::LightSampling => format!(
                "light sampling of {from} at {at} (a light close to the surface, or a sharp lobe): more samples, \
                 or --clamp"
            ),
            Event::Direct => format!("{from} seen at pixel edges: more samples, or a wider pixel filter"),
        };
        eprintln!("  most of the outliers ({:.0}%): {lever}", 100.0 * e / excess);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_crop_printed_for_a_tile_is_that_tile() {
        for (width, height) in [(384, 256), (1920, 1080), (37, 5000), (9999, 3)] {
            let all = PixelWindow { x0: 0, y0: 0, w: width, h: height };
            let (nx, ny) = Tile::grid_of(&all);
            for t in 0..nx * ny {
                let tile = Tile::in_window(t, &all);
                let w = PixelWindow::crop(width, height, crop_of(&tile, width, height)).unwrap();
                assert_eq!((w.x0, w.y0, w.w, w.h), (tile.x0, tile.y0, tile.w, tile.h), "{width}x{height}");
            }
        }
    }
}
