//! The frames of `pathwave animate`. Each frame sets the ECS world's frame time (the
//! systems move keyframed objects, camera and emitters, and the BVH systems refit or rebuild
//! only what moved), renders with ray times spread over the frame's shutter, and writes the
//! image atomically. Frames whose file exists (and is not empty) are skipped unless
//! overwriting, so a killed run resumes where it stopped. `--shard I/N` renders every N-th frame from the I-th, so that N
//! processes (on one machine or several sharing the output directory) split a sequence.

use crate::engine::format::files::InputFile;
use crate::engine::render_scene::RenderScene;
use crate::engine::world::SceneWorld;
use crate::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The output path of `frame`: `{frame}` in `pattern` becomes the number, `{frame:0N}` the
/// number padded with zeros to N digits (at most 10, the digits of the largest `u32`).
pub fn frame_path(pattern: &str, frame: u32) -> Result<PathBuf, String> {
    let Some(start) = pattern.find("{frame") else {
        return Err(format!("the output {pattern} needs {{frame}} or {{frame:04}} (or end in .gif)"));
    };
    let end = start + pattern[start..].find('}').ok_or_else(|| format!("unclosed {{ in {pattern}"))?;
    let spec = &pattern[start + "{frame".len()..end];
    let width = spec.strip_prefix(":0").and_then(|n| n.parse::<usize>().ok());
    let number = match (spec, width) {
        ("", _) => frame.to_string(),
        (_, Some(width)) if width <= 10 => format!("{frame:0width$}"),
        (s, _) => {
            return Err(format!(
                "unknown frame format {{frame{s}}} in {pattern}: use {{frame}} or {{frame:0N}}, N at most 10"
            ));
        }
    };
    Ok(PathBuf::from(format!("{}{number}{}", &pattern[..start], &pattern[end + 1..])))
}

/// The shutter interval of `frame`: it opens at `frame / fps`
/// ([`frame_start`](crate::engine::format::frames::frame_start), the rule `render --time` finds
/// a moment's frame by) and stays open for `shutter` frame intervals.
pub fn frame_time(frame: u32, fps: f32, shutter: f32) -> (f32, f32) {
    let t = crate::engine::format::frames::frame_start(frame, fps);
    (t, t + shutter / fps)
}

/// Sets the world to `frame` (its time, and the files grid sequences read) and returns the
/// scene to render, or why the frame is not the scene the file asks for.
pub fn scene_at(
    world: &mut SceneWorld,
    frame: u32,
    fps: f32,
    shutter: f32,
) -> Result<Arc<RenderScene>, String> {
    let (open, close) = frame_time(frame, fps, shutter);
    world.set_time(open, close);
    world.set_frame(frame);
    let prefix = format!("frame {frame}: ");
    // Errors of the frame's files name it already.
    world.update_checked().map_err(|e| match e.starts_with(&prefix) {
        true => e,
        false => prefix + &e,
    })
}

/// What `run` needs besides the world.
pub struct Sequence<'a> {
    /// Output pattern (or a `.gif` path).
    pub output: &'a str,
    /// Frames `[first, end)`.
    pub frames: (u32, u32),
    /// `(i, n)`: only frames `first + i + k n`.
    pub shard: (u32, u32),
    /// Frames per second.
    pub fps: f32,
    /// Shutter as a fraction of the frame interval.
    pub shutter: f32,
    /// Re-render frames whose file exists.
    pub overwrite: bool,
    /// No progress lines.
    pub quiet: bool,
    /// How a GIF's frames look.
    pub look: crate::look::Look,
}

/// One frame as `run` hands it to its renderer.
#[derive(Clone, Debug)]
pub struct FrameInfo {
    /// The frame number.
    pub frame: u32,
    /// When its shutter opens (seconds).
    pub open: f32,
    /// When it closes.
    pub close: f32,
    /// The file it will be written to (`None` for a GIF's frames).
    pub path: Option<PathBuf>,
    /// How long the ECS update took (keyframes, BVH rebuilds and refits, extraction).
    pub update: std::time::Duration,
    /// What the update built ([`Builds::since`](crate::engine::world::Builds::since)).
    pub built: String,
    /// The files the frame's media were read from besides the scene's inputs (grid
    /// sequences'), with their hashes ([`SceneWorld::frame_inputs`]).
    pub inputs: Vec<InputFile>,
}

/// Whether a frame's file is there: a regular file that is not empty (versions before atomic
/// writes left empty frames on a full disk; those are rendered again).
pub fn frame_written(path: &Path) -> bool {
    path.metadata().is_ok_and(|m| m.is_file() && m.len() > 0)
}

