//! Image files: linear float EXR in and out, tone-clamped sRGB PNG out.

use crate::engine::scene::SceneDesc;
use crate::look::Look;
use glam::Vec3;
use image::{ImageBuffer, Rgb, Rgb32FImage, RgbImage};
use std::path::{Path, PathBuf};

/// A linear RGB image, row 0 on top.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels.
    pub pixels: Vec<Vec3>,
}

/// Reads any image `image` can decode (EXR stays linear; 8-bit files are returned as stored),
/// within the bounds of textures ([`crate::engine::scene::files::decode_image`]).
pub fn read_linear(path: &Path) -> Result<LinearImage, String> {
    let img = crate::engine::scene::files::decode_image(path)?.into_rgb32f();
    let pixels = img.pixels().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    Ok(LinearImage { width: img.width(), height: img.height(), pixels })
}

/// Writes `.exr` (linear float) or `.png` or `.jpg` (through `look`: an exposure, a view
/// transform, sRGB); returns how many pixels an 8-bit file clipped. The image is encoded in memory, then written with
/// [`atomically`].
pub fn write(path: &Path, img: &LinearImage, look: &Look) -> Result<usize, String> {
    let (bytes, clamped) = encode(path, img, look)?;
    atomically(path, &bytes)?;
    Ok(clamped)
}

/// Writes `bytes` to `path` whole or not at all: to a temporary file beside it (`tempfile`),
/// synced to the disk and checked, then renamed over `path`. On any failure the previous file
/// is left as it was and the error names `path`.
pub fn atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write;
    let fail = |e: std::io::Error| format!("{}: cannot write: {e}", path.display());
    let mut tmp = temp_beside(path).map_err(fail)?;
    // Through the `File`: `NamedTempFile`'s own methods add the temporary file's name to errors.
    tmp.as_file_mut().write_all(bytes).map_err(fail)?;
    tmp.as_file().sync_all().map_err(fail)?;
    tmp.persist(path).map_err(|e| fail(e.error))?;
    Ok(())
}

/// Checks an output before any work: a format `write` knows (`.png`, `.exr`; `.gif` too when
/// `gif`), a folder that exists and takes a new file, and not one of `inputs` (the scene, the
/// parts being merged), which it would replace.
pub fn check_output(path: &Path, inputs: &[&Path], gif: bool) -> Result<(), String> {
    let ext = extension(path);
    let known = ["png", "jpg", "jpeg", "exr"].contains(&ext.as_str()) || (gif && ext == "gif");
    if !known {
        let formats = if gif { ".png, .jpg, .exr or .gif" } else { ".png, .jpg or .exr" };
        return Err(format!("{}: unknown output format (use {formats})", path.display()));
    }
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return Err(format!("{}: the output would replace an input ({})", path.display(), input.display()));
    }
    // The folder must take a new file (a temporary one, removed at once).
    temp_beside(path).map(drop).map_err(|e| format!("{}: cannot write there: {e}", path.display()))
}

/// Checks, before any work, every file a render will write (`writes`: its output and the
/// side files its flags add) against the files the scene read ([`Inputs`]), and that none
/// names a folder, comes twice, or lies where a new file cannot be made (a missing folder, a
/// name too long once the temporary file's affixes are added).
pub fn check_writes(writes: &[PathBuf], inputs: &Inputs) -> Result<(), String> {
    for (i, out) in writes.iter().enumerate() {
        inputs.check(out)?;
        if out.is_dir() {
            return Err(format!("{}: is a folder; name the file to write", out.display()));
        }
        if writes[..i].iter().any(|o| o == out || same_file(o, out)) {
            return Err(format!("{}: the render would write this file twice", out.display()));
        }
        temp_beside(out).map(drop).map_err(|e| format!("{}: cannot write there: {e}", out.display()))?;
    }
    Ok(())
}

/// The files a scene read, as their canonical paths: a file to be written must not be one.
pub struct Inputs(Vec<PathBuf>);

