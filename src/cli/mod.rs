//! The command line: the subcommands ([`Command`], each one's flags and work in its own module)
//! and the log they write ([`logging`]).

pub mod logging;

use crate::animate::AnimateCommand;
use crate::bench::BenchCommand;
use crate::bench_rays::BenchRaysCommand;
use crate::compare::CompareCommand;
use crate::convert::ConvertCommand;
use crate::farm::FarmCommand;
use crate::merge::MergeCommand;
use crate::render::RenderCommand;
use crate::render::args::LogArgs;
use crate::watch::WatchArgs;
use crate::{animate, bench, bench_rays, compare, convert, farm, merge, render, watch};
use std::path::PathBuf;

/// `pathwave`'s command line.
#[derive(clap::Parser, Debug)]
#[command(name = "pathwave", version, about = "A physically based path tracer")]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Render a RON scene to PNG (sRGB, clamped) or EXR (linear float).
    Render(RenderCommand),
    /// Render a scene in passes into a window (or tev) and render it again whenever it or a
    /// file it loads changes; a scene with an error shows the error and keeps the last image.
    Watch(WatchArgs),
    /// Merge checkpoints holding disjoint sample ranges of one render (from `render
    /// --samples` on several machines) into its image, and OUT.ckpt when they are contiguous.
    Merge(MergeCommand),
    /// Render an animation sequence: one image per frame (`{frame:04}` in the output name), or
    /// an animated GIF when the output ends in .gif. Existing frames are skipped (empty files are rendered again).
    Animate(AnimateCommand),
    /// Render on a cluster: shares of the work as tasks of a Slurm job array, then a job that
    /// checks and merges them.
    Farm {
        /// `farm slurm` or `farm merge`.
        #[command(subcommand)]
        farm: FarmCommand,
    },
    /// Run time against error: render the scenes that have references at several sample
    /// counts with both integrators; print a markdown table, optionally write an SVG plot.
    Bench(BenchCommand),
    /// BVH build time and traversal rates (Mrays/s) on the Embree anchor's torus knot and on a
    /// scene's geometry: primary, diffuse-bounce and shadow rays on 1 and 2 threads.
    BenchRays(BenchRaysCommand),
    /// Print RMSE and relMSE of image A against reference B (and both means). EXR and HDR
    /// files are linear (an EXR's beauty: R, G, B); an 8-bit file (PNG, JPEG) is sRGB-encoded,
    /// so comparing one with a linear file needs `--encoded` to say how to read it.
    Compare(CompareCommand),
    /// Write a Mitsuba 3 XML or glTF 2.0 scene as a RON scene that renders the same image
    /// (every command that takes a scene also reads .xml, .gltf and .glb directly).
    Convert(ConvertCommand),
}

impl Command {
    /// What the subcommand logs (`-v`, `-q`) and where it writes a Chrome trace (`--trace`).
    pub fn log(&self) -> (LogArgs, Option<PathBuf>) {
        match self {
            Command::Render(RenderCommand { args, .. }) | Command::Animate(AnimateCommand { args, .. }) => {
                (args.log, args.profile.trace.clone())
            }
            Command::Watch(w) => (w.log, None),
            _ => (LogArgs { verbose: 0, quiet: false }, None),
        }
    }
}

/// Runs a parsed command; `matches` are its flags as clap saw them (a farm passes the render
/// flags given to it on to its tasks).
pub fn run(command: Command, matches: &clap::ArgMatches) -> Result<(), String> {
    match command {
        Command::Render(c) => render::run(&c),
        Command::Merge(c) => merge::merge(&c.parts, &c.output, &c.look.look()),
        Command::Watch(args) => watch::run(args),
        Command::Animate(c) => animate::run(&c),
        Command::Farm { farm } => match matches.subcommand_matches("farm") {
            Some(m) => farm::run(&farm, m),
            None => Err("farm: its flags are not where clap puts them".into()),
        },
        Command::Compare(c) => compare::run(&c),
        Command::Convert(c) => convert::run(&c),
        Command::BenchRays(c) => bench_rays::run(&c),
        Command::Bench(c) => bench::run(&c),
    }
}
