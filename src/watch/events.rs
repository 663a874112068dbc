//! Changes of the files a scene read (debounced file events).

use notify_debouncer_full::DebounceEventResult;
use notify_debouncer_full::notify::EventKind;
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// `a/./b/../c` as `a/c`, so that a path a scene names matches the one a file event reports.
pub fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Whether an event can change a file's contents: not reading it (which the reload itself
/// does) nor its access time.
fn writes(kind: &EventKind) -> bool {
    use notify_debouncer_full::notify::event::{AccessKind, AccessMode, MetadataKind, ModifyKind};
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Access(_) | EventKind::Modify(ModifyKind::Metadata(MetadataKind::AccessTime)) => false,
        _ => true,
    }
}

/// The file events, kept to those about the scene's files.
pub struct Events {
    /// The debouncer's events.
    pub rx: mpsc::Receiver<DebounceEventResult>,
    /// The files that matter (normalized absolute paths).
    pub files: BTreeSet<PathBuf>,
}

impl Events {
    /// Whether one of the files changed (waiting up to `wait`).
    pub fn changed(&self, wait: Duration) -> bool {
        let deadline = Instant::now() + wait;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(Ok(events)) => {
                    let ours = |p: &PathBuf| self.files.contains(&normalize(p));
                    if events.iter().any(|e| writes(&e.kind) && e.paths.iter().any(ours)) {
                        // What else came with it is the same save.
                        while self.rx.try_recv().is_ok() {}
                        return true;
                    }
                }
                Ok(Err(errors)) => {
                    for e in errors {
                        eprintln!("watch: {e}");
                    }
                }
                Err(_) => return false,
            }
            if left.is_zero() {
                return false;
            }
        }
    }
}
