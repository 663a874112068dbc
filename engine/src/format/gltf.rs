//! A glTF 2.0 file read whole (for its meshes, `scene::gltf`, and its images, the `GltfImage`
//! texture): its document (parsed and validated by the `gltf` crate, which also
//! splits a `.glb` into its JSON and binary chunks) and its buffers, each resolved here: the
//! `.glb`'s own chunk, a `data:` URI (base64) or a file beside the document, read within the
//! bounds of [`crate::format::files`]. Accessors are read here too, every range checked
//! against its view and buffer, so that no count, offset or stride in a file can read past
//! its data.

use ::gltf::accessor::{DataType, Dimensions};
use std::path::{Path, PathBuf};

/// The extensions a file may require: pathwave reads what they change (lights, emission
/// strength, texture transforms). A file requiring another (Draco or meshopt compression,
/// quantized attributes, ...) is refused by name.
pub const REQUIRED_READ: [&str; 3] =
    ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"];

/// A glTF 2.0 file with its buffers.
#[derive(Debug)]
pub struct GltfFile {
    /// The document.
    pub doc: ::gltf::Document,
    /// Each buffer's bytes (exactly its `byteLength`), by index.
    buffers: Vec<Vec<u8>>,
    /// The folder its relative URIs (buffers, images) are in.
    pub dir: PathBuf,
}

