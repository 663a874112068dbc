//! Render farms. `pathwave farm slurm` splits a render among the tasks of a Slurm job array
//! (sbatch(1), "--array": <https://slurm.schedmd.com/job_array.html>) and submits a job that
//! depends on all of them (`--dependency=afterok`) to merge their work:
//!
//! - a sequence: task `i` of `n` renders every `n`-th frame from the `i`-th (`animate --shard
//!   auto`), the frame files themselves; the merge job checks that every frame is there.
//! - one image (`--split-samples`): task `i` renders the `i`-th of `n` contiguous shares of the
//!   sample indices (`render --samples auto`) into a checkpoint in the job folder's `parts/`;
//!   the merge job checks that every share is there and whole, and adds them into the image
//!   (`pathwave merge`: the bits of one render). With path guiding, a job submitted before the
//!   array learns the guides once (`render --train-only`) into the job folder's `guides.bin`,
//!   and the array, which depends on it, reads them (`--guide-file`).
//!
//! Tasks are idempotent: a frame is written whole or not at all and an existing one is skipped,
//! and a share's task resumes its checkpoint (a finished share is only written out again), so a
//! task that Slurm requeues, or the same command submitted again, redoes no finished work. A
//! missing or unfinished share is named (its task and its samples or frames) and the merge
//! writes nothing.

pub mod job;
mod scripts;

use crate::animate::sequence::frame_path;
use crate::merge::merge;
use crate::render::args::RenderArgs;
use crate::render::load::{confined, load};
use crate::shard;
use job::{MergeArgs, SlurmArgs};
use std::path::Path;

/// `pathwave farm`'s subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum FarmCommand {
    /// Write an sbatch job array whose tasks render every N-th frame (`animate --shard auto`)
    /// or, with --split-samples, a share of one image's samples (`render --samples auto`), and
    /// a merge job that runs after all of them have succeeded; submit both.
    Slurm {
        /// The farm's own flags.
        #[command(flatten)]
        job: SlurmArgs,
        /// The render flags every task is given.
        #[command(flatten)]
        args: Box<RenderArgs>,
    },
    /// Check that every task's share is there and whole, and merge sample shares into the
    /// image; name what is missing (task, samples or frames) and write nothing if anything is.
    Merge(MergeArgs),
}

/// Runs `farm slurm` or `farm merge`; `matches` are `farm`'s flags as clap saw them (the render
/// flags given are passed on to the tasks as given).
pub fn run(command: &FarmCommand, matches: &clap::ArgMatches) -> Result<(), String> {
    match command {
        FarmCommand::Slurm { job, args } => match matches.subcommand_matches("slurm") {
            Some(m) => slurm(job, args, m),
            None => Err("farm slurm: its flags are not where clap puts them".into()),
        },
        FarmCommand::Merge(m) => match (m.spp, &m.parts, &m.frames) {
            (Some(spp), Some(parts), _) => job::check_samples(parts, m.tasks, spp)
                .and_then(|p| merge(&p, Path::new(&m.output), &m.look.look())),
            (_, _, Some(f)) => shard::parse_range(f, "--frames")
                .and_then(|f| job::check_frames(&m.output, f, m.tasks))
                .map(|()| eprintln!("{}: every frame is there", m.output)),
            _ => Err("farm merge takes --spp with --parts, or --frames".into()),
        },
    }
}

/// `pathwave farm slurm`: checks the scene and the options, then writes and submits the jobs.
fn slurm(job: &SlurmArgs, args: &RenderArgs, matches: &clap::ArgMatches) -> Result<(), String> {
    if args.profile.trace.is_some() {
        return Err("--trace: every task would write the same file; trace one share by hand".into());
    }
    if job.split_samples && (args.denoise.is_some() || args.aov.is_some()) {
        return Err("--split-samples: the merge adds samples; it does not denoise or write AOVs".into());
    }
    // Scenes sent to a farm often come from elsewhere: their files must lie in the scene's
    // folder unless --assets-under says where.
    let mut scene_args = args.scene.clone();
    let default_root = match &scene_args.assets_under {
        Some(_) => None,
        None => {
            let dir = std::path::absolute(&job.scene)
                .map_err(|e| format!("{}: {e}", job.scene.display()))?
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default();
            scene_args.assets_under = Some(dir.clone());
            Some(dir)
        }
    };
    let desc = load(&job.scene, &scene_args)?;
    let flags = <RenderArgs as clap::Args>::augment_args(clap::Command::new("render"));
    let mut forwarded = job::forwarded(&flags, matches)?;
    if let Some(dir) = default_root {
        let dir =
            dir.to_str().ok_or_else(|| format!("{}: the scene's folder is not Unicode", dir.display()))?;
        forwarded.push(format!("--assets-under={dir}"));
    }
    let guided = desc.render.guiding == crate::engine::guiding::Guiding::On;
    let frames = (0, desc.animation.frames.get());
    let plan = job::Job::plan(job, desc.render.spp.get(), frames, guided, forwarded)?;
    // Every frame's grid files (sequences': a file per frame) are there and start as grid
    // files do, inside the folder the tasks read from; a share of one image's samples reads
    // frame 0's (render without --time).
    let frames = match plan.work {
        job::Work::Frames { first, end } => first..end,
        job::Work::Samples { .. } => 0..1,
    };
    if desc.grid_sequences().next().is_some() {
        confined(&job.scene, &scene_args, || frames.clone().try_for_each(|f| desc.check_frame(f)))??;
    }
    // What the tasks and the merge will write must not replace a file the scene reads (a
    // frame's grid files included): found now, not when the tasks start.
    let inputs = crate::io::Inputs::of(&desc).and(frames.flat_map(|f| desc.frame_files(f)));
    match plan.work {
        job::Work::Frames { first, end } => {
            let how = args.how();
            how.check_aovs(&frame_path(&plan.output, first)?)?;
            for f in first..end {
                for file in how.files(&frame_path(&plan.output, f)?) {
                    inputs.check(&file)?;
                }
            }
        }
        job::Work::Samples { .. } => inputs.check(std::path::Path::new(&plan.output))?,
    }
    plan.submit(job.dry_run)
}
