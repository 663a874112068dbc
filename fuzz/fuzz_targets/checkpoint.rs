//! Arbitrary bytes, and mutations of checkpoints written by `render --samples` (the seed
//! corpus), into the checkpoint reader and `merge`. The input after its first byte is cut into
//! parts before each `PWCKPT0` magic (formats 2, 3 and 4); when the first byte is odd each part's checksum is
//! recomputed first, so that mutations reach the checks behind it. Whatever loads is merged
//! and read out as `merge` and `--resume` do: nothing may panic, a merged checkpoint must read
//! back as written, and its mean must be finite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave::checkpoint::{self, Checkpoint};
use std::path::Path;

const MAGIC: &[u8] = b"PWCKPT0";

fuzz_target!(|data: &[u8]| {
    let Some((&flags, rest)) = data.split_first() else { return };
    let mut starts: Vec<usize> = (1..rest.len()).filter(|&i| rest[i..].starts_with(MAGIC)).collect();
    starts.insert(0, 0);
    starts.push(rest.len());
    let path = Path::new("fuzz.ckpt");
    let mut parts = Vec::new();
    for w in starts.windows(2).take(4) {
        let mut part = rest[w[0]..w[1]].to_vec();
        if flags & 1 == 1 && part.len() >= 8 {
            let n = part.len() - 8;
            let sum = xxhash_rust::xxh3::xxh3_64(&part[..n]);
            part[n..].copy_from_slice(&sum.to_le_bytes());
        }
        if let Ok(c) = Checkpoint::from_bytes(&part, path) {
            parts.push(c);
        }
    }
    let Ok((merged, end)) = checkpoint::merge(&parts) else { return };
    assert!(merged.first_sample + merged.film.spp <= end && end <= merged.target_spp);
    let f = &merged.film;
    assert!(f.mean().iter().all(|p| p.is_finite()));
    let _ = (f.variance_of_mean(), f.non_finite(), f.non_finite_pixels());
    assert_eq!(Checkpoint::from_bytes(&merged.to_bytes(), path).as_ref(), Ok(&merged));
});
