//! `--preview`: a window that shows the render after each pass, with the PNG output's tone
//! mapping, and its pass, samples and time left in the title. Closing it or pressing Esc stops
//! the render, which keeps what it has.
//!
//! The window is `minifb`'s (X11, whose libraries it loads when the window opens), run on a
//! thread of its own so that it redraws and answers the window system while a pass renders.

use super::{Pass, Viewer, srgb_0rgb};
use crate::integrator::film::Film;
use crate::look::Look;
use minifb::{Key, ScaleMode, Window, WindowOptions};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

/// Event polls per second: often enough to see a short tap of Esc (minifb keeps only whether
/// a key is down when it polls).
const FPS: usize = 60;
/// The image is drawn again (over whatever covered it) at least this often.
const REDRAW: std::time::Duration = std::time::Duration::from_millis(250);
/// How long the display has to let the window open: an X server answers in milliseconds, and
/// one that took the connection and never answers would hold `XOpenDisplay` for ever.
const OPEN_WAIT: std::time::Duration = std::time::Duration::from_secs(10);

/// What the render sends the window.
enum Message {
    /// A new image (0RGB pixels) and title.
    Image(Vec<u32>, String),
    /// A new title only.
    Title(String),
}

/// An open preview window.
pub struct Preview {
    name: String,
    /// How the image is shown (as the PNG output).
    look: Look,
    to_window: Option<mpsc::Sender<Message>>,
    /// False once the window was closed or Esc pressed.
    open: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Preview {
    /// Opens a `width` x `height` window titled after `name`, black until the first pass; an
    /// error says why there is none (no display, no X11 libraries).
    pub fn open(name: &str, width: u32, height: u32, look: Look) -> Result<Self, String> {
        if std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
            return Err("no display (DISPLAY is not set)".into());
        }
        let (w, h) = (width as usize, height as usize);
        let (to_window, messages) = mpsc::channel();
        let (ready, started) = mpsc::channel();
        let open = Arc::new(AtomicBool::new(true));
        let still_open = open.clone();
        let title = format!("{name} - pathwave");
        let thread = std::thread::Builder::new()
            .name("preview".into())
            .spawn(move || {
                let opts = WindowOptions {
                    resize: true,
                    scale_mode: ScaleMode::AspectRatioStretch,
                    ..Default::default()
                };
                let mut window = match Window::new(&title, w, h, opts) {
                    Ok(window) => window,
                    Err(e) => {
                        let _ = ready.send(Err(e.to_string()));
                        return;
                    }
                };
                let _ = ready.send(Ok(()));
                window.set_target_fps(FPS);
                let mut pixels = vec![0u32; w * h];
                let mut drawn: Option<std::time::Instant> = None;
                loop {
                    // The latest image; the render is over when the sender is gone.
                    loop {
                        match messages.try_recv() {
                            Ok(Message::Image(p, t)) => {
                                pixels = p;
                                window.set_title(&t);
                                drawn = None;
                            }
                            Ok(Message::Title(t)) => window.set_title(&t),
                            Err(mpsc::TryRecvError::Empty) => break,
                            Err(mpsc::TryRecvError::Disconnected) => return,
                        }
                    }
                    let shown = match drawn.is_some_and(|d| d.elapsed() < REDRAW) {
                        true => {
                            window.update();
                            true
                        }
                        false => {
                            drawn = Some(std::time::Instant::now());
                            window.update_with_buffer(&pixels, w, h).is_ok()
                        }
                    };
                    if !shown || !window.is_open() || window.is_key_down(Key::Escape) {
                        still_open.store(false, Ordering::Relaxed);
                        return;
                    }
                }
            })
            .map_err(|e| format!("cannot start the window's thread: {e}"))?;
        match started.recv_timeout(OPEN_WAIT) {
            Ok(Ok(())) => Ok(Self {
                name: name.to_string(),
                look,
                to_window: Some(to_window),
                open,
                thread: Some(thread),
            }),
            Ok(Err(e)) => {
                let _ = thread.join();
                Err(format!(
                    "cannot open a window on display {:?} ({e})",
                    std::env::var("DISPLAY").unwrap_or_default()
                ))
            }
            // Left blocked in XOpenDisplay: the thread is not joined (it ends, or the process
            // does); were the display to answer later, the window would close at once, its
            // sender gone.
            Err(mpsc::RecvTimeoutError::Timeout) => Err(format!(
                "the display {:?} did not answer within {} s",
                std::env::var("DISPLAY").unwrap_or_default(),
                OPEN_WAIT.as_secs()
            )),
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let _ = thread.join();
                Err("the window's thread ended before opening it".into())
            }
        }
    }

    fn send(&self, m: Message) {
        if let Some(tx) = &self.to_window {
            // A window closed since is noticed through `open`.
            let _ = tx.send(m);
        }
    }
}

impl Viewer for Preview {
    fn show(&mut self, film: &Film, pass: &Pass) -> bool {
        self.send(Message::Image(
            srgb_0rgb(film, &self.look),
            format!("{} - {}", self.name, pass.describe()),
        ));
        !self.closed()
    }

    fn note(&mut self, text: &str) {
        self.send(Message::Title(format!("{} - {text}", self.name)));
    }

    fn closed(&self) -> bool {
        !self.open.load(Ordering::Relaxed)
    }
}

impl Drop for Preview {
    /// Closes the window.
    fn drop(&mut self) {
        self.to_window = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
