//! Checkpoints of a render in progress: the film's exact per-pixel sums and its sample count,
//! so that a render resumed from one finishes with the bits of an uninterrupted render.
//!
//! The file is binary, little-endian: the magic `PWCKPT04` (the format's version), a 64-bit key
//! (a hash of the scene file and of every setting that changes what a sample is), those
//! settings as text (a `u32` byte count, then UTF-8 lines `name: value`, so that a refusal can
//! say which setting differs), the image width and height, the samples per pixel the render was
//! started for, the index of its first sample and the count done (the samples `first..first + count` of every pixel), then per
//! pixel the three sums (2^50 units) and three sums of squares (2^40 units) as 96-bit
//! fixed-point integers (12 bytes each, as the film keeps them), the count of discarded samples
//! (`u64`) and the sums of the samples' weights and of their squares (`u64` each, 2^32 units),
//! and last the XXH3-64 checksum of everything before it. A file that fails any check (version,
//! checksum, sizes, counts) is refused with what is wrong. Checkpoints of format 3 (`PWCKPT03`:
//! `i128` sums, squares in 2^50 units, no weights, which were all 1) are still read and
//! resumed, their weights the sample counts and their squares' sums rescaled (a variance
//! resumed from one may differ in its last bits from a fresh render's; the image does not).
//! Those of format 2 (format 3 without the settings' text) are read and merge with one
//! another; their key was made from another description of the settings, so `--resume` refuses
//! them, saying that their settings are not recorded. A render with light tracing writes format
//! 5 (`PWCKPT05`): format 4 and, after the pixels, the light tracer's three sums per pixel
//! (`i64`, the film's `LIGHT_UNIT`).

use crate::integrator::film::{Film, PixelSums};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"PWCKPT04";
/// Format 5's magic: format 4 with the light tracer's sums after the pixels.
const MAGIC_V5: &[u8; 8] = b"PWCKPT05";
/// Bytes per pixel of the light tracer's sums (format 5).
const LIGHT_BYTES: usize = 3 * 8;
/// Format 3's magic: no weights (every sample weighed 1).
const MAGIC_V3: &[u8; 8] = b"PWCKPT03";
/// Format 2's magic: format 3 without the settings' text (read with empty
/// [`Checkpoint::settings`]).
const MAGIC_V2: &[u8; 8] = b"PWCKPT02";
/// The first format's magic (no checksum), refused with a message of its own.
const MAGIC_V1: &[u8; 8] = b"PWCKPT01";
/// Bytes of the checksum at the end.
const CHECKSUM_BYTES: usize = 8;
/// Bytes per pixel: six 96-bit sums and three `u64`.
const PIXEL_BYTES: usize = 6 * 12 + 3 * 8;
/// Bytes per pixel of formats 2 and 3: six `i128` and one `u64`.
const PIXEL_BYTES_V3: usize = 6 * 16 + 8;
/// Bytes of the fields after the key (and the settings' text): width, height, target spp,
/// first sample, sample count.
const FIELDS_BYTES: usize = 5 * 4;
/// Bytes before the pixels, but for the settings' text (and its count, in format 3).
const HEADER_BYTES: usize = 8 + 8 + FIELDS_BYTES;
/// The longest settings' text: its `-D` values are the only long part.
pub const MAX_SETTINGS_BYTES: usize = 1 << 20;
/// The largest checkpoint read: that of the largest image `render` makes (65536 x 65536).
pub const MAX_BYTES: u64 = (HEADER_BYTES + 4 + MAX_SETTINGS_BYTES + CHECKSUM_BYTES) as u64
    + (((PIXEL_BYTES + LIGHT_BYTES) as u64) << 32);

