//! `pathwave bench`: run time against error. Renders scenes that have a reference image at a
//! series of sample counts with each integrator (and, if asked, the wavefront's image denoised
//! by each denoiser asked for), and reports seconds, throughput, error (relMSE, RMSE) and the
//! image mean against the reference's as a markdown table and a log-log plot (SVG) of relMSE
//! against seconds, with another renderer's run beside it where given ([`anchor_rows`]).

use crate::denoiser::{self, Denoiser};
use crate::engine::{scene, world::SceneWorld};
use crate::integrator::{oracle, wavefront};
use crate::{io, metrics};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One measurement.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scene file stem.
    pub scene: String,
    /// "wavefront", "oracle", "wavefront + OIDN", "wavefront + à-trous" or [`MITSUBA`].
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
    /// Root mean squared error (NaN where not known).
    pub rmse: f64,
    /// The image mean relative to the reference's, minus 1 (NaN where not known).
    pub mean: f64,
}

/// The `integrator` of rows read by [`anchor_rows`].
pub const MITSUBA: &str = "Mitsuba 3";

/// Mitsuba's rows from a side-by-side run (`side_by_side.py` of the Mitsuba anchor prints one
/// JSON object per line with `scene`, `spp`, `mitsuba_s` and `mitsuba_relmse`; other lines are
/// skipped), for the scenes of `pixels` (scene name, pixel count), so that its curve is drawn
/// beside pathwave's. Its times come from that run: compare them only with pathwave's from
/// the same sitting.
pub fn anchor_rows(path: &Path, pixels: &[(String, u64)]) -> Result<Vec<Row>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("--anchor {}: {e}", path.display()))?;
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let Ok(serde_json::Value::Object(v)) = serde_json::from_str(line) else { continue };
        let field = |k: &str| v.get(k).and_then(|x| x.as_f64()).filter(|x| x.is_finite() && *x > 0.0);
        let scene = v.get("scene").and_then(|x| x.as_str());
        let (Some(scene), Some(spp), Some(seconds), Some(rel_mse)) =
            (scene, field("spp"), field("mitsuba_s"), field("mitsuba_relmse"))
        else {
            return Err(format!(
                "--anchor {}:{}: expected scene, spp, mitsuba_s and mitsuba_relmse (positive numbers)",
                path.display(),
                n + 1
            ));
        };
        let Some(&(_, px)) = pixels.iter().find(|(s, _)| s == scene) else { continue };
        let spp = spp as u32;
        rows.push(Row {
            scene: scene.to_string(),
            integrator: MITSUBA,
            spp,
            seconds,
            msamples: px as f64 * spp as f64 / seconds / 1e6,
            mrays: None,
            rel_mse,
            rmse: f64::NAN,
            mean: f64::NAN,
        });
    }
    if rows.is_empty() {
        return Err(format!("--anchor {}: no rows for the scenes benchmarked", path.display()));
    }
    Ok(rows)
}

/// The `integrator` of a row denoised by `d`.
pub fn label(d: Denoiser) -> &'static str {
    match d {
        Denoiser::Oidn => "wavefront + OIDN",
        Denoiser::Atrous => "wavefront + à-trous",
    }
}

/// Renders `scene_path` at each of `spp` with both integrators and compares with `reference`;
/// also the wavefront's image denoised by each of `denoisers` (rendered again recording the
/// guides; a row's seconds are that render's and its filter's).
pub fn run(
    scene_path: &Path,
    reference: &Path,
    spps: &[u32],
    batch: usize,
    denoisers: &[Denoiser],
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
                mean: relative_mean(&mean, &reference.pixels),
            };
            eprintln!("{}", table_row(&row));
            rows.push(row.clone());
            if denoisers.is_empty() || integrator != "wavefront" {
                continue;
            }
            // Rendered again, recording the guides on the way.
            let start = Instant::now();
            let opts = wavefront::Options { batch, guides: true, ..Default::default() };
            let (film, _) = wavefront::render(&scene, opts, &|_, _| {});
            let (noisy, variance) = (film.mean(), film.variance_of_mean());
            let render_secs = start.elapsed().as_secs_f64();
            let aovs = film.guides.as_ref().expect("the wavefront recorded the guides");
            for &d in denoisers {
                let start = Instant::now();
                let out = denoiser::denoise(d, &noisy, &variance, aovs, rayon::current_num_threads())?;
                let seconds = render_secs + start.elapsed().as_secs_f64();
                let denoised = Row {
                    integrator: label(d),
                    seconds,
                    msamples: samples / seconds / 1e6,
                    mrays: None,
                    rel_mse: metrics::rel_mse(&out, &reference.pixels),
                    rmse: metrics::rmse(&out, &reference.pixels),
                    mean: relative_mean(&out, &reference.pixels),
                    ..row.clone()
                };
                eprintln!("{}", table_row(&denoised));
                rows.push(denoised);
            }
        }
    }
    Ok(rows)
}