impl Inputs {
    /// These files (those that exist).
    pub fn new<'a>(paths: impl IntoIterator<Item = &'a Path>) -> Self {
        Inputs(paths.into_iter().filter_map(|f| std::fs::canonicalize(f).ok()).collect())
    }

    /// Every file the load of `desc` read ([`SceneDesc::inputs`]).
    pub fn of(desc: &SceneDesc) -> Self {
        Self::new(desc.inputs.iter().map(|f| f.path.as_path()))
    }

    /// These inputs and the files `more` (those that exist): a frame's besides the scene's.
    pub fn and(mut self, more: impl IntoIterator<Item = PathBuf>) -> Self {
        self.0.extend(more.into_iter().filter_map(|f| std::fs::canonicalize(f).ok()));
        self
    }

    /// Refuses `out` when it is one of the inputs (through any link or `..`); a file that does
    /// not exist yet is none.
    pub fn check(&self, out: &Path) -> Result<(), String> {
        match std::fs::canonicalize(out) {
            Ok(c) if self.0.contains(&c) => Err(format!(
                "{}: the render would write over this file, which the scene reads",
                out.display()
            )),
            _ => Ok(()),
        }
    }
}

/// True when both paths exist and name the same file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// A temporary file in `path`'s directory, named after it (`.NAME.XXXXXX.tmp`), created with
/// the permissions a new file gets (0o666 less the umask, not `tempfile`'s private 0o600),
/// since it becomes `path`.
///
/// It is locked (`File::lock`) while it lives, and the temporary files of `path` that no live
/// process holds (left by one killed while writing) are removed first: interrupted writes leave
/// nothing behind for long. Its errors do not name the temporary file ([`without_temp_name`]).
pub fn temp_beside(path: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let prefix = format!(".{name}.");
    remove_stale_temps(dir, &prefix);
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    b.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = b.tempfile_in(dir).map_err(without_temp_name)?;
    tmp.as_file().lock()?;
    Ok(tmp)
}

