//! The `pathwave` command line: `main` checks the CPU, parses the flags, starts the log (and
//! the trace) and hands the command to [`cli::run`].

use pathwave::cli::{self, Cli};
use std::process::ExitCode;

/// The binary is built for x86-64-v3 (`.cargo/config.toml`: the same instructions, so the same
/// bits, on every machine); on a CPU without the instructions it was built with it would die of
/// an illegal instruction somewhere. Say so instead, first thing.
#[cfg(target_arch = "x86_64")]
fn check_cpu() -> Result<(), String> {
    let have = [
        ("AVX", !cfg!(target_feature = "avx") || std::arch::is_x86_feature_detected!("avx")),
        ("AVX2", !cfg!(target_feature = "avx2") || std::arch::is_x86_feature_detected!("avx2")),
        ("FMA", !cfg!(target_feature = "fma") || std::arch::is_x86_feature_detected!("fma")),
        ("BMI1", !cfg!(target_feature = "bmi1") || std::arch::is_x86_feature_detected!("bmi1")),
        ("BMI2", !cfg!(target_feature = "bmi2") || std::arch::is_x86_feature_detected!("bmi2")),
        ("F16C", !cfg!(target_feature = "f16c") || std::arch::is_x86_feature_detected!("f16c")),
        ("LZCNT", !cfg!(target_feature = "lzcnt") || std::arch::is_x86_feature_detected!("lzcnt")),
        ("MOVBE", !cfg!(target_feature = "movbe") || std::arch::is_x86_feature_detected!("movbe")),
    ];
    let missing: Vec<&str> = have.iter().filter(|(_, ok)| !ok).map(|(name, _)| *name).collect();
    match missing.is_empty() {
        true => Ok(()),
        false => Err(format!(
            "this CPU lacks {}: pathwave is built for x86-64-v3 CPUs (Intel Haswell, AMD Excavator \
             or later); see the README for building for older ones",
            missing.join(", ")
        )),
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn check_cpu() -> Result<(), String> {
    Ok(())
}

fn main() -> ExitCode {
    if let Err(e) = check_cpu() {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    // The matches too: a farm passes the render flags given to it on to its tasks.
    let matches = <Cli as clap::CommandFactory>::command().get_matches();
    let cli = match <Cli as clap::FromArgMatches>::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.format(&mut <Cli as clap::CommandFactory>::command()).exit(),
    };
    let (log, trace) = cli.command.log();
    let trace_file = match cli::logging::init_tracing(log, trace.as_deref()) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = cli::run(cli.command, &matches);
    let result = match (trace_file, result) {
        (Some(file), Ok(())) => file.finish().map(|()| {
            let t = trace.expect("a trace file has a path");
            eprintln!("trace written to {} (open it in ui.perfetto.dev)", t.display());
        }),
        (_, result) => result,
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Errors quote the scene's names and values: nothing in them may drive the terminal.
            eprintln!("error: {}", pathwave::terminal::safe(&e));
            ExitCode::FAILURE
        }
    }
}
