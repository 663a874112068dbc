//! Mitsuba's grid-volume files (`.vol`, the format of its `gridvolume` and `sdfgrid` plugins,
//! compatible with Mitsuba 0.6; `src/render/volumegrid.cpp`).
//!
//! Little-endian: the bytes `VOL`, the version 3, the encoding 1 (32-bit floats, the only one
//! Mitsuba reads), the number of points along x, y and z and the channel count (32-bit
//! integers), a bounding box (six 32-bit floats: the low corner, then the high), then the
//! values with x varying fastest: `data[((z * yres + y) * xres + x) * channels + c]`.

use glam::Vec3;
use std::path::Path;

/// The fixed part of a file, before the values.
pub const HEADER_BYTES: usize = 48;

/// The most values a file may hold (1 GiB of them).
#[cfg(not(fuzzing))]
pub const MAX_VALUES: usize = 1 << 28;
/// The most values a file may hold, in fuzzing builds (`cargo fuzz` sets `cfg(fuzzing)`): 4 MiB
/// of them, so that an input asking for the largest box takes milliseconds, not seconds, and
/// the fuzzers reach their executions. The same checks run at the smaller bound; the unit tests
/// check the bound itself.
#[cfg(fuzzing)]
pub const MAX_VALUES: usize = 1 << 20;

/// What a file's header says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolHeader {
    /// Points along x, y and z (each at least 1).
    pub size: [usize; 3],
    /// Values per point (1 to 6).
    pub channels: usize,
    /// The bounding box the file gives.
    pub bbox: (Vec3, Vec3),
}

impl VolHeader {
    /// Reads and checks the header at the start of `bytes`: `what` and `path` name the file in
    /// errors ("the {what} {path}: ...").
    pub fn parse(bytes: &[u8], path: &Path, what: &str) -> Result<Self, String> {
        let fail = |why: String| format!("the {what} {}: {why}", path.display());
        if bytes.get(..3) != Some(b"VOL") {
            return Err(fail("not a grid volume (Mitsuba's .vol starts with VOL)".into()));
        }
        if bytes.len() < HEADER_BYTES {
            return Err(fail(format!("the header is cut short ({} bytes of {HEADER_BYTES})", bytes.len())));
        }
        if bytes[3] != 3 {
            return Err(fail(format!("version {}: Mitsuba and pathwave read version 3", bytes[3])));
        }
        let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
        let int = |at: usize| i32::from_le_bytes(word(at));
        if int(4) != 1 {
            return Err(fail(format!("data type {}: Mitsuba and pathwave read type 1 (float32)", int(4))));
        }
        let (x, y, z, channels) = (int(8), int(12), int(16), int(20));
        if [x, y, z].iter().any(|&s| s < 1) {
            return Err(fail(format!("size {x} x {y} x {z}: each side must be at least 1")));
        }
        if !(1..=6).contains(&channels) {
            return Err(fail(format!("{channels} channels: Mitsuba's grids have 1 to 6")));
        }
        let size = [x, y, z].map(|s| s as usize);
        let values =
            size.iter().try_fold(channels as usize, |a, &s| a.checked_mul(s)).filter(|&n| n <= MAX_VALUES);
        if values.is_none() {
            return Err(fail(format!(
                "size {x} x {y} x {z} x {channels} channels: more than {MAX_VALUES} values"
            )));
        }
        let float = |at: usize| f32::from_le_bytes(word(at));
        let bbox = (Vec3::new(float(24), float(28), float(32)), Vec3::new(float(36), float(40), float(44)));
        Ok(VolHeader { size, channels: channels as usize, bbox })
    }

    /// How many values the file holds.
    pub fn count(&self) -> usize {
        self.size.iter().product::<usize>() * self.channels
    }

    /// The values after the header in `bytes`, which must hold exactly [`Self::count`] of
    /// them, all finite; `what` and `path` as in [`Self::parse`].
    pub fn values(&self, bytes: &[u8], path: &Path, what: &str) -> Result<Vec<f32>, String> {
        let fail = |why: String| format!("the {what} {}: {why}", path.display());
        let [x, y, z] = self.size;
        if bytes.len() != HEADER_BYTES + 4 * self.count() {
            return Err(fail(format!(
                "{} bytes of values for {x} x {y} x {z} points of {} channel(s) (4 bytes each)",
                bytes.len().saturating_sub(HEADER_BYTES),
                self.channels
            )));
        }
        let values: Vec<f32> = bytes[HEADER_BYTES..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(fail(format!("{} at {}: the values must be finite", values[i], self.place(i))));
        }
        Ok(values)
    }

    /// Where the `i`-th value lies: "point (x, y, z)", and its channel where there are several.
    pub fn place(&self, i: usize) -> String {
        let (c, p) = (i % self.channels, i / self.channels);
        let [x, y] = [self.size[0], self.size[1]];
        let at = format!("point ({}, {}, {})", p % x, p / x % y, p / (x * y));
        match self.channels {
            1 => at,
            _ => format!("{at}, channel {c}"),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The bytes of a `.vol` file of `size` points and `channels` holding `data`.
    pub(crate) fn vol_bytes(size: [i32; 3], channels: i32, data: &[f32]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for n in [1, size[0], size[1], size[2], channels] {
            b.extend(n.to_le_bytes());
        }
        for x in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0].iter().chain(data) {
            b.extend(x.to_le_bytes());
        }
        b
    }

    #[test]
    fn bad_files_are_refused_with_what_is_wrong() {
        let path = Path::new("smoke.vol");
        let read = |b: &[u8]| VolHeader::parse(b, path, "grid").and_then(|h| h.values(b, path, "grid"));
        let err = |b: &[u8]| read(b).unwrap_err();
        let good = vol_bytes([2, 2, 2], 1, &[1.0; 8]);
        assert_eq!(read(&good).unwrap(), vec![1.0; 8]);
        assert!(err(&good[..79]).contains("31 bytes of values"), "{}", err(&good[..79]));
        assert!(err(&good[..20]).contains("cut short"));
        let mut long = good.clone();
        long.push(0);
        assert!(err(&long).contains("33 bytes"));
        let mut nan = good.clone();
        nan[HEADER_BYTES + 4 * 5..HEADER_BYTES + 4 * 6].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(err(&nan).contains("NaN at point (1, 0, 1):"), "{}", err(&nan));
        let inf = vol_bytes([1, 2, 1], 3, &[0.0, 0.0, 0.0, 0.0, f32::INFINITY, 0.0]);
        assert!(err(&inf).contains("point (0, 1, 0), channel 1"), "{}", err(&inf));
        assert!(err(&vol_bytes([0, 1, 1], 1, &[])).contains("at least 1"));
        assert!(err(&vol_bytes([1, 1, 1], 7, &[0.0; 7])).contains("7 channels"));
        let huge = vol_bytes([65536, 65536, 65536], 1, &[]);
        assert!(err(&huge).contains("more than"), "{}", err(&huge));
        let mut wrong = good.clone();
        wrong[0] = b'X';
        assert!(err(&wrong).contains("not a grid volume") && err(&wrong).contains("smoke.vol"));
    }
}