/// `x`'s mean over pixels and channels relative to the reference's, minus 1 (0 against a black
/// reference).
fn relative_mean(x: &[glam::Vec3], reference: &[glam::Vec3]) -> f64 {
    let r = metrics::mean(reference);
    if r > 0.0 { metrics::mean(x) / r - 1.0 } else { 0.0 }
}

/// The markdown table header.
pub fn table_header() -> String {
    "| scene | integrator | spp | seconds | M samples/s | M rays/s | relMSE | RMSE | mean vs reference |\n|---|---|---|---|---|---|---|---|---|"
        .to_string()
}

/// One markdown table row.
pub fn table_row(r: &Row) -> String {
    format!(
        "| {} | {} | {} | {:.3} | {:.3} | {} | {:.6} | {} | {} |",
        r.scene,
        r.integrator,
        r.spp,
        r.seconds,
        r.msamples,
        r.mrays.map_or("-".to_string(), |m| format!("{m:.2}")),
        r.rel_mse,
        if r.rmse.is_nan() { "-".to_string() } else { format!("{:.5}", r.rmse) },
        if r.mean.is_nan() { "-".to_string() } else { format!("{:+.3}%", 100.0 * r.mean) },
    )
}

/// A log-log plot of relMSE against seconds, one line per (scene, integrator): solid for the
/// wavefront, dashed for the oracle, dotted for the wavefront with the à-trous filter, long
/// dashes with OIDN, dash-dots for Mitsuba (plotters' SVG backend).
pub fn svg(rows: &[Row]) -> Result<String, String> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| format!("the time-against-error plot: {e}");
    let range = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        if lo.is_finite() && hi > lo { (lo / 1.3)..(hi * 1.3) } else { 1e-3..1.0 }
    };
    let xs = range(&mut rows.iter().map(|r| r.seconds));
    let ys = range(&mut rows.iter().map(|r| r.rel_mse));
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (720, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(xs.log_scale(), ys.log_scale())
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("render seconds")
            .y_desc("relMSE against the reference")
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| fail(&e))?;
        let mut series: Vec<(&str, &str)> = Vec::new();
        for r in rows {
            if !series.contains(&(r.scene.as_str(), r.integrator)) {
                series.push((r.scene.as_str(), r.integrator));
            }
        }
        let mut scenes: Vec<&str> = series.iter().map(|s| s.0).collect();
        scenes.dedup();
        for (scene, integrator) in series {
            // A colour per scene, a dash per integrator.
            let k = scenes.iter().position(|s| *s == scene).unwrap_or(0);
            let colour = Palette99::pick(k).stroke_width(2);
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.scene == scene && r.integrator == integrator)
                .map(|r| (r.seconds, r.rel_mse))
                .collect();
            let (dash, gap) = match integrator {
                "oracle" => (6, 4),
                "wavefront + à-trous" => (2, 3),
                "wavefront + OIDN" => (14, 4),
                MITSUBA => (10, 3),
                _ => (1000, 0),
            };
            let legend = colour;
            chart
                .draw_series(DashedLineSeries::new(points, dash, gap, colour))
                .map_err(|e| fail(&e))?
                .label(format!("{scene} {integrator}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], legend));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(out)
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

/// "2026-11-22" for the current UTC date (`jiff`).
pub fn today() -> String {
    jiff::Timestamp::now().to_zoned(jiff::tz::TimeZone::UTC).date().to_string()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchor_rows_read_a_side_by_side_run() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("anchor.jsonl");
        let run = r#"{"scene": "cornell", "spp": 64, "pathwave_s": 1.16, "mitsuba_s": 2.0, "pathwave_relmse": 0.0668, "mitsuba_relmse": 0.0666, "equal_error_time_ratio": 0.607}
wrote /tmp/mitsuba-anchor/sky.exr
{"scene": "mesh", "spp": 64, "mitsuba_s": 6.4, "mitsuba_relmse": 0.0011}
| scene | spp | pathwave s |"#;
        std::fs::write(&path, run).unwrap();
        let rows = anchor_rows(&path, &[("cornell".into(), 1000)]).unwrap();
        assert_eq!(rows.len(), 1, "only the scenes benchmarked");
        let r = &rows[0];
        assert_eq!((r.scene.as_str(), r.integrator, r.spp), ("cornell", MITSUBA, 64));
        assert_eq!((r.seconds, r.rel_mse, r.msamples), (2.0, 0.0666, 1000.0 * 64.0 / 2.0 / 1e6));
        assert!(table_row(r).ends_with("| 0.066600 | - | - |"), "{}", table_row(r));
        // An object without Mitsuba's fields is an error naming the line.
        std::fs::write(&path, "{\"scene\": \"cornell\", \"spp\": 64}\n").unwrap();
        let e = anchor_rows(&path, &[("cornell".into(), 1000)]).unwrap_err();
        assert!(e.contains("anchor.jsonl:1: expected"), "{e}");
        std::fs::write(&path, "nothing\n").unwrap();
        assert!(anchor_rows(&path, &[("cornell".into(), 1000)]).unwrap_err().contains("no rows"));
    }
}