impl GltfFile {
    /// The file `bytes` (`.gltf` JSON or `.glb`), read from `path`, whose folder holds the
    /// files its URIs name.
    pub fn new(bytes: &[u8], path: &Path) -> Result<Self, String> {
        let fail = |m: String| format!("cannot read the glTF file {}: {m}", path.display());
        let gltf = ::gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| fail(describe(e)))?;
        if let Some(e) = gltf.extensions_required().find(|e| !REQUIRED_READ.contains(e)) {
            return Err(fail(format!(
                "it requires the extension {e}, which pathwave does not read (it reads {})",
                REQUIRED_READ.join(", ")
            )));
        }
        let mut blob = gltf.blob;
        let json = gltf.document.into_json();
        // gltf-json 1.4.1's validation reads each primitive's POSITION accessor without checking
        // its index (it panicked on one past the end).
        let count = json.accessors.len();
        for (m, mesh) in json.meshes.iter().enumerate() {
            for (p, prim) in mesh.primitives.iter().enumerate() {
                let position = prim
                    .attributes
                    .get(&::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions));
                if let Some(i) = position.filter(|i| i.value() >= count) {
                    return Err(fail(format!(
                        "meshes[{m}].primitives[{p}].attributes.POSITION is accessor {}, but there are {count}",
                        i.value()
                    )));
                }
            }
        }
        let doc = ::gltf::Document::from_json(json).map_err(|e| fail(describe(e)))?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut buffers = Vec::new();
        for b in doc.buffers() {
            let at = || format!("buffer {}{}", b.index(), name(b.name()));
            let mut data = match b.source() {
                ::gltf::buffer::Source::Bin => blob
                    .take()
                    .ok_or_else(|| fail(format!("{} is the GLB's binary chunk, which it lacks", at())))?,
                ::gltf::buffer::Source::Uri(uri) => {
                    uri_bytes(uri, &dir, "buffer").map_err(|m| fail(format!("{}: {m}", at())))?
                }
            };
            if data.len() < b.length() {
                return Err(fail(format!(
                    "{} has {} bytes, fewer than its byteLength {}",
                    at(),
                    data.len(),
                    b.length()
                )));
            }
            data.truncate(b.length());
            buffers.push(data);
        }
        Ok(Self { doc, buffers, dir })
    }

    /// The glTF file at `path` as read before in this parse (by a mesh or a texture), else read
    /// now and kept for the parse's later uses.
    pub fn read(path: &Path) -> Result<std::sync::Arc<Self>, String> {
        if let Some(file) = super::context::read_before::<Self>(path) {
            return Ok(file);
        }
        let bytes = super::files::read_bounded(path, super::files::MAX_ASSET_BYTES, "glTF file")?;
        let file = std::sync::Arc::new(Self::new(&bytes, path)?);
        super::context::keep(path.to_owned(), file.clone());
        Ok(file)
    }

    /// The encoded bytes (PNG, JPEG) of image `index`: its buffer view, its `data:` URI or its
    /// file beside the document. `path` names the glTF file in errors.
    pub fn image_bytes(&self, index: usize, path: &Path) -> Result<Vec<u8>, String> {
        let fail = |m: String| format!("the glTF file {}: image {index}: {m}", path.display());
        match self.image_at(index).map_err(fail)? {
            ImageAt::View(view) => self.view_bytes(&view).map(<[u8]>::to_vec).map_err(fail),
            ImageAt::Uri(uri) => uri_bytes(uri, &self.dir, "image").map_err(fail),
        }
    }

    /// Where image `index` is, read from the JSON: the `gltf` crate's `Image::source` (1.4.1)
    /// panicked on an image with a bufferView and no mimeType, or with neither a bufferView nor
    /// a uri (found by the `gltf` fuzz target).
    pub fn image_at(&self, index: usize) -> Result<ImageAt<'_>, String> {
        let images = &self.doc.as_json().images;
        let Some(json) = images.get(index) else {
            return Err(format!("there is no such image (it has {})", images.len()));
        };
        match (&json.buffer_view, &json.uri) {
            // The index was validated with the document.
            (Some(v), _) => {
                self.doc.views().nth(v.value()).map(ImageAt::View).ok_or_else(|| "no bufferView".into())
            }
            (None, Some(uri)) => Ok(ImageAt::Uri(uri)),
            (None, None) => Err("it has neither a bufferView nor a uri".into()),
        }
    }

    /// The bytes of buffer view `view`, checked against its buffer.
    fn view_bytes(&self, view: &::gltf::buffer::View) -> Result<&[u8], String> {
        let data = &self.buffers[view.buffer().index()];
        view.offset().checked_add(view.length()).and_then(|end| data.get(view.offset()..end)).ok_or_else(
            || {
                format!(
                    "bufferView {} (bytes {} to {} + {}) overruns buffer {} of {} bytes",
                    view.index(),
                    view.offset(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    data.len()
                )
            },
        )
    }

    /// The components of accessor `a` as numbers, `dims` of them per element: floats as
    /// written, integer types only if `normalized` is allowed and the accessor is normalised
    /// (mapped to [0, 1] or [-1, 1] as the glTF spec's "Animations" and "Meshes" sections say).
    /// `what` names the accessor's use in errors.
    pub fn floats(
        &self,
        a: &::gltf::Accessor,
        dims: Dimensions,
        normalized: bool,
        what: &str,
    ) -> Result<Vec<f32>, String> {
        let n = components(dims).ok_or_else(|| format!("{what}: expected {dims:?}"))?;
        let t = a.data_type();
        let ok = t == DataType::F32 || (normalized && a.normalized() && t != DataType::U32);
        if a.dimensions() != dims || !ok {
            let types = if normalized { "floats or normalised integers" } else { "floats" };
            return Err(format!(
                "{what}: accessor {} holds {:?} of {:?}{}, not {dims:?} of {types}",
                a.index(),
                a.dimensions(),
                t,
                if a.normalized() { " (normalised)" } else { "" }
            ));
        }
        let elements = self.elements(a, what)?;
        let mut out = Vec::with_capacity(a.count() * n);
        for e in elements {
            for c in 0..n {
                let s = c * t.size();
                out.push(match t {
                    DataType::F32 => f32::from_le_bytes(e[s..s + 4].try_into().unwrap()),
                    DataType::U8 => e[s] as f32 / 255.0,
                    DataType::U16 => u16::from_le_bytes([e[s], e[s + 1]]) as f32 / 65535.0,
                    DataType::I8 => (e[s] as i8 as f32 / 127.0).max(-1.0),
                    DataType::I16 => (i16::from_le_bytes([e[s], e[s + 1]]) as f32 / 32767.0).max(-1.0),
                    DataType::U32 => unreachable!("refused above"),
                });
            }
        }
        Ok(out)
    }

    /// The values of the scalar accessor `a` of unsigned integers (vertex indices).
    pub fn indices(&self, a: &::gltf::Accessor, what: &str) -> Result<Vec<u32>, String> {
        let t = a.data_type();
        if a.dimensions() != Dimensions::Scalar || !matches!(t, DataType::U8 | DataType::U16 | DataType::U32)
        {
            return Err(format!(
                "{what}: accessor {} holds {:?} of {t:?}, not scalar unsigned integers",
                a.index(),
                a.dimensions()
            ));
        }
        Ok(self
            .elements(a, what)?
            .map(|e| match t {
                DataType::U8 => e[0] as u32,
                DataType::U16 => u16::from_le_bytes([e[0], e[1]]) as u32,
                _ => u32::from_le_bytes(e[..4].try_into().unwrap()),
            })
            .collect())
    }

    /// The bytes of each element of accessor `a`, every range checked.
    fn elements<'s>(
        &'s self,
        a: &::gltf::Accessor,
        what: &str,
    ) -> Result<impl Iterator<Item = &'s [u8]>, String> {
        let fail = |m: String| format!("{what}: accessor {}{}: {m}", a.index(), name(a.name()));
        if a.sparse().is_some() {
            return Err(fail("it is sparse, which pathwave does not read".into()));
        }
        let Some(view) = a.view() else {
            return Err(fail("it has no bufferView (all zeros), which pathwave does not read".into()));
        };
        let size = a.data_type().size() * components(a.dimensions()).unwrap_or(16);
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(fail(format!(
                "its bufferView's byteStride {stride} is less than an element's {size} bytes"
            )));
        }
        let count = a.count();
        if count == 0 {
            return Err(fail("it has no elements".into()));
        }
        let view_bytes = self.view_bytes(&view).map_err(|m| fail(format!("its {m}")))?;
        let end = count
            .checked_sub(1)
            .and_then(|last| last.checked_mul(stride))
            .and_then(|b| b.checked_add(size))
            .and_then(|b| b.checked_add(a.offset()));
        let bytes = match end.and_then(|end| view_bytes.get(a.offset()..end)) {
            Some(b) => b,
            None => {
                return Err(fail(format!(
                    "{count} elements of {size} bytes, {stride} apart from byte {}, overrun its bufferView {} of {} bytes",
                    a.offset(),
                    view.index(),
                    view_bytes.len()
                )));
            }
        };
        Ok((0..count).map(move |i| &bytes[i * stride..i * stride + size]))
    }
}