/// A render in progress.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// What the samples depend on (see [`key`]).
    pub key: u64,
    /// The settings in the key, one `name: value` per line ([`settings_text`]); empty for a
    /// checkpoint of format 2, which kept only the key.
    pub settings: String,
    /// Samples per pixel the render was started for (the count its sample pattern is
    /// stratified for).
    pub target_spp: u32,
    /// Index of the first sample held (0 unless the render was split by sample ranges).
    pub first_sample: u32,
    /// The samples so far (`film.spp` of them per pixel, from `first_sample` on).
    pub film: Film,
}

/// Where the checkpoint of the image `output` goes: beside it, `.ckpt` appended.
pub fn path_for(output: &Path) -> PathBuf {
    let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_file_name(format!("{name}.ckpt"))
}

/// FNV-1a over what identifies the loaded scene (the hashes of the files it read) and a
/// description of the settings that change what a sample is (not the sample count).
pub fn key(scene: &[u8], settings: &str) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for &b in scene.iter().chain([0xff].iter()).chain(settings.as_bytes()) {
        h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The settings' text of a checkpoint: one `name: value` line per setting, in the given order.
pub fn settings_text(settings: &[(&str, String)]) -> String {
    settings.iter().map(|(name, value)| format!("{name}: {value}\n")).collect()
}

/// The settings whose values differ between two settings' texts, as `(name, value in a,
/// value in b)`, in `a`'s order and then `b`'s (a setting missing on one side reads as
/// `(none)`).
pub fn differences<'a>(a: &'a str, b: &'a str) -> Vec<(&'a str, &'a str, &'a str)> {
    let parse = |t: &'a str| t.lines().map(|l| l.split_once(": ").unwrap_or((l, ""))).collect::<Vec<_>>();
    let (a, b) = (parse(a), parse(b));
    let find = |list: &[(&'a str, &'a str)], name: &str| list.iter().find(|e| e.0 == name).map(|e| e.1);
    let mut out = Vec::new();
    for &(name, va) in &a {
        let vb = find(&b, name).unwrap_or("(none)");
        if va != vb {
            out.push((name, va, vb));
        }
    }
    for &(name, vb) in &b {
        if find(&a, name).is_none() {
            out.push((name, "(none)", vb));
        }
    }
    out
}

/// Why two renders' keys differ, in words: the settings that differ (`a` and `b` name the
/// sides, e.g. "the checkpoint" and "this render"), or else the scene's files.
pub fn mismatch(a_name: &str, a: &str, b_name: &str, b: &str) -> String {
    if a.is_empty() || b.is_empty() {
        return "its settings are not recorded: it was written by an older pathwave".into();
    }
    let diff = differences(a, b);
    if diff.is_empty() {
        return "same settings: the scene file or a file it reads has changed".into();
    }
    diff.iter()
        .map(|(name, va, vb)| format!("{name} {va} in {a_name}, {vb} in {b_name}"))
        .collect::<Vec<_>>()
        .join("; ")
}

