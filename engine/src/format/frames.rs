//! Frame-numbered file names (`smoke_{frame:04}.vdb`) and the frame a moment of time belongs
//! to.
//!
//! A name holds `{frame}` (the frame number as written, `7`) or `{frame:0N}` (padded with
//! zeros to N digits, N from 1 to 10, the digits of the largest `u32`: `{frame:04}` gives
//! `0007`), once or more; any other `{` or `}` is refused (there is no escape for a literal
//! brace). It is the syntax of `pathwave animate`'s output pattern.
//!
//! Frame `n` of a sequence at `fps` frames per second opens its shutter at [`frame_start`]
//! `(n, fps)`, and the frame of a moment `t` ([`frame_at`]) is the last one opened at or before
//! `t`: a shutter never reaches the next frame's start, so every moment inside frame `n`'s
//! shutter belongs to frame `n`.

/// A file name with frame numbers in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {
    /// Text and numbers, in order.
    parts: Vec<Part>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Part {
    Text(String),
    /// The frame number, padded with zeros to this many digits (0: as written).
    Frame(usize),
}

/// The most digits `{frame:0N}` pads to.
pub const MAX_FRAME_DIGITS: usize = 10;

impl FramePattern {
    /// The pattern of `name`: `None` for a name without braces (one file for every frame),
    /// an error naming the first brace that is not `{frame}` or `{frame:0N}`.
    pub fn parse(name: &str) -> Result<Option<Self>, String> {
        if !name.contains(['{', '}']) {
            return Ok(None);
        }
        let bad = |what: &str| {
            format!(
                "{what} in \"{name}\": a file name takes {{frame}} or {{frame:0N}} (N from 1 to {MAX_FRAME_DIGITS}) for the frame number, and no other braces"
            )
        };
        let (mut parts, mut rest) = (Vec::new(), name);
        while let Some(open) = rest.find(['{', '}']) {
            if rest[open..].starts_with('}') {
                return Err(bad("a `}` that closes nothing"));
            }
            let Some(len) = rest[open..].find('}') else { return Err(bad("an unclosed `{`")) };
            let field = &rest[open..open + len + 1];
            let width = match field.strip_prefix("{frame").and_then(|f| f.strip_suffix('}')) {
                Some("") => 0,
                Some(spec) => match spec.strip_prefix(":0").and_then(|n| n.parse::<usize>().ok()) {
                    Some(n) if (1..=MAX_FRAME_DIGITS).contains(&n) && !spec[2..].starts_with('+') => n,
                    _ => return Err(bad(&format!("`{field}`"))),
                },
                None => return Err(bad(&format!("`{field}`"))),
            };
            if open > 0 {
                parts.push(Part::Text(rest[..open].to_owned()));
            }
            parts.push(Part::Frame(width));
            rest = &rest[open + len + 1..];
        }
        if !rest.is_empty() {
            parts.push(Part::Text(rest.to_owned()));
        }
        Ok(Some(Self { parts }))
    }

    /// The name of frame `frame`.
    pub fn at(&self, frame: u32) -> String {
        self.parts
            .iter()
            .map(|p| match p {
                Part::Text(t) => t.clone(),
                Part::Frame(width) => format!("{frame:0width$}"),
            })
            .collect()
    }
}

/// When frame `frame` opens its shutter at `fps` frames per second: `frame / fps` seconds, in
/// single precision (what `pathwave animate` renders it at).
pub fn frame_start(frame: u32, fps: f32) -> f32 {
    frame as f32 / fps
}

/// The frame that the moment `time` (seconds) belongs to at `fps` frames per second: the last
/// one whose [`frame_start`] is at or before it, so that `frame_at(frame_start(n, fps), fps)`
/// is `n`. A moment before frame 0, or past the last `u32` frame, has none.
pub fn frame_at(time: f32, fps: f32) -> Result<u32, String> {
    let guess = (time as f64 * fps as f64).floor();
    if guess < 0.0 {
        return Err(format!("{time} s at {fps} frames per second comes before frame 0"));
    }
    if !(guess < (u32::MAX - 1) as f64) {
        return Err(format!("{time} s at {fps} frames per second lies past frame {}", u32::MAX - 1));
    }
    // The guess, corrected to agree with `frame_start`'s rounding.
    let mut n = guess.max(0.0) as u32;
    while n > 0 && frame_start(n, fps) > time {
        n -= 1;
    }
    while n < u32::MAX - 1 && frame_start(n + 1, fps) <= time {
        n += 1;
    }
    match frame_start(n, fps) <= time {
        true => Ok(n),
        false => Err(format!("{time} s at {fps} frames per second comes before frame 0")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_number_frames_and_refuse_other_braces() {
        let p = |s: &str| FramePattern::parse(s).unwrap().unwrap();
        assert_eq!(p("smoke_{frame:04}.vdb").at(7), "smoke_0007.vdb");
        assert_eq!(p("{frame}/d_{frame:02}.vol").at(123), "123/d_123.vol");
        assert_eq!(p("{frame:010}").at(u32::MAX), "4294967295");
        assert_eq!(FramePattern::parse("plain.vol").unwrap(), None);
        for bad in ["a{frame", "a}b", "{frame:4}", "{frame:00}", "{frame:011}", "{fram}", "{}", "{frame:0+4}"]
        {
            let e = FramePattern::parse(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("{frame:0N}"), "{bad}: {e}");
        }
    }

    #[test]
    fn a_moment_belongs_to_the_last_frame_opened() {
        for fps in [24.0, 30.0, 29.97, 7.0, 0.5] {
            for n in [0, 1, 17, 18, 100, 9999] {
                let t = frame_start(n, fps);
                assert_eq!(frame_at(t, fps), Ok(n), "{n} at {fps}");
                // Half a frame on, and just before the next frame.
                assert_eq!(frame_at(t + 0.5 / fps, fps), Ok(n));
                let next = frame_start(n + 1, fps);
                assert_eq!(frame_at(f32::from_bits(next.to_bits() - 1), fps), Ok(n));
            }
        }
        assert!(frame_at(-0.01, 24.0).is_err());
        assert_eq!(frame_at(-0.0, 24.0), Ok(0));
        assert!(frame_at(1e7, 1e6).is_err());
    }
}
