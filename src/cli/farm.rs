//! `pathwave farm slurm`: the render's options checked here, then the job array written and
//! submitted.

use super::args::RenderArgs;
use super::load::load;
use pathwave::{animate, farm};

/// `pathwave farm slurm`: checks the scene and the options, then writes and submits the jobs.
pub fn farm_slurm(
    job: &farm::SlurmArgs,
    args: &RenderArgs,
    matches: &clap::ArgMatches,
) -> Result<(), String> {
    if args.profile.trace.is_some() {
        return Err("--trace: every task would write the same file; trace one share by hand".into());
    }
    if job.split_samples && (args.denoise.is_some() || args.aov.is_some()) {
        return Err("--split-samples: the merge adds samples; it does not denoise or write AOVs".into());
    }
    let desc = load(&job.scene, &args.overrides())?;
    let flags = <RenderArgs as clap::Args>::augment_args(clap::Command::new("render"));
    let forwarded = farm::forwarded(&flags, matches)?;
    let plan = farm::Job::plan(job, desc.render.spp.get(), (0, desc.animation.frames.get()), forwarded)?;
    if let farm::Work::Frames { first, .. } = plan.work {
        args.how().check_aovs(&animate::frame_path(&plan.output, first)?)?;
    }
    plan.submit(job.dry_run)
}