impl Checkpoint {
    /// Writes the checkpoint to `path` (whole or not at all).
    pub fn save(&self, path: &Path) -> Result<(), String> {
        crate::io::atomically(path, &self.to_bytes())
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let f = &self.film;
        let mut out =
            Vec::with_capacity(HEADER_BYTES + 4 + self.settings.len() + f.pixels.len() * PIXEL_BYTES);
        out.extend_from_slice(if f.light.is_some() { MAGIC_V5 } else { MAGIC });
        out.extend_from_slice(&self.key.to_le_bytes());
        out.extend_from_slice(&(self.settings.len() as u32).to_le_bytes());
        out.extend_from_slice(self.settings.as_bytes());
        for v in [f.width, f.height, self.target_spp, self.first_sample, f.spp] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for p in &f.pixels {
            let (sums, non_finite, weights) = p.raw();
            for v in sums {
                out.extend_from_slice(&v.to_le_bytes()[..12]);
            }
            for v in [non_finite, weights[0], weights[1]] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for s in f.light.iter().flatten() {
            s.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        }
        let checksum = xxhash_rust::xxh3::xxh3_64(&out);
        out.extend_from_slice(&checksum.to_le_bytes());
        out
    }

    /// Reads a checkpoint written by [`Self::save`]: a regular file (not a device or a pipe)
    /// of at most [`MAX_BYTES`].
    pub fn load(path: &Path) -> Result<Self, String> {
        let bytes = crate::engine::scene::files::read_bounded(path, MAX_BYTES, "checkpoint")?;
        Self::from_bytes(&bytes, path)
    }

    /// Reads a checkpoint's bytes; `path` names it in errors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, String> {
        let bad = |what: &str| format!("{}: not a usable pathwave checkpoint ({what})", path.display());
        if bytes.starts_with(MAGIC_V1) {
            return Err(bad("written by an older pathwave, without a checksum; render without --resume"));
        }
        let (v2, v3, v5) =
            (bytes.starts_with(MAGIC_V2), bytes.starts_with(MAGIC_V3), bytes.starts_with(MAGIC_V5));
        if bytes.len() < HEADER_BYTES + CHECKSUM_BYTES || !(v2 || v3 || v5 || bytes.starts_with(MAGIC)) {
            return Err(bad("no PWCKPT05, PWCKPT04, PWCKPT03 or PWCKPT02 header"));
        }
        let light_bytes = if v5 { LIGHT_BYTES } else { 0 };
        let pixel_bytes = if v2 || v3 { PIXEL_BYTES_V3 } else { PIXEL_BYTES };
        let (body, tail) = bytes.split_at(bytes.len() - CHECKSUM_BYTES);
        if xxhash_rust::xxh3::xxh3_64(body) != u64::from_le_bytes(tail.try_into().unwrap()) {
            return Err(bad("its checksum does not match: the file is damaged"));
        }
        let key = u64::from_le_bytes(bytes[8..16].try_into().unwrap());
        // Format 3 holds the settings' text after the key; format 2 none.
        let (settings, at) = match v2 {
            true => (String::new(), 16),
            false => {
                let n = u32::from_le_bytes(bytes[16..20].try_into().unwrap()) as usize;
                if n > MAX_SETTINGS_BYTES || 20 + n + FIELDS_BYTES > body.len() {
                    return Err(bad(&format!("a settings' text of {n} bytes does not fit")));
                }
                let text = std::str::from_utf8(&bytes[20..20 + n])
                    .map_err(|_| bad("its settings' text is not UTF-8"))?;
                (text.to_string(), 20 + n)
            }
        };
        let u32_at = |i: usize| u32::from_le_bytes(bytes[at + i..at + i + 4].try_into().unwrap());
        let (width, height, target_spp) = (u32_at(0), u32_at(4), u32_at(8));
        let (first_sample, spp) = (u32_at(12), u32_at(16));
        let pixels_at = at + FIELDS_BYTES;
        let expected = (width as u64 * height as u64)
            .checked_mul((pixel_bytes + light_bytes) as u64)
            .and_then(|n| n.checked_add((pixels_at + CHECKSUM_BYTES) as u64));
        if width == 0 || height == 0 || expected != Some(bytes.len() as u64) {
            return Err(bad(&format!("{} bytes do not hold a {width}x{height} image", bytes.len())));
        }
        if first_sample.checked_add(spp).is_none_or(|end| end > target_spp) {
            return Err(bad(&format!(
                "samples {first_sample}..+{spp} do not fit the {target_spp} per pixel it was started for"
            )));
        }
        let mut film = Film::new(width, height);
        film.spp = spp;
        let light_at = pixels_at + film.pixels.len() * pixel_bytes;
        if v5 {
            let sums = body[light_at..].chunks_exact(LIGHT_BYTES);
            let i64_at = |c: &[u8], k: usize| i64::from_le_bytes(c[8 * k..8 * k + 8].try_into().unwrap());
            film.light = Some(sums.map(|c| [0, 1, 2].map(|k| i64_at(c, k))).collect());
        }
        for (p, chunk) in film.pixels.iter_mut().zip(body[pixels_at..light_at].chunks_exact(pixel_bytes)) {
            // Format 4: 96-bit sums (sign-extended); formats 2 and 3: `i128`, squares in 2^50
            // units (2^10 times format 4's).
            let v4 = pixel_bytes == PIXEL_BYTES;
            let size = if v4 { 12 } else { 16 };
            let int_at = |k: usize| {
                let mut b = [0u8; 16];
                b[..size].copy_from_slice(&chunk[size * k..size * (k + 1)]);
                if v4 && chunk[size * k + 11] & 0x80 != 0 {
                    b[12..].fill(0xff);
                }
                i128::from_le_bytes(b)
            };
            let u64_at = |k: usize| {
                let at = 6 * size + 8 * k;
                u64::from_le_bytes(chunk[at..at + 8].try_into().unwrap())
            };
            let mut sums = [0, 1, 2, 3, 4, 5].map(int_at);
            let weights = match v4 {
                true => [u64_at(1), u64_at(2)],
                false => {
                    sums[3..].iter_mut().for_each(|s| *s >>= 10);
                    PixelSums::unit_weights(spp)
                }
            };
            *p = PixelSums::from_raw(sums, u64_at(0), weights);
        }
        Ok(Self { key, settings, target_spp, first_sample, film })
    }
}

