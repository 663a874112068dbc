//! `pathwave animate`: a sequence of frames, each rendered as `render` renders one image. Its
//! flags ([`AnimateCommand`]) and the frame loop ([`sequence`]).

pub mod sequence;

use crate::checkpoint;
use crate::denoiser;
use crate::integrator::wavefront;
use crate::io;
use crate::render::args::{Checkpointing, How, RenderArgs, heat_map};
use crate::render::image::{RenderId, metadata, render_id, render_image};
use crate::render::load::{confined, load, log_scene, world};
use crate::render::stats::{print_stats, stage_shares, write_heat_map};
use crate::shard;
use crate::view::Viewers;
use std::path::{Path, PathBuf};

/// `pathwave animate`'s flags.
#[derive(clap::Args, Debug)]
pub struct AnimateCommand {
    /// The scene file.
    pub scene: PathBuf,
    /// Output pattern, e.g. out/frame_{frame:04}.png (or .exr), or anim.gif.
    #[arg(short, long, visible_alias = "outfile")]
    pub output: String,
    /// Frames A..B (B excluded) or A..=B (default: 0..the scene's `animation.frames`).
    #[arg(long)]
    pub frames: Option<String>,
    /// Frames per second (default: the scene's, 24 if it has none).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Shutter as a fraction of the frame interval, 0 = no motion blur (default: the
    /// scene's `animation.shutter`).
    #[arg(long)]
    pub shutter: Option<f32>,
    /// Render frames whose file already exists.
    #[arg(long)]
    pub overwrite: bool,
    /// Render only every N-th frame from the I-th (I/N, 0-based), so that N processes split
    /// the sequence (frame files only, not a GIF); `auto`: this task's, from a Slurm job
    /// array's or a Kubernetes Indexed Job's environment.
    #[arg(long, value_name = "I/N|auto")]
    pub shard: Option<String>,
    /// With `--shard auto`: the number of tasks (else SLURM_ARRAY_TASK_COUNT or
    /// PATHWAVE_SHARD_COUNT).
    #[arg(long, value_name = "N")]
    pub shard_count: Option<u32>,
    /// The flags `render` takes too.
    #[command(flatten)]
    pub args: RenderArgs,
}