/// Removes the files `dir/PREFIX??????.tmp` (a [`temp_beside`]'s names) whose lock no process
/// holds. Best effort: a file that cannot be read or removed is left.
fn remove_stale_temps(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let random = name.strip_prefix(prefix).and_then(|r| r.strip_suffix(".tmp"));
        if !random.is_some_and(|r| r.len() == 6 && r.chars().all(|c| c.is_ascii_alphanumeric())) {
            continue;
        }
        // A lock taken is a file nobody writes: its writer died.
        if let Ok(f) = std::fs::File::open(e.path())
            && f.try_lock().is_ok()
        {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// `e` without the temporary file's name, which `tempfile` wraps around the system's errors
/// (the user knows the output's path, not the temporary name): its kind ("permission denied",
/// "no storage space").
pub fn without_temp_name(e: std::io::Error) -> std::io::Error {
    match e.get_ref() {
        Some(_) if e.kind() == std::io::ErrorKind::NotFound => {
            std::io::Error::new(e.kind(), "no such folder")
        }
        Some(_) => std::io::Error::from(e.kind()),
        None => e,
    }
}

fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

/// An animated GIF (through a [`Look`], 256 colours per frame, played at `fps`, looping) written as
/// its frames come: each frame is encoded and appended to a temporary file beside the output
/// at once, so no frame stays in memory; [`GifWriter::finish`] renames it over the output.
/// Dropped unfinished (an error, an interrupt), it leaves the output as it was.
pub struct GifWriter {
    path: PathBuf,
    tmp: tempfile::NamedTempFile,
    /// What the encoder wrote since the last frame was appended to `tmp`.
    spool: std::rc::Rc<std::cell::RefCell<Vec<u8>>>,
    enc: Option<image::codecs::gif::GifEncoder<Spool>>,
    fps: f64,
    frames: u64,
    look: Look,
}

/// The encoder's output, appended to the file after each frame (so that a failed write is
/// seen where it happens, which a buffered writer dropped at the end would hide).
struct Spool(std::rc::Rc<std::cell::RefCell<Vec<u8>>>);

impl std::io::Write for Spool {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl GifWriter {
    /// Starts the GIF at `path`, played at `fps` (> 0), its frames through `look`.
    pub fn create(path: &Path, fps: f32, look: Look) -> Result<Self, String> {
        let fail = |e: std::io::Error| format!("{}: cannot write: {e}", path.display());
        let tmp = temp_beside(path).map_err(fail)?;
        let spool = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
        let mut enc = image::codecs::gif::GifEncoder::new_with_speed(Spool(spool.clone()), 10);
        enc.set_repeat(image::codecs::gif::Repeat::Infinite)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Self { path: path.to_owned(), tmp, spool, enc: Some(enc), fps: fps as f64, frames: 0, look })
    }

    /// Appends a frame. GIF delays are whole hundredths of a second: frame i shows from
    /// round(100 i / fps) to round(100 (i + 1) / fps) (at least one hundredth), so that 24 fps
    /// alternates 4 and 5 and plays at 24 frames a second on average, not 25.
    pub fn add(&mut self, img: &LinearImage) -> Result<(), String> {
        let at = |i: u64| (100.0 * i as f64 / self.fps).round() as u64;
        let hundredths = (at(self.frames + 1) - at(self.frames)).clamp(1, u16::MAX as u64) as u32;
        let delay = image::Delay::from_numer_denom_ms(10 * hundredths, 1);
        let (rgb, _) = self.look.srgb8(&img.pixels);
        let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 255]).collect();
        let buf = image::RgbaImage::from_raw(img.width, img.height, rgba).expect("size");
        let enc = self.enc.as_mut().expect("frames are added before finish");
        enc.encode_frame(image::Frame::from_parts(buf, 0, 0, delay))
            .map_err(|e| format!("{}: {e}", self.path.display()))?;
        self.frames += 1;
        self.append()
    }

    /// Ends the GIF and renames it over the output, synced to the disk.
    pub fn finish(mut self) -> Result<(), String> {
        // The encoder writes the trailer when dropped.
        drop(self.enc.take());
        self.append()?;
        let fail = |e: std::io::Error| format!("{}: cannot write: {e}", self.path.display());
        self.tmp.as_file().sync_all().map_err(fail)?;
        self.tmp.persist(&self.path).map_err(|e| fail(e.error))?;
        Ok(())
    }

    fn append(&mut self) -> Result<(), String> {
        use std::io::Write;
        let bytes = std::mem::take(&mut *self.spool.borrow_mut());
        // Through the `File`: `NamedTempFile`'s own methods add the temporary file's name to errors.
        self.tmp
            .as_file_mut()
            .write_all(&bytes)
            .map_err(|e| format!("{}: cannot write: {e}", self.path.display()))
    }
}

/// The file's bytes for `path`'s format, and how many pixels a PNG clamped.
fn encode(path: &Path, img: &LinearImage, look: &Look) -> Result<(Vec<u8>, usize), String> {
    let err = |e: image::ImageError| format!("{}: {e}", path.display());
    let mut bytes = std::io::Cursor::new(Vec::new());
    let clamped = match extension(path).as_str() {
        "exr" => {
            let data: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
            let buf: Rgb32FImage = ImageBuffer::from_raw(img.width, img.height, data).expect("size matches");
            buf.write_to(&mut bytes, image::ImageFormat::OpenExr).map_err(err)?;
            0
        }
        "png" => {
            let (data, clamped) = look.srgb8(&img.pixels);
            let buf: RgbImage =
                ImageBuffer::<Rgb<u8>, _>::from_raw(img.width, img.height, data).expect("size");
            buf.write_to(&mut bytes, image::ImageFormat::Png).map_err(err)?;
            clamped
        }
        "jpg" | "jpeg" => {
            let (data, clamped) = look.srgb8(&img.pixels);
            // Quality 95 of 100: what image editors call high (the crate's default is 75).
            let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95);
            let buf: RgbImage =
                ImageBuffer::<Rgb<u8>, _>::from_raw(img.width, img.height, data).expect("size");
            buf.write_with_encoder(enc).map_err(err)?;
            clamped
        }
        _ => return Err(format!("{}: unknown output format (use .png, .jpg or .exr)", path.display())),
    };
    Ok((bytes.into_inner(), clamped))
}

