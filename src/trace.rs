//! `--trace FILE.json`: a Chrome trace-event file (open it in ui.perfetto.dev) written from
//! `tracing`, sized for long renders.
//!
//! - Spans of pathwave's crates become complete events (`"ph": "X"`) from creation to close,
//!   with their fields as `args` (scene load, ECS systems, frames, passes, tiles).
//! - Events with target [`STAGE`] become complete events at the interval they name (fields
//!   `name`, `ago_us`: how long before the event the interval began, `dur_us`, and any others
//!   as args): the wavefront reports each stage once per tile, its time summed over the tile's
//!   iterations and laid out in pipeline order inside the tile, instead of a span per stage per
//!   iteration (which cost 53 bytes per sample).
//! - Events with target [`COUNTER`] become counter tracks (`"ph": "C"`): field `name` names the
//!   track, `value` is its value.
//!
//! The file is written to a temporary file beside `FILE.json` (`tempfile`) and renamed over it
//! once complete, so a failed run leaves any previous trace as it was. Not `tracing-chrome`: it writes one event
//! per span entry and exit, cannot place an interval it did not see open, and has no counters.

use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use tracing::field::{Field, Visit};
use tracing::span::{Attributes, Id, Record};
use tracing_subscriber::layer::Context;
use tracing_subscriber::registry::LookupSpan;

/// Target of events that describe a stage's interval.
pub const STAGE: &str = "pathwave::stage";
/// Target of counter events.
pub const COUNTER: &str = "pathwave::counter";

struct Out {
    file: Option<BufWriter<tempfile::NamedTempFile>>,
    error: Option<std::io::Error>,
}

impl Out {
    fn event(&mut self, json: &str) {
        if let Some(file) = &mut self.file
            && self.error.is_none()
            && let Err(e) = file.write_all(json.as_bytes())
        {
            self.error = Some(e);
        }
    }
}

/// The `tracing` layer that writes the trace.
pub struct ChromeLayer {
    out: Arc<Mutex<Out>>,
    start: Instant,
}

/// Finishes the file: [`TraceFile::finish`] closes the JSON and renames it into place (a
/// trace file dropped unfinished deletes its temporary file).
pub struct TraceFile {
    out: Arc<Mutex<Out>>,
    path: PathBuf,
}

/// Opens `path` for a trace (checked before any work: its folder must exist and be writable).
pub fn create(path: &Path) -> Result<(ChromeLayer, TraceFile), String> {
    if path.extension().is_none_or(|e| !e.eq_ignore_ascii_case("json")) {
        return Err(format!("{}: a trace is written as JSON (.json)", path.display()));
    }
    let fail = |e| format!("{}: cannot write the trace: {}", path.display(), crate::io::without_temp_name(e));
    let tmp = crate::io::temp_beside(path).map_err(fail)?;
    let mut out = Out { file: Some(BufWriter::with_capacity(1 << 20, tmp)), error: None };
    out.event("{\"displayTimeUnit\":\"ms\",\"traceEvents\":[\n");
    let meta = format!(
        "{{\"ph\":\"M\",\"pid\":1,\"name\":\"process_name\",\"args\":{{\"name\":\"pathwave {}\"}}}}",
        env!("CARGO_PKG_VERSION")
    );
    out.event(&meta);
    let out = Arc::new(Mutex::new(out));
    let layer = ChromeLayer { out: out.clone(), start: Instant::now() };
    Ok((layer, TraceFile { out, path: path.to_owned() }))
}

impl TraceFile {
    /// Ends the JSON, flushes and syncs it, and renames it over the trace's path.
    pub fn finish(self) -> Result<(), String> {
        let mut out = self.out.lock().unwrap_or_else(|p| p.into_inner());
        out.event("\n]}\n");
        let fail = |e| {
            format!("{}: cannot write the trace: {}", self.path.display(), crate::io::without_temp_name(e))
        };
        if let Some(e) = out.error.take() {
            return Err(fail(e));
        }
        let file = out.file.take().expect("finished once");
        let tmp = file.into_inner().map_err(|e| fail(e.into_error()))?;
        tmp.as_file().sync_all().map_err(fail)?;
        tmp.persist(&self.path).map_err(|e| fail(e.error))?;
        Ok(())
    }
}

impl Drop for TraceFile {
    fn drop(&mut self) {
        // Unfinished: the temporary file goes (the layer, which lives on, shares `out`).
        drop(self.out.lock().unwrap_or_else(|p| p.into_inner()).file.take());
    }
}

/// A small index per thread (Perfetto's track per thread).
fn thread_index() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    thread_local! { static INDEX: u64 = NEXT.fetch_add(1, Ordering::Relaxed); }
    INDEX.with(|i| *i)
}