/// Renders the frames the flags ask for.
pub fn run(c: &AnimateCommand) -> Result<(), String> {
    let (path, output, args) = (c.scene.as_path(), c.output.as_str(), &c.args);
    // Frame folders are created as frames come; the format and the scene are checked now.
    let first = match Path::new(output).extension().is_some_and(|e| e.eq_ignore_ascii_case("gif")) {
        true => PathBuf::from(output),
        false => sequence::frame_path(output, 0)?,
    };
    if io::same_file(path, &first) {
        return Err(format!("{output}: the output would replace the scene {}", path.display()));
    }
    let ext = first.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if !["png", "jpg", "jpeg", "exr", "gif"].contains(&ext.as_str()) {
        return Err(format!("{output}: unknown output format (use .png, .jpg, .exr or .gif)"));
    }
    // The load's parallel work (files read ahead, tables) runs on the render's threads.
    let pool = crate::pool(args.engine.threads)?;
    let desc = pool.install(|| load(path, &args.scene))?;
    let a = &desc.animation;
    let frames = match &c.frames {
        Some(f) => shard::parse_range(f, "--frames")?,
        None => (0, a.frames.get()),
    };
    let fps = c.fps.unwrap_or(a.fps.0);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(format!("--fps takes a number > 0, not {fps}"));
    }
    // The times of the frames stay where --time may go.
    if frames.1 as f32 / fps > 1e7 {
        return Err(format!("frames up to {} at {fps} fps reach beyond 1e7 seconds", frames.1));
    }
    let shutter = c.shutter.unwrap_or(a.shutter.0);
    if !(0.0..=1.0).contains(&shutter) {
        return Err(format!("--shutter takes a fraction of the frame interval in [0, 1], not {shutter}"));
    }
    let shard = match c.shard.as_deref() {
        Some(s) => shard::parse_shard(s, c.shard_count).map(|t| (t.index, t.count))?,
        None => (0, 1),
    };
    let every = args.checkpoint_every()?;
    args.how().check_aovs(&first)?;
    let gif = Path::new(output).extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if gif && (args.denoise.is_some() || args.aov.is_some() || every.is_some()) {
        return Err(format!(
            "{output}: --denoise, --aov and --checkpoint-every write files beside each frame; \
             render frame files (e.g. frame_{{frame:04}}.png) rather than a GIF"
        ));
    }
    // Every frame this task renders reads its grid files (sequences'): they are there and
    // start as grid files do, checked now rather than when the frame comes.
    let task = (frames.0..frames.1).filter(|f| (f - frames.0) % shard.1 == shard.0);
    if desc.grid_sequences().next().is_some() {
        let written = |f: u32| {
            !gif && !c.overwrite && sequence::frame_path(output, f).is_ok_and(|p| sequence::frame_written(&p))
        };
        let todo: Vec<u32> = task.clone().filter(|&f| !written(f)).collect();
        confined(path, &args.scene, || todo.iter().try_for_each(|&f| desc.check_frame(f)))??;
    }
    // No frame of this task, nor a file beside one, nor the trace may replace a scene's input,
    // nor a grid file a frame reads (this task's, another's, or one of the scene's frames
    // outside --frames).
    let last = frames.1.max(a.frames.get());
    let inputs = io::Inputs::of(&desc).and((0..last).flat_map(|f| desc.frame_files(f)));
    if let Some(trace) = &args.profile.trace {
        inputs.check(trace)?;
    }
    match gif {
        true => inputs.check(&first)?,
        false => {
            let how = args.how();
            for f in task {
                let out = sequence::frame_path(output, f)?;
                for w in how.files(&out).iter().chain(&every.map(|_| checkpoint::path_for(&out))) {
                    inputs.check(w)?;
                }
            }
        }
    }
    // A frame killed half way resumes from its checkpoint.
    let checkpointing = every.map(|every| Checkpointing { every, resume: true });
    if let Some(d) = args.denoise {
        denoiser::prepare(d, pool.current_num_threads())?;
    }
    let mut world = world(&desc, path, &args.scene);
    let quiet = args.log.quiet;
    let look = args.look.look();
    let seq = sequence::Sequence { output, frames, shard, fps, shutter, overwrite: c.overwrite, quiet, look };
    // Frames report one line each (from `animate::run`), not a bar or a line per pass.
    if args.guide_file.is_some() {
        return Err("--guide-file keeps one image's guides; animate's frames each learn their own".into());
    }
    let how = How { quiet: true, ..args.how() };
    let mut total: Option<(wavefront::Stats, f64, u64)> = None;
    // With --stats, each frame's number, render seconds, update time, what the update built and
    // microseconds per sample.
    let mut frames: Vec<FrameCost> = Vec::new();
    let mut logged = false;
    // Frames are not shown while they render.
    let nv = &mut Viewers::default();
    sequence::run(&mut world, &seq, |scene, info| {
        if !logged {
            log_scene(scene);
            logged = true;
        }
        let r = match &info.path {
            Some(out) => {
                let inputs: Vec<_> = desc.inputs.iter().chain(&info.inputs).cloned().collect();
                let id = render_id(&inputs, scene, &how, info.open, (info.open, info.close))?;
                let r = render_image(scene, &id, out, &how, checkpointing.as_ref(), None, &pool, false, nv)?;
                let metadata = metadata(id.key, scene, &r);
                (r, metadata)
            }
            // A GIF's frames: no checkpoints, no files beside them (refused above).
            None => {
                {
                    // No checkpoint, so nothing identifies it.
                    let id = RenderId { key: 0, settings: String::new(), whole_key: 0 };
                    (
                        render_image(scene, &id, Path::new(output), &how, None, None, &pool, false, nv)?,
                        Vec::new(),
                    )
                }
            }
        };
        let (r, metadata) = r;
        if args.profile.stats {
            let per_sample = r.secs / r.new_samples.max(1.0) * 1e6;
            match &r.stats {
                Some(st) => eprintln!(
                    "frame {}: scene update {:.2} ms ({}), render {:.2} s ({per_sample:.3} us per sample), {}",
                    info.frame,
                    info.update.as_secs_f64() * 1e3,
                    info.built,
                    r.secs,
                    stage_shares(st)
                ),
                None => eprintln!("--stats: per-stage statistics exist for the wavefront integrator only"),
            }
            frames.push((info.frame, r.secs, info.update, info.built.clone(), per_sample));
            if let (Some(out), Some(costs)) = (&info.path, &r.costs) {
                write_heat_map(costs, (scene.settings.window.w, scene.settings.window.h), &heat_map(out))?;
            }
            if let Some(st) = r.stats.clone() {
                total = Some(match total.take() {
                    Some((t, s, n)) => (t.merge(st), s + r.secs, n + r.non_finite),
                    None => (st, r.secs, r.non_finite),
                });
            }
        }
        Ok(io::Output { img: r.img, layers: r.layers, metadata, look: how.look })
    })?;
    if let Some((st, secs, non_finite)) = &total {
        eprintln!("the sequence's frames together:");
        print_stats(st, *secs, *non_finite);
    }
    slowest_frames(&mut frames);
    Ok(())
}

/// A frame's number, render seconds, update time, what the update built and microseconds per
/// sample.
type FrameCost = (u32, f64, std::time::Duration, String, f64);

/// The `--stats` summary of a sequence: its slowest frames against the median, with what their
/// update built and their time per sample (a frame slow for its rebuilds, or for its samples).
fn slowest_frames(frames: &mut [FrameCost]) {
    if frames.len() < 2 {
        return;
    }
    let mut secs: Vec<f64> = frames.iter().map(|f| f.1).collect();
    secs.sort_by(f64::total_cmp);
    let median = secs[secs.len() / 2];
    frames.sort_by(|a, b| b.1.total_cmp(&a.1));
    eprintln!("slowest frames (median render {median:.2} s):");
    for (frame, secs, update, built, per_sample) in frames.iter().take(3) {
        eprintln!(
            "  frame {frame}: render {secs:.2} s ({:.1}x the median, {per_sample:.3} us per sample), scene update {:.2} ms ({built})",
            secs / median.max(1e-12),
            update.as_secs_f64() * 1e3
        );
    }
}
