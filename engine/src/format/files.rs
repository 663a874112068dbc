//! Reading the files a scene names, within bounds: only regular files (not devices, pipes or
//! folders), at most a documented size, so that no path in a scene can make a load read
//! forever or exhaust memory.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest scene file read: 256 MiB.
pub const MAX_SCENE_BYTES: u64 = 256 << 20;
/// The largest mesh (OBJ) or image file read: 1 GiB.
pub const MAX_ASSET_BYTES: u64 = 1 << 30;
/// The largest image a texture may decode to, per side (and 1 GiB of pixels in all).
pub const MAX_IMAGE_SIDE: u32 = 32768;

/// The bytes of the regular file `path`, refused beyond `max` bytes; `what` names it in errors.
pub fn read_bounded(path: &Path, max: u64, what: &str) -> Result<Vec<u8>, String> {
    let (path_read, len) = regular_file(path, max, what)?;
    let fail = |e: std::io::Error| format!("cannot read the {what} {}: {e}", path.display());
    let mut bytes = Vec::with_capacity(len as usize);
    // A file that grows while it is read stops at the bound too.
    std::fs::File::open(path_read).and_then(|f| f.take(max + 1).read_to_end(&mut bytes)).map_err(fail)?;
    if bytes.len() as u64 > max {
        return Err(format!("the {what} {} has more than the {max} bytes allowed", path.display()));
    }
    record(path, &bytes);
    Ok(bytes)
}

/// The first `n` bytes of the regular file `path` (all of a shorter one) and its length, with
/// [`read_bounded`]'s checks (its bound `max`, the folder of [`confined`]) but not recorded as
/// an input: what a check of a file before it is read looks at.
pub fn read_head(path: &Path, n: usize, max: u64, what: &str) -> Result<(Vec<u8>, u64), String> {
    let (path_read, len) = regular_file(path, max, what)?;
    let mut head = Vec::with_capacity(n);
    std::fs::File::open(path_read)
        .and_then(|f| f.take(n as u64).read_to_end(&mut head))
        .map_err(|e| format!("cannot read the {what} {}: {e}", path.display()))?;
    Ok((head, len))
}

/// The file to read for `path` (as resolved inside [`confined`]) and its length: a regular
/// file of at most `max` bytes.
fn regular_file(path: &Path, max: u64, what: &str) -> Result<(PathBuf, u64), String> {
    let fail = |e: std::io::Error| match e.kind() {
        // Where it was looked for: a path relative to the scene's folder, or to one the
        // scene file did not say.
        std::io::ErrorKind::NotFound => {
            format!("cannot read the {what} {}: {}", path.display(), missing(path))
        }
        _ => format!("cannot read the {what} {}: {e}", path.display()),
    };
    // Inside `confined`, the file as resolved (links followed), which is then what is read.
    let real = CONFINED.with(|c| match &*c.borrow() {
        None => Ok(None),
        Some((root, exempt)) => {
            let real = path.canonicalize().map_err(fail)?;
            match real == *exempt || real.starts_with(root) {
                true => Ok(Some(real)),
                false => Err(format!(
                    "the {what} {} lies outside {}, the folder the scene's files must be in (--assets-under)",
                    path.display(),
                    root.display()
                )),
            }
        }
    })?;
    let path_read = real.unwrap_or_else(|| path.to_owned());
    let meta = std::fs::metadata(&path_read).map_err(fail)?;
    if !meta.is_file() {
        return Err(format!("the {what} {} is not a regular file", path.display()));
    }
    if meta.len() > max {
        return Err(format!(
            "the {what} {} has {} bytes, more than the {max} allowed",
            path.display(),
            meta.len()
        ));
    }
    Ok((path_read, meta.len()))
}

/// Why `path`, which is not there, is not: no such file in its (absolute) folder, or no such
/// folder.
fn missing(path: &Path) -> String {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) if dir.is_dir() => {
            format!("there is no {} in {}", name.to_string_lossy(), dir.display())
        }
        (Some(dir), _) => format!("there is no folder {}", dir.display()),
        _ => format!("there is no {}", abs.display()),
    }
}

/// A file a load read: its absolute path and a hash of the bytes read (XXH3, 64 bits), so that
/// what identifies a render is what was loaded, not the file as it is later.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// The path (absolute, as named: not resolved through links).
    pub path: PathBuf,
    /// XXH3-64 of its bytes.
    pub hash: u64,
}

thread_local! {
    /// Inside [`confined`]: the folder files must lie in, and the file exempt (both resolved).
    static CONFINED: RefCell<Option<(PathBuf, PathBuf)>> = const { RefCell::new(None) };
    /// The files [`read_bounded`] read on this thread inside [`recording`], when inside one,
    /// and their hashes.
    static READ: RefCell<Option<BTreeMap<PathBuf, u64>>> = const { RefCell::new(None) };
}

fn record(path: &Path, bytes: &[u8]) {
    READ.with(|r| {
        if let Some(files) = r.borrow_mut().as_mut() {
            let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
            files.insert(path, xxhash_rust::xxh3::xxh3_64(bytes));
        }
    });
}

/// Runs `f` and returns with its result every file that [`read_bounded`] read on this thread
/// meanwhile (sorted by path, each once, with the hash of what was read last): a loaded scene's
/// inputs, which no output may replace and which identify its renders. Recordings nest: an
/// outer one gets the inner one's files too.
pub fn recording<R>(f: impl FnOnce() -> R) -> (R, Vec<InputFile>) {
    /// Puts the outer recording back, with this one's files added, however `f` ends.
    struct Restore(Option<BTreeMap<PathBuf, u64>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let outer = self.0.take();
            READ.with(|r| {
                let mut r = r.borrow_mut();
                let inner = r.take().unwrap_or_default();
                *r = outer.map(|mut o| {
                    o.extend(inner);
                    o
                });
            });
        }
    }
    let restore = Restore(READ.with(|r| r.borrow_mut().replace(BTreeMap::new())));
    let out = f();
    let files = READ.with(|r| {
        r.borrow().iter().flatten().map(|(path, &hash)| InputFile { path: path.clone(), hash }).collect()
    });
    drop(restore);
    (out, files)
}

