//! Bounds on what a render may ask for, checked before any work: the image size against the
//! memory the system has, the samples per pixel and the bounces.

use crate::engine::scene::RenderDesc;

/// The largest image side.
pub const MAX_SIDE: u32 = 1 << 16;
/// The end of frame and sample ranges: 2^24, the last integer an f32 (a frame's time, a
/// sample count in the film's arithmetic) holds exactly.
pub const MAX_INDEX: u32 = 1 << 24;
/// The most samples per pixel: sample indices stop at 2^24 (as `--samples` ranges do).
pub const MAX_SPP: u32 = MAX_INDEX;
/// The most bounces: with more, a closed box of mirrors makes a render that never ends.
pub const MAX_DEPTH: u32 = 1024;

/// Refuses render settings (from the scene and the command line's overrides) beyond the bounds
/// above, or an image whose film would not fit in memory ([`check_size`]).
pub fn check_render(r: &RenderDesc) -> Result<(), String> {
    check_size(r.width.get(), r.height.get())?;
    if r.spp.get() > MAX_SPP || r.max_depth > MAX_DEPTH {
        return Err(format!(
            "{} spp, max depth {}: at most {MAX_SPP} samples per pixel and {MAX_DEPTH} bounces \
             (from the scene or --spp, --max-depth)",
            r.spp, r.max_depth
        ));
    }
    Ok(())
}

/// Refuses an image whose side is beyond [`MAX_SIDE`] or whose film (exact sums, the mean,
/// the guides) would not fit in the memory the system has available, before any work.
pub fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!("a {width}x{height} image: each side is at most {MAX_SIDE} pixels"));
    }
    // Per pixel: the accumulator, the mean and a copy for the output, the three guides.
    let per_pixel = std::mem::size_of::<crate::integrator::film::PixelSums>() + 6 * 12;
    let need = width as u64 * height as u64 * per_pixel as u64;
    let available = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        let line = m.lines().find(|l| l.starts_with("MemAvailable:"))?.to_owned();
        line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kib| kib * 1024)
    });
    match available {
        Some(have) if need > have => Err(format!(
            "a {width}x{height} image needs about {} MiB for its film, more than the {} MiB available",
            need >> 20,
            have >> 20
        )),
        _ => Ok(()),
    }
}