/// Merges checkpoints of one render (same scene, settings and size) holding disjoint sample
/// ranges; the result starts at the lowest first sample. Its samples may have gaps: the second
/// value is the end of the last range (`first_sample + film.spp` when there are none).
pub fn merge(parts: &[Checkpoint]) -> Result<(Checkpoint, u32), String> {
    let mut m = Merger::default();
    for c in parts {
        m.add(c.clone())?;
    }
    m.finish()
}

/// [`merge`] as the parts come, one at a time: what it holds is the sum so far and each part's
/// sample range, so that 64 shares of a 4K frame cost the memory of two, not 64. The sums are
/// integers ([`Film`]'s fixed point), so the order the parts come in does not change a bit.
#[derive(Default)]
pub struct Merger {
    sum: Option<Checkpoint>,
    /// Each part's samples, as `first..end`.
    ranges: Vec<(u32, u32)>,
}

impl Merger {
    /// Adds a part: refused if it is of another render than the first part added.
    pub fn add(&mut self, c: Checkpoint) -> Result<(), String> {
        let range = |c: &Checkpoint| format!("samples {}..{}", c.first_sample, c.first_sample + c.film.spp);
        let Some(sum) = &mut self.sum else {
            self.ranges.push((c.first_sample, c.first_sample + c.film.spp));
            self.sum = Some(c);
            return Ok(());
        };
        let (first, _) = self.ranges[0];
        let first = format!("samples {first}..{}", self.ranges[0].1);
        let why = if c.key != sum.key {
            Some(mismatch(&range(&c), &c.settings, &first, &sum.settings))
        } else if c.target_spp != sum.target_spp {
            Some(format!("started for {} and {} samples per pixel", c.target_spp, sum.target_spp))
        } else if (c.film.width, c.film.height) != (sum.film.width, sum.film.height) {
            let (a, b) = (&c.film, &sum.film);
            Some(format!("images of {}x{} and {}x{}", a.width, a.height, b.width, b.height))
        } else {
            None
        };
        if let Some(why) = why {
            return Err(format!("{} are of another render than {first}: {why}", range(&c)));
        }
        self.ranges.push((c.first_sample, c.first_sample + c.film.spp));
        sum.first_sample = sum.first_sample.min(c.first_sample);
        sum.film.merge(&c.film);
        Ok(())
    }