/// An image as written: the beauty, the layers an EXR carries beside it (AOVs) and the header's
/// metadata. A PNG holds the beauty only.
pub struct Output {
    /// The beauty.
    pub img: LinearImage,
    /// Further layers (EXR only).
    pub layers: Vec<ExrLayer<'static>>,
    /// String attributes of an EXR's header.
    pub metadata: Vec<(&'static str, String)>,
    /// How a PNG shows the beauty.
    pub look: Look,
}

impl Output {
    /// The beauty alone.
    pub fn plain(img: LinearImage) -> Self {
        Self { img, layers: Vec::new(), metadata: Vec::new(), look: Look::default() }
    }
}

/// Writes `out` to `path`: with layers, an EXR with the beauty as `R`, `G`, `B`, `A` (1), every
/// layer as named channels (float) and the metadata; else as [`write()`] does (a PNG of the
/// beauty, or an EXR of it alone, as `merge` and resumed renders write it, to the same bytes);
/// returns how many pixels a PNG clamped.
pub fn write_output(path: &Path, out: &Output) -> Result<usize, String> {
    if extension(path) != "exr" || out.layers.is_empty() {
        return write(path, &out.img, &out.look);
    }
    let n = out.img.pixels.len();
    let beauty = out.img.pixels.iter().flat_map(|p| [p.x, p.y, p.z, 1.0]).collect();
    let mut layers = vec![ExrLayer { name: "", channels: &["R", "G", "B", "A"], data: beauty }];
    for l in &out.layers {
        assert_eq!(l.data.len(), n * l.channels.len(), "layer {}", l.name);
        layers.push(ExrLayer { name: l.name, channels: l.channels, data: l.data.clone() });
    }
    write_exr_layers(path, (out.img.width, out.img.height), &layers, false, &out.metadata)?;
    Ok(0)
}

/// One layer of a multi-layer EXR: channels `name.C` for each `C` of `channels` (the beauty,
/// with an empty name, has bare `R`, `G`, `B`), and the samples pixel by pixel, row 0 on top,
/// `channels.len()` per pixel.
pub struct ExrLayer<'a> {
    /// Prefix of its channels (`albedo`), empty for the beauty.
    pub name: &'a str,
    /// Its channels' names (`R`, `G`, `B`; `X`, `Y`, `Z`; `Z`).
    pub channels: &'a [&'a str],
    /// The samples.
    pub data: Vec<f32>,
}

/// Writes one EXR file holding `layers` of a `width` x `height` image as channels of one part
/// (pbrt-v4's and Blender's convention: `R`, `G`, `B`, `albedo.R`, `normal.X`, `depth.Z`, ...),
/// as 16-bit halves when `half` (else 32-bit floats), with `metadata` as string attributes of
/// the header; atomically, as [`write()`] does.
pub fn write_exr_layers(
    path: &Path,
    (width, height): (u32, u32),
    layers: &[ExrLayer],
    half: bool,
    metadata: &[(&str, String)],
) -> Result<(), String> {
    use exr::prelude::*;
    let n = width as usize * height as usize;
    let mut list = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for layer in layers {
        let k = layer.channels.len();
        assert_eq!(layer.data.len(), n * k, "layer {}: {k} samples per pixel", layer.name);
        for (c, channel) in layer.channels.iter().enumerate() {
            let samples = layer.data.iter().skip(c).step_by(k).copied();
            let samples = match half {
                true => FlatSamples::F16(samples.map(f16::from_f32).collect()),
                false => FlatSamples::F32(samples.collect()),
            };
            let name = match layer.name.is_empty() {
                true => channel.to_string(),
                false => format!("{}.{channel}", layer.name),
            };
            list.push(AnyChannel::new(name.as_str(), samples));
        }
    }
    let mut attributes =
        LayerAttributes { software_name: Some(Text::from("pathwave")), ..Default::default() };
    for (key, value) in metadata {
        attributes.other.insert(Text::from(*key), AttributeValue::Text(Text::from(value.as_str())));
    }
    let size = Vec2(width as usize, height as usize);
    let image =
        Image::from_layer(Layer::new(size, attributes, Encoding::FAST_LOSSLESS, AnyChannels::sort(list)));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    atomically(path, &bytes.into_inner())
}

