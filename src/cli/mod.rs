//! The subcommands. `args` is the command line's schema (clap), `load` reads a scene with the
//! flags' overrides, `render` runs one image (checkpoints, passes, previews) for `render` and for
//! each frame of `animate`; the other modules are one subcommand each.

pub mod animate;
pub mod args;
pub mod bench;
pub mod compare;
pub mod farm;
pub mod load;
pub mod logging;
pub mod merge;
pub mod post_process;
pub mod render;
pub mod stats;

use args::{Checkpointing, Command, FarmCommand};
use pathwave::denoiser::Denoiser;
use pathwave::shard;
use std::path::Path;

/// Runs a parsed command; `matches` are its flags as clap saw them (a farm passes the render
/// flags given to it on to its tasks).
pub fn run(command: Command, matches: &clap::ArgMatches) -> Result<(), String> {
    match command {
        Command::Render { scene, output, args, time, resume, samples, shard_count, view } => (|| {
            let every = args.checkpoint_every()?;
            let samples = samples.as_deref().map(|r| shard::Samples::parse(r, shard_count)).transpose()?;
            // A part is kept in its checkpoint for `merge`.
            let checkpoint = (every.is_some() || resume || samples.is_some())
                .then(|| Checkpointing { every: every.unwrap_or(60.0), resume });
            render::render(&scene, &output, args.overrides(), &args.how(), time, checkpoint, samples, &view)
        })(),
        Command::Merge { parts, output } => merge::merge(&parts, &output),
        Command::Watch(args) => pathwave::watch::run(args),
        Command::Animate { scene, output, frames, fps, shutter, overwrite, shard, shard_count, args } => {
            let seq = animate::SequenceArgs { frames, fps, shutter, overwrite, shard, shard_count };
            animate::animate(&scene, &output, seq, &args)
        }
        Command::Farm { farm: FarmCommand::Slurm { job, args } } => {
            match matches.subcommand_matches("farm").and_then(|m| m.subcommand_matches("slurm")) {
                Some(m) => farm::farm_slurm(&job, &args, m),
                None => Err("farm slurm: its flags are not where clap puts them".into()),
            }
        }
        Command::Farm { farm: FarmCommand::Merge(m) } => match (m.spp, &m.parts, &m.frames) {
            (Some(spp), Some(parts), _) => pathwave::farm::check_samples(parts, m.tasks, spp)
                .and_then(|p| merge::merge(&p, Path::new(&m.output))),
            (_, _, Some(f)) => pathwave::animate::parse_range(f, "--frames")
                .and_then(|f| pathwave::farm::check_frames(&m.output, f, m.tasks))
                .map(|()| eprintln!("{}: every frame is there", m.output)),
            _ => Err("farm merge takes --spp with --parts, or --frames".into()),
        },
        Command::Compare { a, b, encoded } => compare::compare(&a, &b, encoded),
        Command::BenchRays { rings, segments, scene, instances, scaling } => {
            pathwave::raybench::run((rings, segments), Some(&scene))
                .and_then(|_| instances.map_or(Ok(()), |p| pathwave::raybench::instance_update(&p, 100)))
                .and_then(|_| scaling.map_or(Ok(()), pathwave::raybench::scaling))
        }
        Command::Bench { spp, refs, only, batch, svg, denoise, threads, anchor } => {
            let denoise = match denoise {
                Some(d) if d.is_empty() => Denoiser::AVAILABLE.to_vec(),
                d => d.unwrap_or_default(),
            };
            bench::bench(&spp, &refs, &only, batch, svg, &denoise, threads, anchor.as_deref())
        }
    }
}

/// A rayon pool of `threads` workers (all cores when `None`).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| format!("cannot start {threads:?} threads: {e}"))
}