    /// The merged checkpoint and the end of its last range, once no two parts' samples overlap.
    pub fn finish(mut self) -> Result<(Checkpoint, u32), String> {
        let sum = self.sum.ok_or("nothing to merge")?;
        self.ranges.sort_unstable();
        let mut end = self.ranges[0].0;
        for &(first, last) in &self.ranges {
            if first < end {
                return Err(format!(
                    "samples {first}..{last} overlap samples before {end}: each sample must come from one part"
                ));
            }
            end = last;
        }
        Ok((sum, end))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::film::PixelAccumulator;
    use glam::Vec3;

    #[test]
    fn the_light_tracers_sums_read_back_as_written() {
        let mut film = Film::new(2, 2);
        film.spp = 3;
        film.light = Some(vec![[1, -2, 3], [i64::MAX, 0, 5], [7, 8, 9], [i64::MIN, 1, 2]]);
        let settings = settings_text(&[("light_tracing", "On".into())]);
        let c = Checkpoint { key: key(b"scene", &settings), settings, target_spp: 8, first_sample: 0, film };
        let bytes = c.to_bytes();
        assert!(bytes.starts_with(MAGIC_V5));
        let path = Path::new("light.ckpt");
        assert_eq!(Checkpoint::from_bytes(&bytes, path).unwrap(), c);
        // The same film without them is format 4, a byte count the other cannot pass for.
        let plain = Checkpoint { film: Film { light: None, ..c.film.clone() }, ..c.clone() };
        let mut b = plain.to_bytes();
        assert!(b.starts_with(MAGIC));
        b[..8].copy_from_slice(MAGIC_V5);
        let n = b.len() - CHECKSUM_BYTES;
        let sum = xxhash_rust::xxh3::xxh3_64(&b[..n]);
        b[n..].copy_from_slice(&sum.to_le_bytes());
        let err = Checkpoint::from_bytes(&b, path).unwrap_err();
        assert!(err.contains("do not hold a 2x2 image"), "{err}");
    }

    #[test]
    fn a_checkpoint_reads_back_as_written_and_a_damaged_one_is_refused() {
        let mut film = Film::new(3, 2);
        film.spp = 2;
        for (i, p) in film.pixels.iter_mut().enumerate() {
            let mut a = PixelAccumulator::default();
            // Negative sums too (the 96-bit fields are sign-extended as read).
            a.add(Vec3::new(i as f32 - 2.5, 0.5, 1e-9));
            a.add(Vec3::splat(f32::NAN));
            p.add(&a);
        }
        let settings = settings_text(&[("seed", "0".into()), ("max_depth", "64".into())]);
        let c = Checkpoint { key: key(b"scene", &settings), settings, target_spp: 64, first_sample: 3, film };
        let path = std::env::temp_dir().join(format!("pathwave-ckpt-{}.ckpt", std::process::id()));
        c.save(&path).unwrap();
        assert_eq!(Checkpoint::load(&path).unwrap(), c);
        let bytes = std::fs::read(&path).unwrap();
        let truncated = Checkpoint::from_bytes(&bytes[..bytes.len() - 1], &path).unwrap_err();
        assert!(truncated.contains("checksum does not match"), "{truncated}");
        // Consistent checksums over inconsistent contents: each field check speaks.
        let resealed = |edit: &dyn Fn(&mut Vec<u8>)| {
            let mut b = bytes[..bytes.len() - CHECKSUM_BYTES].to_vec();
            edit(&mut b);
            let sum = xxhash_rust::xxh3::xxh3_64(&b);
            b.extend_from_slice(&sum.to_le_bytes());
            Checkpoint::from_bytes(&b, &path).unwrap_err()
        };
        // The fields after the settings' text.
        let at = 20 + c.settings.len();
        let set = |b: &mut Vec<u8>, i: usize, v: u32| b[at + i..at + i + 4].copy_from_slice(&v.to_le_bytes());
        let wide = resealed(&|b| set(b, 0, 4));
        assert!(wide.contains("do not hold a 4x2 image"), "{wide}");
        let wrapped = resealed(&|b| {
            set(b, 0, 0x1_0000);
            set(b, 4, 0x1_0000);
        });
        assert!(wrapped.contains("do not hold a 65536x65536 image"), "{wrapped}");
        let many = resealed(&|b| set(b, 16, 62));
        assert!(many.contains("do not fit the 64 per pixel"), "{many}");
        let long = resealed(&|b| b[16..20].copy_from_slice(&u32::MAX.to_le_bytes()));
        assert!(long.contains("settings' text of 4294967295 bytes does not fit"), "{long}");
        let beyond = resealed(&|b| {
            let n = b.len() as u32;
            b[16..20].copy_from_slice(&n.to_le_bytes())
        });
        assert!(beyond.contains("does not fit"), "{beyond}");
        let binary = resealed(&|b| b[20] = 0xff);
        assert!(binary.contains("not UTF-8"), "{binary}");
        // Formats 3 (no weights: every sample weighed 1) and 2 (no settings' text either) are
        // still read, with the weights of their sample counts and empty settings.
        // Their pixels: `i128` sums, squares in 2^50 units.
        let pixels = at + FIELDS_BYTES;
        let unweighted: Vec<u8> = c
            .film
            .pixels
            .iter()
            .flat_map(|p| {
                let (sums, non_finite, _) = p.raw();
                let wide = [sums[0], sums[1], sums[2], sums[3] << 10, sums[4] << 10, sums[5] << 10];
                let mut b: Vec<u8> = wide.iter().flat_map(|v| v.to_le_bytes()).collect();
                b.extend_from_slice(&non_finite.to_le_bytes());
                b
            })
            .collect();
        assert_eq!(unweighted.len(), c.film.pixels.len() * PIXEL_BYTES_V3);
        let sealed = |mut b: Vec<u8>| {
            let sum = xxhash_rust::xxh3::xxh3_64(&b);
            b.extend_from_slice(&sum.to_le_bytes());
            b
        };
        let v3 = sealed([b"PWCKPT03", &bytes[8..pixels], &unweighted[..]].concat());
        assert_eq!(Checkpoint::from_bytes(&v3, &path).unwrap(), c);
        let v2 = sealed([b"PWCKPT02", &bytes[8..16], &bytes[at..pixels], &unweighted[..]].concat());
        let old = Checkpoint::from_bytes(&v2, &path).unwrap();
        assert_eq!(old, Checkpoint { settings: String::new(), ..c.clone() });
        let png = Checkpoint::from_bytes(b"PNG....", &path).unwrap_err();
        assert!(png.contains("not a usable pathwave checkpoint"), "{png}");
        let v1 = Checkpoint::from_bytes(b"PWCKPT01 and the rest of an old file", &path).unwrap_err();
        assert!(v1.contains("older pathwave"), "{v1}");
        std::fs::remove_file(&path).unwrap();
        assert_ne!(key(b"scene", "settings"), key(b"scene", "settingz"));
        assert_ne!(key(b"scene", "settings"), key(b"scen", "esettings"));
    }

    #[test]
    fn a_mismatch_names_the_settings_that_differ() {
        let a = settings_text(&[("size", "96x96".into()), ("seed", "0".into()), ("defines", "[]".into())]);
        let b = settings_text(&[("size", "96x96".into()), ("seed", "7".into()), ("sampler", "Sobol".into())]);
        assert_eq!(
            differences(&a, &b),
            [("seed", "0", "7"), ("defines", "[]", "(none)"), ("sampler", "(none)", "Sobol")]
        );
        assert!(differences(&a, &a).is_empty());
        let why = mismatch("the checkpoint", &a, "this render", &b);
        assert!(why.starts_with("seed 0 in the checkpoint, 7 in this render; defines"), "{why}");
        assert_eq!(
            mismatch("x", &a, "y", &a),
            "same settings: the scene file or a file it reads has changed"
        );
        assert!(mismatch("x", "", "y", &a).contains("older pathwave"));
        // A value holding ": " keeps the rest of its line.
        let t = settings_text(&[("defines", "[(\"A\", \"b: c\")]".into())]);
        assert_eq!(differences(&t, ""), [("defines", "[(\"A\", \"b: c\")]", "(none)")]);
    }
}
