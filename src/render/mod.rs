//! `pathwave render`: one image. Its flags ([`RenderCommand`]), the flags it shares with
//! `animate`, `watch` and `farm slurm` ([`args`]), the scene loaded with their overrides
//! ([`load`]), and the work from samples to file ([`image`], [`post_process`], [`stats`]), which
//! `animate` runs for each frame.

pub mod args;
pub mod image;
pub mod load;
pub mod post_process;
pub mod stats;

use crate::checkpoint;
use crate::denoiser;
use crate::engine::render_scene::PixelWindow;
use crate::io;
use crate::shard;
use crate::view::{ViewArgs, Viewers};
use args::{Checkpointing, RenderArgs, TimeArgs};
use image::{metadata, render_id, render_image};
use load::{load, log_scene};
use std::path::PathBuf;

/// `pathwave render`'s flags.
#[derive(clap::Args, Debug)]
pub struct RenderCommand {
    /// The scene file.
    pub scene: PathBuf,
    /// Output image; the extension picks the format (.png or .exr).
    #[arg(short, long, visible_alias = "outfile", required_unless_present = "train_only")]
    pub output: Option<PathBuf>,
    /// Only learn path guiding's guides for the whole image (of --spp samples per pixel) and
    /// write them to --guide-file, rendering nothing else: what a farm runs once before the
    /// shares that read them.
    #[arg(long, requires = "guide_file", conflicts_with_all = ["output", "samples", "resume"])]
    pub train_only: bool,
    /// The flags `animate` takes too.
    #[command(flatten)]
    pub args: RenderArgs,
    /// The moment rendered.
    #[command(flatten)]
    pub time: TimeArgs,
    /// Continue from OUT.ckpt if it exists (same scene and settings; the result has the
    /// bits of an uninterrupted render); checkpoints every 60 s unless --checkpoint-every.
    #[arg(long)]
    pub resume: bool,
    /// Render only sample indices A..B of each pixel (of --spp) and keep them in OUT.ckpt,
    /// for `pathwave merge` to add to the other parts; `auto`: this task's share, from a
    /// Slurm job array's or a Kubernetes Indexed Job's environment.
    #[arg(long, value_name = "A..B|auto")]
    pub samples: Option<String>,
    /// With `--samples auto`: the number of tasks (else SLURM_ARRAY_TASK_COUNT or
    /// PATHWAVE_SHARD_COUNT).
    #[arg(long, value_name = "N")]
    pub shard_count: Option<u32>,
    /// Where to show the passes.
    #[command(flatten)]
    pub view: ViewArgs,
}

/// Renders the scene into the output, as the flags say.
pub fn run(c: &RenderCommand) -> Result<(), String> {
    let Some(output) = &c.output else {
        return train_only(c);
    };
    let (path, how) = (&c.scene, c.args.how());
    let every = c.args.checkpoint_every()?;
    let samples = c.samples.as_deref().map(|r| shard::Samples::parse(r, c.shard_count)).transpose()?;
    // A part is kept in its checkpoint for `merge`.
    let checkpointing = (every.is_some() || c.resume || samples.is_some())
        .then(|| Checkpointing { every: every.unwrap_or(60.0), resume: c.resume });
    io::check_output(output, &[path], false)?;
    how.check_aovs(output)?;
    let mut writes = how.files(output);
    writes.extend(checkpointing.as_ref().map(|_| checkpoint::path_for(output)));
    // Path guiding's guides, when it is on (known once the scene is loaded; checked before).
    writes.extend(how.guide_file.clone());
    writes.extend(checkpointing.as_ref().map(|_| image::guides_beside(&checkpoint::path_for(output))));
    writes.extend(c.args.profile.trace.clone());
    let Loaded { pool, desc, scene, id } = load_checked(c, &how, &writes)?;
    let samples = samples.map(|s| s.range(desc.render.spp.get())).transpose()?;
    if let Some(d) = how.denoise {
        denoiser::prepare(d, pool.current_num_threads())?;
    }
    log_scene(&scene);
    let s = scene.settings;
    let mut viewers = Viewers::open(&c.view, &output.display().to_string(), &s, how.look);
    let r =
        render_image(&scene, &id, output, &how, checkpointing.as_ref(), samples, &pool, true, &mut viewers)?;
    if how.stats {
        let names: Vec<String> = desc.materials.iter().map(|(n, _)| n.clone()).collect();
        match (&r.stats, &r.costs) {
            (Some(st), costs) => {
                stats::print_stats(st, r.secs, r.non_finite);
                if let Some(costs) = costs {
                    stats::report_costs(&scene, costs, st, &names, &args::heat_map(output))?;
                }
            }
            (None, _) => eprintln!("--stats: per-stage statistics exist for the wavefront integrator only"),
        }
        let first = samples.map_or(0, |(lo, _)| lo);
        let n = stats::diagnosed(r.spp);
        pool.install(|| stats::report_noise(&scene, first..first + n, (&r.luminance, r.spp), &names));
    }
    let metadata = metadata(id.key, &scene, &r);
    let clamped =
        io::write_output(output, &io::Output { img: r.img, layers: r.layers, metadata, look: how.look })?;
    eprintln!(
        "{}: {}x{}{} {} spp in {:.2} s, {:.3} M samples/s, {} threads, {} NaN/Inf samples discarded{}{}",
        output.display(),
        s.window.w,
        s.window.h,
        match s.window == (PixelWindow { x0: 0, y0: 0, w: s.width, h: s.height }) {
            true => String::new(),
            false => format!(" (crop at {},{} of {}x{})", s.window.x0, s.window.y0, s.width, s.height),
        },
        r.spp,
        r.secs,
        r.new_samples / r.secs.max(1e-9) / 1e6,
        pool.current_num_threads(),
        r.non_finite,
        if clamped > 0 {
            format!(", {clamped} pixels clamped to 1 in the 8-bit image")
        } else {
            String::new()
        },
        match checkpointing {
            Some(_) => format!("; checkpoint {}", checkpoint::path_for(output).display()),
            None => String::new(),
        },
    );
    Ok(())
}

