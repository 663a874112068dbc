//! Looking at a render while it runs: progressive passes (1, 2, 4, ... samples per pixel) shown
//! after each pass in a window (`--preview`, [`preview`]) or in the tev image viewer
//! (`--tev HOST:PORT`, [`tev`]).
//!
//! The film keeps exact sums, so a render done in passes has the bits of a render done at once:
//! passes change when the image can be seen, never what it is.

use crate::engine::render_scene::RenderSettings;
use crate::integrator::film::Film;
use crate::look::Look;
use std::time::Duration;

pub mod preview;
pub mod tev;

/// Where to show a render while it runs.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct ViewArgs {
    /// Render in passes (1, 2, 4, ... spp) and show the image after each in a window; Esc or
    /// closing the window stops the render and keeps what it has.
    #[arg(long)]
    pub preview: bool,
    /// Render in passes and stream the image after each to the tev image viewer listening on
    /// HOST:PORT (tev's default is 127.0.0.1:14158).
    #[arg(long, value_name = "HOST:PORT")]
    pub tev: Option<String>,
}

/// Where a render stands after a pass.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    /// Passes done (1 after the first).
    pub number: u32,
    /// Samples per pixel in the film.
    pub spp: u32,
    /// Samples per pixel the render is for.
    pub target: u32,
    /// Time left at the rate so far.
    pub eta: Duration,
}

impl Pass {
    /// `pass 3, 4/64 spp, ETA 12 s`: what a window's title says.
    pub fn describe(&self) -> String {
        let eta = self.eta.as_secs_f64();
        let eta = match eta {
            _ if self.spp >= self.target => "done".to_string(),
            e if e < 60.0 => format!("ETA {e:.0} s"),
            e if e < 3600.0 => format!("ETA {}:{:02}", (e / 60.0) as u64, e as u64 % 60),
            e => format!("ETA {}:{:02}:{:02}", (e / 3600.0) as u64, (e / 60.0) as u64 % 60, e as u64 % 60),
        };
        format!("pass {}, {}/{} spp, {eta}", self.number, self.spp, self.target)
    }
}

/// One place a render is shown.
pub trait Viewer {
    /// Shows the film after a pass; false when the viewer asks the render to stop (its window
    /// was closed).
    fn show(&mut self, film: &Film, pass: &Pass) -> bool;
    /// Says something that is not an image (a scene's error in watch mode); a window shows it
    /// in its title.
    fn note(&mut self, _text: &str) {}
    /// Whether the viewer was closed (its window).
    fn closed(&self) -> bool {
        false
    }
}

/// The viewers of a render: none (one pass), or a window and/or tev (passes).
#[derive(Default)]
pub struct Viewers {
    list: Vec<Box<dyn Viewer>>,
    progressive: bool,
}

impl Viewers {
    /// Opens what `args` asks for, for the image of `s` (the window shows its crop window, tev
    /// the whole image with the crop window filled in) called `name`. A viewer that cannot
    /// start says why on stderr and the render goes on without it (still in passes).
    pub fn open(args: &ViewArgs, name: &str, s: &RenderSettings, look: Look) -> Self {
        let mut list: Vec<Box<dyn Viewer>> = Vec::new();
        if args.preview {
            match preview::Preview::open(name, s.window.w, s.window.h, look) {
                Ok(p) => list.push(Box::new(p)),
                Err(e) => eprintln!("--preview: {e}; rendering without a window"),
            }
        }
        if let Some(addr) = &args.tev {
            list.push(Box::new(tev::Tev::connect(
                addr,
                name,
                (s.width, s.height),
                (s.window.x0, s.window.y0),
            )));
        }
        Self { list, progressive: args.preview || args.tev.is_some() }
    }

    /// Whether the render goes in passes.
    pub fn progressive(&self) -> bool {
        self.progressive
    }

    /// Shows the film to every viewer; false when one asks the render to stop.
    pub fn show(&mut self, film: &Film, pass: &Pass) -> bool {
        let mut go_on = true;
        for v in &mut self.list {
            go_on &= v.show(film, pass);
        }
        go_on
    }

    /// Whether a viewer was closed.
    pub fn closed(&self) -> bool {
        self.list.iter().any(|v| v.closed())
    }

    /// Says `text` to every viewer.
    pub fn note(&mut self, text: &str) {
        self.list.iter_mut().for_each(|v| v.note(text));
    }
}

/// The longest a progressive pass should take after the first ones: the image is shown (and a
/// stop is noticed) at least this often.
pub const MAX_PASS: Duration = Duration::from_secs(10);

/// Samples in the next progressive pass of a film holding `done` samples per pixel: as many
/// again (1, 2, 4, ... in all), fewer if at `secs_per_sample` the pass would take longer than
/// `max_pass`, and never past `left`.
pub fn next_pass(done: u32, left: u32, secs_per_sample: f64, max_pass: Duration) -> u32 {
    let fit = (max_pass.as_secs_f64() / secs_per_sample.max(1e-9)).max(1.0);
    (done.max(1) as f64).min(fit).min(left as f64).max(1.0) as u32
}

/// 0RGB pixels (as minifb and most frame buffers take them) through `look`, as a PNG output.
pub fn srgb_0rgb(film: &Film, look: &Look) -> Vec<u32> {
    let (rgb, _) = look.srgb8(&film.mean());
    rgb.chunks_exact(3).map(|c| u32::from_be_bytes([0, c[0], c[1], c[2]])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_double_within_the_time_and_the_samples_left() {
        let long = Duration::from_secs(1000);
        let mut done = 0;
        let mut sizes = Vec::new();
        while done < 20 {
            let k = next_pass(done, 20 - done, 0.1, long);
            sizes.push(k);
            done += k;
        }
        assert_eq!(sizes, [1, 1, 2, 4, 8, 4]);
        // 0.5 s a sample, passes of at most 2 s: 4 samples.
        assert_eq!(next_pass(64, 1000, 0.5, Duration::from_secs(2)), 4);
        // Slower than a pass may take: still one sample.
        assert_eq!(next_pass(64, 1000, 30.0, Duration::from_secs(2)), 1);
    }

    #[test]
    fn a_title_says_pass_samples_and_time_left() {
        let p = Pass { number: 3, spp: 4, target: 64, eta: Duration::from_secs(75) };
        assert_eq!(p.describe(), "pass 3, 4/64 spp, ETA 1:15");
        let done = Pass { spp: 64, ..p };
        assert_eq!(done.describe(), "pass 3, 64/64 spp, done");
    }
}