/// Renders the sequence; `render` turns a scene into an image (and reports its own progress).
/// Prints frame i/N with the overall ETA, then a summary of per-frame times.
pub fn run(
    world: &mut SceneWorld,
    seq: &Sequence,
    mut render: impl FnMut(&RenderScene, &FrameInfo) -> Result<io::Output, String>,
) -> Result<(), String> {
    let gif = Path::new(seq.output).extension().is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    if gif && Path::new(seq.output).exists() && !seq.overwrite {
        eprintln!("{} exists: nothing to do (--overwrite renders it again)", seq.output);
        return Ok(());
    }
    let (first, end) = seq.frames;
    let (shard, shards) = seq.shard;
    if gif && shards > 1 {
        return Err(format!(
            "{}: a GIF needs every frame in one process; shard a sequence of image files instead",
            seq.output
        ));
    }
    let frames: Vec<u32> = (first..end).filter(|f| (f - first) % shards == shard).collect();
    let total = frames.len() as u32;
    let start = Instant::now();
    let (mut times, mut skipped) = (Vec::new(), 0u32);
    let mut gif_out = match gif {
        true => Some(io::GifWriter::create(Path::new(seq.output), seq.fps, seq.look)?),
        false => None,
    };
    for (i, frame) in frames.into_iter().enumerate() {
        let path = if gif { None } else { Some(frame_path(seq.output, frame)?) };
        if let Some(p) = &path
            && frame_written(p)
            && !seq.overwrite
        {
            skipped += 1;
            if !seq.quiet {
                eprintln!("frame {}/{total} ({frame}): {} exists, skipped", i + 1, p.display());
            }
            continue;
        }
        if let Some(dir) = path.as_ref().and_then(|p| p.parent()).filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        let _span = tracing::info_span!("frame", frame).entered();
        let t0 = Instant::now();
        let before = world.builds();
        let scene = {
            let _span = tracing::info_span!("scene_update", frame).entered();
            scene_at(world, frame, seq.fps, seq.shutter)?
        };
        let update = t0.elapsed();
        let built = world.builds().since(&before);
        let (open, close) = frame_time(frame, seq.fps, seq.shutter);
        let inputs = world.frame_inputs();
        let info = FrameInfo { frame, open, close, path: path.clone(), update, built, inputs };
        let out = render(&scene, &info)?;
        match &path {
            Some(p) => {
                io::write_output(p, &out)?;
            }
            None => gif_out.as_mut().expect("a GIF's writer").add(&out.img)?,
        }
        let secs = t0.elapsed().as_secs_f64();
        tracing::info!(frame, update_ms = update.as_secs_f64() * 1e3, "frame rendered in {secs:.2} s");
        times.push((frame, secs));
        if !seq.quiet {
            let done = times.len() as f64;
            let left = (total - skipped) as f64 - done;
            let eta = start.elapsed().as_secs_f64() / done * left;
            let what = path.as_ref().map_or_else(|| "in memory".to_string(), |p| p.display().to_string());
            eprintln!("frame {}/{total} ({frame}): {what} in {secs:.2} s; ETA {eta:.1} s", i + 1);
        }
    }
    // A GIF of no frame (all of them outside the range) is not written.
    if let Some(out) = gif_out.filter(|_| !times.is_empty()) {
        out.finish()?;
    }
    // A fold from +0 (an empty f64 sum is -0.0, printed as -0.00).
    let sum = times.iter().fold(0.0, |a, t| a + t.1);
    eprintln!(
        "{} frames rendered, {skipped} skipped (already there), {sum:.2} s in all{}",
        times.len(),
        if gif { format!(", written to {}", seq.output) } else { String::new() }
    );
    if !times.is_empty() && !seq.quiet {
        let list: Vec<String> = times.iter().map(|(f, s)| format!("{f}: {s:.2} s")).collect();
        eprintln!("per frame: {}", list.join(", "));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_paths_and_times() {
        assert_eq!(frame_path("out/f_{frame:04}.png", 7).unwrap(), PathBuf::from("out/f_0007.png"));
        assert_eq!(frame_path("{frame}.exr", 12).unwrap(), PathBuf::from("12.exr"));
        assert!(frame_path("out.png", 1).is_err());
        assert!(frame_path("f{frame:x}.png", 1).unwrap_err().contains("unknown frame format"));
        // A width of 10^11 zeros would ask for 100 GB.
        assert!(frame_path("f{frame:099999999999}.png", 1).unwrap_err().contains("N at most 10"));
        assert_eq!(frame_time(12, 24.0, 0.5), (0.5, 0.5 + 0.5 / 24.0));
    }
}