/// Where an image's bytes are.
pub enum ImageAt<'a> {
    /// In a buffer view.
    View(::gltf::buffer::View<'a>),
    /// At a URI: a `data:` URI or a file beside the glTF.
    Uri(&'a str),
}

/// How many numbers an element of `dims` has (vectors and scalars only).
fn components(dims: Dimensions) -> Option<usize> {
    match dims {
        Dimensions::Scalar => Some(1),
        Dimensions::Vec2 => Some(2),
        Dimensions::Vec3 => Some(3),
        Dimensions::Vec4 => Some(4),
        Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4 => None,
    }
}

/// ` "name"`, or nothing for an unnamed item.
pub fn name(n: Option<&str>) -> String {
    n.map(|n| format!(" {n:?}")).unwrap_or_default()
}

/// The `gltf` crate's error, with at most the first three validation errors.
fn describe(e: ::gltf::Error) -> String {
    match e {
        ::gltf::Error::Validation(errors) => {
            let first: Vec<String> = errors.iter().take(3).map(|(p, e)| format!("{p}: {e}")).collect();
            let more = errors.len().saturating_sub(3);
            let more = if more > 0 { format!(" (and {more} more)") } else { String::new() };
            format!("it is not valid glTF 2.0: {}{more}", first.join("; "))
        }
        e => e.to_string(),
    }
}

/// The bytes a URI names: a `data:` URI's base64 payload, or a file relative to `dir` (with
/// its `%XX` escapes decoded). `what` names the file in errors.
pub fn uri_bytes(uri: &str, dir: &Path, what: &str) -> Result<Vec<u8>, String> {
    use base64::Engine;
    if let Some(data) = uri.strip_prefix("data:") {
        let Some((_, payload)) = data.split_once(";base64,") else {
            return Err("a data: URI that is not base64 (`data:<type>;base64,<data>`)".into());
        };
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("its data: URI is not valid base64: {e}"));
    }
    crate::format::files::read_bounded(&dir.join(uri_path(uri)?), crate::format::files::MAX_ASSET_BYTES, what)
}

/// The relative path a URI names, its `%XX` escapes decoded; URIs with a scheme (`http:`,
/// `file:`) are refused.
pub fn uri_path(uri: &str) -> Result<PathBuf, String> {
    let scheme = uri.split_once(':').is_some_and(|(s, _)| s.len() > 1 && !s.contains(['/', '\\']));
    if scheme {
        return Err(format!("the URI {uri:?} is not a relative path or a data: URI"));
    }
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (bytes[i], bytes.get(i + 1).copied().and_then(hex), bytes.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, ..) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out)
        .map(PathBuf::from)
        .map_err(|_| format!("the URI {uri:?} escapes bytes that are not UTF-8"))
}