/// This thread's rules for reading files ([`confined`]'s folder, and whether a [`recording`]
/// is on), to read files on other threads as this one would: a scene's loader reads its
/// meshes and images across rayon's threads.
#[derive(Clone, Debug)]
pub struct ReadRules {
    confined: Option<(PathBuf, PathBuf)>,
    recording: bool,
}

impl ReadRules {
    /// The rules of the calling thread.
    pub fn here() -> Self {
        Self {
            confined: CONFINED.with(|c| c.borrow().clone()),
            recording: READ.with(|r| r.borrow().is_some()),
        }
    }

    /// Runs `f` on the calling thread under these rules; returns its result and the files it
    /// read, for [`Self::keep`] on the thread the rules came from.
    pub fn apply<R>(&self, f: impl FnOnce() -> R) -> (R, FilesRead) {
        /// Puts this thread's own rules back however `f` ends.
        struct Restore(Option<(PathBuf, PathBuf)>, Option<BTreeMap<PathBuf, u64>>);
        impl Drop for Restore {
            fn drop(&mut self) {
                CONFINED.with(|c| *c.borrow_mut() = self.0.take());
                READ.with(|r| *r.borrow_mut() = self.1.take());
            }
        }
        let restore = Restore(
            CONFINED.with(|c| std::mem::replace(&mut *c.borrow_mut(), self.confined.clone())),
            READ.with(|r| r.borrow_mut().replace(BTreeMap::new())),
        );
        let out = f();
        let read = READ.with(|r| r.borrow_mut().take().unwrap_or_default());
        drop(restore);
        (out, FilesRead(if self.recording { read } else { BTreeMap::new() }))
    }
}

/// The files read under [`ReadRules::apply`] on another thread, with their hashes.
#[derive(Debug, Default)]
pub struct FilesRead(BTreeMap<PathBuf, u64>);

impl FilesRead {
    /// Adds them to this thread's [`recording`], if one is on, as if read here.
    pub fn keep(self) {
        READ.with(|r| {
            if let Some(files) = r.borrow_mut().as_mut() {
                files.extend(self.0);
            }
        });
    }
}

/// Runs `f` with every file that [`read_bounded`] reads on this thread required to lie in the
/// folder `root` once links are resolved, but `exempt` (the scene file the user named): a scene
/// from elsewhere then cannot render a private file (`../`, an absolute path, `/proc`) into its
/// image. Loads read their files on the calling thread.
pub fn confined<R>(root: &Path, exempt: &Path, f: impl FnOnce() -> R) -> Result<R, String> {
    /// Puts the outer confinement back however `f` ends.
    struct Restore(Option<(PathBuf, PathBuf)>);
    impl Drop for Restore {
        fn drop(&mut self) {
            CONFINED.with(|c| *c.borrow_mut() = self.0.take());
        }
    }
    let fail = |e: std::io::Error| format!("--assets-under {}: {e}", root.display());
    let dir = root.canonicalize().map_err(fail)?;
    if !dir.is_dir() {
        return Err(format!("--assets-under {}: not a folder", root.display()));
    }
    let exempt = exempt.canonicalize().unwrap_or_else(|_| exempt.to_owned());
    let restore = Restore(CONFINED.with(|c| c.borrow_mut().replace((dir, exempt))));
    let out = f();
    drop(restore);
    Ok(out)
}

/// Decodes an image file within [`MAX_IMAGE_SIDE`] and 1 GiB of decoded pixels (`image`'s
/// limits), so that a small file that expands to a huge image is refused.
pub fn decode_image(path: &Path) -> Result<image::DynamicImage, String> {
    decode_image_bytes(read_bounded(path, MAX_ASSET_BYTES, "image")?, path, MAX_IMAGE_SIDE)
}

/// Decodes the bytes of an image file (format guessed from them) within `max_side` pixels a
/// side and 1 GiB of decoded pixels; `path` names the file in errors.
pub fn decode_image_bytes(bytes: Vec<u8>, path: &Path, max_side: u32) -> Result<image::DynamicImage, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read the image {}: {e}", path.display()))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(max_side);
    limits.max_image_height = Some(max_side);
    limits.max_alloc = Some(MAX_ASSET_BYTES);
    reader.limits(limits);
    reader.decode().map_err(|e| format!("cannot read the image {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recording_lists_the_files_read_and_nests() {
        let dir = std::env::temp_dir().join(format!("pathwave-recording-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.txt"), dir.join("b.txt"));
        std::fs::write(&a, "a").unwrap();
        std::fs::write(&b, "b").unwrap();
        let ((_, inner), outer) = recording(|| {
            read_bounded(&a, 10, "file").unwrap();
            let r = recording(|| read_bounded(&b, 10, "file").unwrap());
            // A refused read is not an input.
            assert!(read_bounded(&dir.join("missing"), 10, "file").is_err());
            r
        });
        let file = |path: &PathBuf, text: &str| InputFile {
            path: path.clone(),
            hash: xxhash_rust::xxh3::xxh3_64(text.as_bytes()),
        };
        assert_eq!(inner, vec![file(&b, "b")]);
        assert_eq!(outer, vec![file(&a, "a"), file(&b, "b")]);
        // Outside a recording nothing is kept.
        read_bounded(&a, 10, "file").unwrap();
        assert_eq!(recording(|| ()).1, Vec::new());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
