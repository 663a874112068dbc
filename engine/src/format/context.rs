//! The parse context: what the scene format's `Deserialize` impls need to know beyond the text
//! they read. serde gives a `Deserialize` impl no argument of its own, so the loader keeps one
//! [`Context`] per thread and sets it for the parse ([`ParseScope`]); the impls read it through
//! the functions here, and nothing else in the crate touches it.
//!
//! A scene is parsed twice ([`crate::scene::parse_with`]): the first pass collects the names
//! a scene defines, which may come after their uses in the file; the second, inside a
//! [`ParseScope`], checks every name against them while the parser still knows where that
//! name stands, and reads the image and mesh files.

use std::any::{Any, TypeId};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What the second pass knows of the scene from the first.
pub(crate) struct Names {
    /// All material names.
    pub materials: Vec<String>,
    /// The names of the emitting materials.
    pub lights: Vec<String>,
    /// The names of the wrappers (`Mask`, `Blend`).
    pub wrappers: Vec<String>,
    /// All texture names, in file order.
    pub textures: Vec<String>,
    /// The names of the `Image` and `GltfImage` textures.
    pub images: Vec<String>,
    /// The names of the bump and normal maps, and of the wrappers that hold one.
    pub tilting: Vec<String>,
    /// The mesh attributes each material reads through its textures (materials that read
    /// none are left out).
    pub attributes: Vec<(String, Vec<String>)>,
    /// The directory image and mesh paths are relative to.
    pub dir: PathBuf,
}

/// The state of a parse on this thread.
#[derive(Default)]
struct Context {
    /// `Some` in the second pass only.
    names: Option<Names>,
    /// While a texture is parsed: how many textures precede it (only they may be named in it).
    textures_before: Option<usize>,
    /// While a material is parsed: how many materials precede it (only they may be wrapped
    /// in it).
    materials_before: Option<usize>,
    /// The index of the object being parsed, while inside `objects` (errors name it).
    object: Option<usize>,
    /// Files read so far in this parse (meshes, images), by path and by the type they were
    /// read as: each file is read once and shared. The types (the scene's `MeshData`, a
    /// texture's image) are not named here, so that this module depends on nothing else of the
    /// engine.
    files: HashMap<(PathBuf, TypeId), Arc<dyn Any + Send + Sync>>,
    /// In the first pass, the files the scene names, as written, in file order: what the
    /// loader reads across threads before the second pass ([`take_wanted`]).
    wanted: Vec<(PathBuf, Wanted)>,
}

/// What a file the first pass met is read as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Wanted {
    /// A mesh file (OBJ, PLY, glTF, Mitsuba's serialized format).
    Mesh,
    /// An image (a texture's, an environment map's).
    Image,
}

thread_local! {
    static CONTEXT: RefCell<Context> = RefCell::new(Context::default());
}

fn with<R>(f: impl FnOnce(&mut Context) -> R) -> R {
    CONTEXT.with(|c| f(&mut c.borrow_mut()))
}

/// While alive, the second pass: names are checked against `names` and files are read.
pub(crate) struct ParseScope;

impl ParseScope {
    /// Starts the second pass on this thread.
    pub(crate) fn enter(names: Names) -> Self {
        with(|c| c.names = Some(names));
        ParseScope
    }
}

impl Drop for ParseScope {
    fn drop(&mut self) {
        with(|c| *c = Context::default());
    }
}

/// Runs `f` with the second pass's names, `None` in the first pass.
pub(crate) fn names<R>(f: impl FnOnce(Option<&Names>) -> R) -> R {
    with(|c| f(c.names.as_ref()))
}

/// The directory files are read from, in the second pass.
pub(crate) fn scene_dir() -> Option<PathBuf> {
    names(|n| n.map(|n| n.dir.clone()))
}

/// How many textures precede the one being parsed (`None` outside the texture list).
pub(crate) fn textures_before() -> Option<usize> {
    with(|c| c.textures_before)
}

/// Sets [`textures_before`].
pub(crate) fn set_textures_before(n: Option<usize>) {
    with(|c| c.textures_before = n);
}

/// How many materials precede the one being parsed (`None` outside the material list).
pub(crate) fn materials_before() -> Option<usize> {
    with(|c| c.materials_before)
}

/// Sets [`materials_before`].
pub(crate) fn set_materials_before(n: Option<usize>) {
    with(|c| c.materials_before = n);
}

/// Notes the index of the object being parsed (`None` when leaving the list).
pub(crate) fn set_current_object(i: Option<usize>) {
    with(|c| c.object = i);
}

/// The index in `objects` of the object the parser stopped in, if it stopped in one: errors
/// name it. Taking it resets it for the next parse.
pub(crate) fn take_current_object() -> Option<usize> {
    with(|c| c.object.take())
}

/// Notes, in the first pass, that the scene names the file `path` (as written), to be read as
/// `what`.
pub(crate) fn want(path: &Path, what: Wanted) {
    with(|c| c.wanted.push((path.to_owned(), what)));
}

/// The files noted by [`want`] since the last call, in order, each once.
pub(crate) fn take_wanted() -> Vec<(PathBuf, Wanted)> {
    let mut wanted = with(|c| std::mem::take(&mut c.wanted));
    let mut seen = std::collections::HashSet::new();
    wanted.retain(|w| seen.insert(w.clone()));
    wanted
}

/// What was read from the file at `path` earlier in this parse, as a `T`.
pub(crate) fn read_before<T: Any + Send + Sync>(path: &Path) -> Option<Arc<T>> {
    let key = (path.to_owned(), TypeId::of::<T>());
    with(|c| c.files.get(&key).cloned()).and_then(|m| m.downcast().ok())
}

/// Keeps what was read from `path` for later uses of the file in this parse.
pub(crate) fn keep<T: Any + Send + Sync>(path: PathBuf, read: Arc<T>) {
    with(|c| c.files.insert((path, TypeId::of::<T>()), read));
}