/// `render --train-only`: learns the guides of the scene's whole image and writes them to
/// `--guide-file` (nothing is done where the file holds them already).
fn train_only(c: &RenderCommand) -> Result<(), String> {
    let how = c.args.how();
    let file = how.guide_file.clone().ok_or("--train-only writes the guides to --guide-file")?;
    let Loaded { pool, scene, id, .. } = load_checked(c, &how, std::slice::from_ref(&file))?;
    if scene.settings.guiding != crate::engine::guiding::Guiding::On {
        return Err("--train-only: the scene renders without path guiding (--guiding on)".into());
    }
    let last = crate::integrator::guide_training::stage_of(scene.settings.spp - 1);
    image::learn_guides(&scene, &id, &how, last, Some(&file), &pool)?;
    if !how.quiet {
        eprintln!("{}: the guides of {} training stages", file.display(), last + 1);
    }
    Ok(())
}

/// A scene loaded for `render`: the threads it loaded on (the render's), its description, its
/// render scene at the moment asked for and what identifies its samples.
struct Loaded {
    pool: rayon::ThreadPool,
    desc: crate::engine::scene::SceneDesc,
    scene: std::sync::Arc<crate::engine::render_scene::RenderScene>,
    id: image::RenderId,
}

/// Loads `c`'s scene at its `--time`, none of the files it `writes` being one the scene reads
/// (checked before loading, then with every file the load and the frame read).
fn load_checked(c: &RenderCommand, how: &args::How, writes: &[PathBuf]) -> Result<Loaded, String> {
    let path = &c.scene;
    io::check_writes(writes, &io::Inputs::new([path.as_path()]))?;
    let time = c.time.checked()?;
    // The load's parallel work (files read ahead, BLAS, tables) runs on the render's threads.
    let pool = crate::pool(how.threads)?;
    let desc = pool.install(|| load(path, &c.args.scene))?;
    // The frame's grid files are inputs too.
    let frame = args::frame_at(&desc, time)?;
    io::check_writes(writes, &io::Inputs::of(&desc).and(desc.frame_files(frame)))?;
    let shutter = args::shutter_at(&desc, time);
    let (mut world, scene) = pool.install(|| {
        let mut world = load::world(&desc, path, &c.args.scene);
        world.set_time(shutter.0, shutter.1);
        world.set_frame(frame);
        world.update_checked().map(|scene| (world, scene))
    })?;
    let inputs: Vec<_> = desc.inputs.iter().cloned().chain(world.frame_inputs()).collect();
    let id = render_id(&inputs, &scene, how, time, shutter)?;
    Ok(Loaded { pool, desc, scene, id })
}
