//! The tracing subscriber: log lines on stderr, and a Chrome trace or Tracy when asked.

use crate::render::args::LogArgs;
use crate::trace;
use std::path::Path;

/// One subscriber for every subcommand. Log lines go to stderr at the level `log` asks for
/// (warnings by default and with -q, info with -v, debug with -vv, which also logs each
/// span's duration when it closes) unless RUST_LOG sets the levels; colours only on a
/// terminal. With a trace file, the Chrome layer takes every span and stage report of
/// pathwave's crates; the returned file is finished by the caller.
pub fn init_tracing(log: LogArgs, trace: Option<&Path>) -> Result<Option<trace::TraceFile>, String> {
    use std::io::IsTerminal;
    use tracing::level_filters::LevelFilter;
    use tracing_subscriber::prelude::*;
    // Quiet silences progress and per-frame lines, never warnings.
    let level = match log.verbose {
        0 => LevelFilter::WARN,
        1 => LevelFilter::INFO,
        _ => LevelFilter::DEBUG,
    };
    let filter = match std::env::var("RUST_LOG") {
        Ok(v) if !v.trim().is_empty() => tracing_subscriber::EnvFilter::builder().parse_lossy(v),
        _ => tracing_subscriber::EnvFilter::default().add_directive(level.into()),
    };
    let spans = match filter.max_level_hint().is_some_and(|l| l >= LevelFilter::DEBUG) {
        true => tracing_subscriber::fmt::format::FmtSpan::CLOSE,
        false => tracing_subscriber::fmt::format::FmtSpan::NONE,
    };
    let fmt = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_span_events(spans)
        .with_filter(filter);
    let ours = || {
        tracing_subscriber::filter::Targets::new()
            .with_target("pathwave", tracing::Level::TRACE)
            .with_target("pathwave_engine", tracing::Level::TRACE)
            .with_target("pathwave_integrator", tracing::Level::TRACE)
    };
    let (chrome, file) = match trace {
        Some(path) => {
            let (layer, file) = trace::create(path)?;
            (Some(layer.with_filter(ours())), Some(file))
        }
        None => (None, None),
    };
    // Built with `--features tracy`: the Tracy profiler can connect while pathwave runs.
    #[cfg(feature = "tracy")]
    let tracy = Some(tracing_tracy::TracyLayer::default().with_filter(ours()));
    #[cfg(not(feature = "tracy"))]
    let tracy: Option<tracing_subscriber::layer::Identity> = None;
    tracing_subscriber::registry().with(fmt).with(chrome).with(tracy).init();
    Ok(file)
}