/// Appends `s` as a JSON string.
fn json_str(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// Fields as the members of a JSON object (`"a":1,"b":"x"`), with `name`, `ago_us`, `dur_us`
/// and `value` kept apart for stage and counter events.
#[derive(Default)]
struct Fields {
    args: String,
    name: Option<String>,
    ago_us: f64,
    dur_us: f64,
    value: Option<f64>,
}

impl Fields {
    fn member(&mut self, field: &Field) -> &mut String {
        if !self.args.is_empty() {
            self.args.push(',');
        }
        json_str(&mut self.args, field.name());
        self.args.push(':');
        &mut self.args
    }

    fn number(&mut self, field: &Field, v: f64) {
        match field.name() {
            "ago_us" => self.ago_us = v,
            "dur_us" => self.dur_us = v,
            "value" => self.value = Some(v),
            _ => {
                let v = if v.is_finite() { v } else { 0.0 };
                let _ = write!(self.member(field), "{v}");
            }
        }
    }
}

impl Visit for Fields {
    fn record_f64(&mut self, field: &Field, v: f64) {
        self.number(field, v);
    }
    fn record_i64(&mut self, field: &Field, v: i64) {
        self.number(field, v as f64);
    }
    fn record_u64(&mut self, field: &Field, v: u64) {
        self.number(field, v as f64);
    }
    fn record_bool(&mut self, field: &Field, v: bool) {
        let _ = write!(self.member(field), "{v}");
    }
    fn record_str(&mut self, field: &Field, v: &str) {
        if field.name() == "name" {
            self.name = Some(v.to_owned());
            return;
        }
        json_str(self.member(field), v);
    }
    fn record_debug(&mut self, field: &Field, v: &dyn std::fmt::Debug) {
        let text = format!("{v:?}");
        if field.name() == "name" {
            self.name = Some(text);
            return;
        }
        json_str(self.member(field), &text);
    }
}

/// What a span keeps until it closes.
struct SpanData {
    start: Instant,
    fields: Fields,
}

impl ChromeLayer {
    fn us(&self, t: Instant) -> f64 {
        t.duration_since(self.start).as_secs_f64() * 1e6
    }

    fn complete(&self, name: &str, ts: f64, dur: f64, args: &str) {
        let mut e = String::with_capacity(96 + args.len());
        e.push_str(",\n{\"ph\":\"X\",\"pid\":1,\"tid\":");
        let _ =
            write!(e, "{},\"ts\":{:.3},\"dur\":{:.3},\"name\":", thread_index(), ts.max(0.0), dur.max(0.0));
        json_str(&mut e, name);
        let _ = write!(e, ",\"args\":{{{args}}}}}");
        self.out.lock().unwrap_or_else(|p| p.into_inner()).event(&e);
    }
}

impl<S: tracing::Subscriber + for<'a> LookupSpan<'a>> tracing_subscriber::Layer<S> for ChromeLayer {
    fn on_new_span(&self, attrs: &Attributes<'_>, id: &Id, ctx: Context<'_, S>) {
        let mut fields = Fields::default();
        attrs.record(&mut fields);
        if let Some(span) = ctx.span(id) {
            span.extensions_mut().insert(SpanData { start: Instant::now(), fields });
        }
    }

    fn on_record(&self, id: &Id, values: &Record<'_>, ctx: Context<'_, S>) {
        if let Some(span) = ctx.span(id)
            && let Some(data) = span.extensions_mut().get_mut::<SpanData>()
        {
            values.record(&mut data.fields);
        }
    }

    fn on_close(&self, id: Id, ctx: Context<'_, S>) {
        let Some(span) = ctx.span(&id) else { return };
        let ext = span.extensions();
        let Some(data) = ext.get::<SpanData>() else { return };
        let now = Instant::now();
        self.complete(
            span.name(),
            self.us(data.start),
            (now - data.start).as_secs_f64() * 1e6,
            &data.fields.args,
        );
    }

    fn on_event(&self, event: &tracing::Event<'_>, _ctx: Context<'_, S>) {
        let target = event.metadata().target();
        if target != STAGE && target != COUNTER {
            return;
        }
        let mut f = Fields::default();
        event.record(&mut f);
        let Some(name) = f.name.take() else { return };
        let now = self.us(Instant::now());
        if target == STAGE {
            self.complete(&name, now - f.ago_us, f.dur_us, &f.args);
            return;
        }
        let Some(value) = f.value else { return };
        let mut e = String::with_capacity(96);
        let _ = write!(e, ",\n{{\"ph\":\"C\",\"pid\":1,\"ts\":{now:.3},\"name\":");
        json_str(&mut e, &name);
        let _ = write!(e, ",\"args\":{{\"value\":{}}}}}", if value.is_finite() { value } else { 0.0 });
        self.out.lock().unwrap_or_else(|p| p.into_inner()).event(&e);
    }
}