/// Every channel of an EXR file by name, as f32 samples row by row (the first part only),
/// with the image's size and the header's string attributes.
pub fn read_exr_channels(path: &Path) -> Result<ExrChannels, String> {
    use exr::prelude::*;
    let err = |e: exr::error::Error| format!("{}: {e}", path.display());
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(err)?;
    let layer = &image.layer_data;
    let channels = (layer.channel_data.list.iter())
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    let metadata = (layer.attributes.other.iter())
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok(ExrChannels { width: layer.size.0 as u32, height: layer.size.1 as u32, channels, metadata })
}

/// What [`read_exr_channels`] returns.
#[derive(Debug)]
pub struct ExrChannels {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Each channel's name and samples, in the file's (alphabetical) order.
    pub channels: Vec<(String, Vec<f32>)>,
    /// String attributes of the header.
    pub metadata: Vec<(String, String)>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A write removes the temporary files of its output that a killed writer left, and keeps
    /// those a live writer holds.
    #[test]
    fn stale_temporary_files_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.exr");
        let stale = dir.path().join(".out.exr.Ab12Cd.tmp");
        std::fs::write(&stale, b"half written").unwrap();
        let live = dir.path().join(".out.exr.Zz99Yy.tmp");
        let held = std::fs::File::create(&live).unwrap();
        held.lock().unwrap();
        let other = dir.path().join(".other.exr.Ab12Cd.tmp");
        std::fs::write(&other, b"another output's").unwrap();
        atomically(&out, b"image").unwrap();
        assert!(!stale.exists(), "the stale file is left");
        assert!(live.exists() && other.exists(), "a live writer's or another output's file is removed");
        assert_eq!(std::fs::read(&out).unwrap(), b"image");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left.len(), 3, "{left:?}");
        drop(held);
    }

    /// A beauty with albedo, normal and depth layers: one file whose channels read back by name
    /// (float and half), with its metadata, and which the plain reader sees as the beauty.
    #[test]
    fn layers_and_metadata_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (5u32, 3u32);
        let n = (w * h) as usize;
        let beauty: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32, 0.5, 2.0)).collect();
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let albedo = vec![0.25f32; 3 * n];
        let depth: Vec<f32> = (0..n).map(|i| 10.0 + i as f32).collect();
        for half in [false, true] {
            let path = dir.path().join(format!("l{half}.exr"));
            let layers = [
                ExrLayer { name: "", channels: &["R", "G", "B"], data: flat(&beauty) },
                ExrLayer { name: "albedo", channels: &["R", "G", "B"], data: albedo.clone() },
                ExrLayer { name: "depth", channels: &["Z"], data: depth.clone() },
            ];
            write_exr_layers(&path, (w, h), &layers, half, &[("spp", "16".into())]).unwrap();
            let got = read_exr_channels(&path).unwrap();
            let names: Vec<&str> = got.channels.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(names, ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R", "depth.Z"]);
            assert_eq!((got.width, got.height), (w, h));
            assert_eq!(got.channels[6].1, depth, "depth (exact in half too: small integers)");
            assert_eq!(got.channels[2].1, beauty.iter().map(|p| p.x).collect::<Vec<_>>());
            assert!(got.metadata.contains(&("spp".to_string(), "16".to_string())));
            let plain = read_linear(&path).unwrap();
            assert_eq!(plain.pixels, beauty, "the plain reader sees the beauty");
        }
    }
}
