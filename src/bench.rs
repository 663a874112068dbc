//! `pathwave bench`: run time against error. Renders scenes that have a reference image at a
//! series of sample counts with each integrator (and, if asked, the wavefront's image denoised),
//! and reports seconds, throughput and error (relMSE, RMSE) as a markdown table and a log-log
//! plot (SVG) of relMSE against seconds.

use crate::engine::{scene, world::SceneWorld};
use crate::integrator::{denoise as denoiser, oracle, wavefront};
use crate::{io, metrics};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One measurement.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scene file stem.
    pub scene: String,
    /// "wavefront", "oracle" or "wavefront + denoiser".
    pub integrator: &'static str,
    /// Samples per pixel.
    pub spp: u32,
    /// Render time (scene loading and BVH build excluded).
    pub seconds: f64,
    /// Million samples per second.
    pub msamples: f64,
    /// Million rays (closest and shadow) per second, where counted.
    pub mrays: Option<f64>,
    /// Error against the reference.
    pub rel_mse: f64,
    /// Root mean squared error.
    pub rmse: f64,
}

/// Renders `scene_path` at each of `spp` with both integrators and compares with `reference`;
/// with `denoise`, also the wavefront's image denoised (rendered again recording the guides;
/// its seconds include that render and the filter).
pub fn run(
    scene_path: &Path,
    reference: &Path,
    spps: &[u32],
    batch: usize,
    denoise: bool,
) -> Result<Vec<Row>, String> {
    let reference = io::read_linear(reference)?;
    let name = scene_path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene").to_string();
    let mut rows = Vec::new();
    for &spp in spps {
        for integrator in ["wavefront", "oracle"] {
            let mut desc = scene::load(scene_path).map_err(|e| e.to_string())?;
            desc.render.spp = spp.try_into().map_err(|_| "spp must be > 0".to_string())?;
            let scene = SceneWorld::render_scene(&desc);
            let start = Instant::now();
            let (film, stats) = match integrator {
                "oracle" => (oracle::render(&scene, &|_, _| {}), None),
                _ => {
                    let opts = wavefront::Options { batch, ..Default::default() };
                    let (f, s) = wavefront::render(&scene, opts, &|_, _| {});
                    (f, Some(s))
                }
            };
            let seconds = start.elapsed().as_secs_f64();
            let mean = film.mean();
            if (film.width, film.height) != (reference.width, reference.height) {
                return Err(format!("{name}: the reference is {}x{}", reference.width, reference.height));
            }
            let samples = film.width as f64 * film.height as f64 * spp as f64;
            let mrays = stats.map(|s| {
                let rays = s.items[wavefront::Stage::IntersectClosest.index()]
                    + s.items[wavefront::Stage::TraceShadowRays.index()];
                rays as f64 / seconds / 1e6
            });
            let row = Row {
                scene: name.clone(),
                integrator,
                spp,
                seconds,
                msamples: samples / seconds / 1e6,
                mrays,
                rel_mse: metrics::rel_mse(&mean, &reference.pixels),
                rmse: metrics::rmse(&mean, &reference.pixels),
            };
            eprintln!("{}", table_row(&row));
            if denoise && integrator == "wavefront" {
                // Rendered again, recording the guides on the way.
                let start = Instant::now();
                let opts = wavefront::Options { batch, guides: true };
                let (film, _) = wavefront::render(&scene, opts, &|_, _| {});
                let aovs = film.guides.as_ref().expect("the wavefront recorded the guides");
                let out =
                    denoiser::denoise(&film.mean(), &film.variance_of_mean(), aovs, &Default::default());
                let seconds = start.elapsed().as_secs_f64();
                let denoised = Row {
                    integrator: "wavefront + denoiser",
                    seconds,
                    msamples: samples / seconds / 1e6,
                    mrays: None,
                    rel_mse: metrics::rel_mse(&out, &reference.pixels),
                    rmse: metrics::rmse(&out, &reference.pixels),
                    ..row.clone()
                };
                eprintln!("{}", table_row(&denoised));
                rows.push(row);
                rows.push(denoised);
            } else {
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// The markdown table header.
pub fn table_header() -> String {
    "| scene | integrator | spp | seconds | M samples/s | M rays/s | relMSE | RMSE |\n|---|---|---|---|---|---|---|---|"
        .to_string()
}

/// One markdown table row.
pub fn table_row(r: &Row) -> String {
    format!(
        "| {} | {} | {} | {:.3} | {:.3} | {} | {:.6} | {:.5} |",
        r.scene,
        r.integrator,
        r.spp,
        r.seconds,
        r.msamples,
        r.mrays.map_or("-".to_string(), |m| format!("{m:.2}")),
        r.rel_mse,
        r.rmse
    )
}

/// A log-log plot of relMSE against seconds, one polyline per (scene, integrator).
pub fn svg(rows: &[Row]) -> String {
    let (w, h, m) = (720.0, 480.0, 60.0);
    let lx = |s: f64| s.max(1e-3).log10();
    let ly = |e: f64| e.max(1e-9).log10();
    let (x0, x1) = bounds(rows.iter().map(|r| lx(r.seconds)));
    let (y0, y1) = bounds(rows.iter().map(|r| ly(r.rel_mse)));
    let px = |s: f64| m + (lx(s) - x0) / (x1 - x0) * (w - 2.0 * m);
    let py = |e: f64| h - m - (ly(e) - y0) / (y1 - y0) * (h - 2.0 * m);
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    for d in (x0.floor() as i32)..=(x1.ceil() as i32) {
        let x = m + (d as f64 - x0) / (x1 - x0) * (w - 2.0 * m);
        if (m..=w - m).contains(&x) {
            let _ = writeln!(
                out,
                "<line x1=\"{x:.1}\" y1=\"{m}\" x2=\"{x:.1}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{x:.1}\" y=\"{}\" text-anchor=\"middle\">1e{d} s</text>",
                h - m,
                h - m + 18.0
            );
        }
    }
    for d in (y0.floor() as i32)..=(y1.ceil() as i32) {
        let y = h - m - (d as f64 - y0) / (y1 - y0) * (h - 2.0 * m);
        if (m..=h - m).contains(&y) {
            let _ = writeln!(
                out,
                "<line x1=\"{m}\" y1=\"{y:.1}\" x2=\"{}\" y2=\"{y:.1}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{d}</text>",
                w - m,
                m - 6.0,
                y + 4.0
            );
        }
    }
    let _ = writeln!(
        out,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">render seconds (log)</text>",
        w / 2.0,
        h - 12.0
    );
    let _ = writeln!(
        out,
        "<text x=\"16\" y=\"{}\" transform=\"rotate(-90 16 {})\" text-anchor=\"middle\">relMSE vs reference (log)</text>",
        h / 2.0,
        h / 2.0
    );
    let colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"];
    let mut series: Vec<(String, &str)> = Vec::new();
    for r in rows {
        if !series.iter().any(|(s, i)| *s == r.scene && *i == r.integrator) {
            series.push((r.scene.clone(), r.integrator));
        }
    }
    for (k, (scene, integrator)) in series.iter().enumerate() {
        let colour = colours[k % colours.len()];
        let dash = match *integrator {
            "oracle" => " stroke-dasharray=\"6 4\"",
            "wavefront + denoiser" => " stroke-dasharray=\"2 3\"",
            _ => "",
        };
        let pts: Vec<String> = rows
            .iter()
            .filter(|r| r.scene == *scene && r.integrator == *integrator)
            .map(|r| format!("{:.1},{:.1}", px(r.seconds), py(r.rel_mse)))
            .collect();
        let _ = writeln!(
            out,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\"{dash}/>",
            pts.join(" ")
        );
        let _ = writeln!(
            out,
            "<text x=\"{}\" y=\"{}\" fill=\"{colour}\">{scene} {integrator}</text>",
            w - m - 170.0,
            m + 16.0 * k as f64
        );
    }
    out.push_str("</svg>\n");
    out
}

fn bounds(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if lo.is_finite() && hi > lo { (lo - 0.1, hi + 0.1) } else { (0.0, 1.0) }
}

/// The default scenes: those in `scenes/` with a reference `<name>.exr` in `refs`, by name.
pub fn default_scenes(refs: &Path) -> Vec<(PathBuf, PathBuf)> {
    let mut out: Vec<(PathBuf, PathBuf)> = std::fs::read_dir("scenes")
        .into_iter()
        .flatten()
        .filter_map(|e| {
            let path = e.ok()?.path();
            let stem = path.file_stem()?.to_str()?.to_owned();
            let reference = refs.join(format!("{stem}.exr"));
            (path.extension()? == "ron" && reference.exists()).then_some((path, reference))
        })
        .collect();
    out.sort();
    out
}

/// "2026-11-22" for the current UTC date.
pub fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() / 86_400)
        .unwrap_or(0) as i64;
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    format!("{}-{m:02}-{d:02}", yoe + era * 400 + (m <= 2) as i64)
}

/// The CPU model and core count, from /proc/cpuinfo where available.
pub fn machine() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = info
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .map(|l| l.trim_start_matches([' ', '\t', ':']));
    format!(
        "{}, {} logical cores",
        model.unwrap_or("unknown CPU"),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    )
}
