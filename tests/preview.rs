//! `--preview`: progressive passes give the bits of one render; without a display, or with one
//! that never answers, the render goes on; under Xvfb the window shows the passes with the PNG
//! output's tone mapping. The tests under Xvfb need Xvfb, xwd and xdotool, the silent display
//! libX11, so they are ignored unless asked for (`cargo test --release --test preview --
//! --ignored`, as `.ci/run` does); asked for where they cannot run, they fail saying what is
//! missing.

mod common;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-preview-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn pathwave(out: &Path, size: u32, spp: u32, extra: &[&str]) -> Command {
    common::render_cornell(out, (size, size), spp, extra)
}

#[test]
fn progressive_passes_without_a_display_give_the_bits_of_one_render() {
    let dir = temp("passes");
    let (plain, shown) = (dir.join("plain.exr"), dir.join("shown.exr"));
    assert!(pathwave(&plain, 48, 24, &["-q"]).status().unwrap().success());
    let run = pathwave(&shown, 48, 24, &["--preview"]).env_remove("DISPLAY").output().unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert!(log.contains("--preview: no display (DISPLAY is not set); rendering without a window"), "{log}");
    // 1, 2, 4, ... samples per pixel in all.
    for pass in ["0..1 ", "1..2 ", "2..4 ", "4..8 ", "8..16 ", "16..24 "] {
        assert!(log.contains(&format!("pass: samples {pass}of 24")), "no pass {pass}: {log}");
    }
    assert_eq!(
        std::fs::read(&shown).unwrap(),
        std::fs::read(&plain).unwrap(),
        "the passes changed the image"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A display that takes the connection and never answers (a stalled X server, a forwarded
/// display whose far end hangs) holds `XOpenDisplay` for ever: the render waits for it a few
/// seconds, then goes on without the window. Needs libX11 (installed with Xvfb).
#[test]
#[ignore = "needs libX11 (installed with Xvfb): cargo test --release --test preview -- --ignored"]
fn a_display_that_never_answers_does_not_hold_up_the_render() {
    let dir = temp("silent");
    // An X display over TCP is port 6000 + its number.
    let (listener, n) = (100..400)
        .find_map(|n| std::net::TcpListener::bind(("127.0.0.1", 6000 + n)).ok().map(|l| (l, n)))
        .expect("a free port for a display");
    std::thread::spawn(move || {
        let mut held = Vec::new();
        for c in listener.incoming().flatten() {
            held.push(c);
        }
    });
    let start = Instant::now();
    let run = pathwave(&dir.join("a.png"), 16, 2, &["--preview"])
        .env("DISPLAY", format!("127.0.0.1:{n}"))
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert!(log.contains(&format!("the display \"127.0.0.1:{n}\" did not answer within 10 s")), "{log}");
    assert!(log.contains("rendering without a window"), "{log}");
    assert!(start.elapsed() < Duration::from_secs(60), "{:?}", start.elapsed());
    assert!(dir.join("a.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An X server of a test's own (Xvfb, black root, 320x240), killed when dropped, with the lock
/// that keeps the tests' servers one at a time: two started at once were seen to hand out a
/// display on which one client connected (xwd) and the next did not (XOpenDisplay failed).
/// `-noreset`: by default an X server resets when its last client leaves, and a client that
/// connects during the reset is refused; here every xwd and xdotool is such a last client, and
/// CI saw the window refused right after a screenshot.
struct Xvfb(
    Child,
    String,
    #[expect(dead_code, reason = "held, not read: it keeps the lock until the server is dropped")]
    std::sync::MutexGuard<'static, ()>,
);

static ONE_SERVER: std::sync::Mutex<()> = std::sync::Mutex::new(());

impl Xvfb {
    /// None (and why) when there is no Xvfb to start.
    fn start() -> Result<Self, String> {
        let lock = ONE_SERVER.lock().unwrap_or_else(|e| e.into_inner());
        // -displayfd: Xvfb picks a free display and writes its number once it accepts clients.
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "320x240x24", "-br", "-nolisten", "tcp", "-noreset"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("Xvfb: {e}"))?;
        let mut number = String::new();
        let mut out = child.stdout.take().unwrap();
        let mut byte = [0u8];
        while out.read(&mut byte).map_err(|e| e.to_string())? == 1 && byte[0] != b'\n' {
            number.push(byte[0] as char);
        }
        let mut xvfb = Xvfb(child, String::new(), lock);
        let n =
            number.trim().parse::<u32>().map_err(|_| format!("Xvfb did not say its display ({number:?})"))?;
        xvfb.1 = format!(":{n}");
        // Clients are let in once a screenshot works (a window opened before that was seen
        // to fail with XOpenDisplay on a loaded machine).
        let start = Instant::now();
        while screenshot(&xvfb.1).is_none() {
            if start.elapsed() > Duration::from_secs(20) {
                return Err(format!("Xvfb on {} took no client for 20 s", xvfb.1));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        Ok(xvfb)
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The screen as 0xRRGGBB, from `xwd -root` (the X Window Dump format: a big-endian header of
/// 25 words, the window name, a colour map, then the pixels).
fn screenshot(display: &str) -> Option<(usize, usize, Vec<u32>)> {
    let out = Command::new("xwd").args(["-root", "-silent", "-display", display]).output().ok()?;
    let d = out.stdout;
    let word = |i: usize| u32::from_be_bytes(d[4 * i..4 * i + 4].try_into().unwrap());
    if !out.status.success() || d.len() < 100 {
        return None;
    }
    let (header, width, height) = (word(0) as usize, word(4) as usize, word(5) as usize);
    let (lsb_first, bits, line) = (word(7) == 0, word(11), word(12) as usize);
    let (colours, masks) = (word(19) as usize, [word(14), word(15), word(16)]);
    assert_eq!((bits, masks), (32, [0xff0000, 0xff00, 0xff]), "a 24-bit TrueColor screen");
    let start = header + 12 * colours;
    let mut px = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let b: [u8; 4] =
                d.get(start + y * line + 4 * x..start + y * line + 4 * x + 4)?.try_into().ok()?;
            let v = if lsb_first { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) };
            px.push(v & 0xff_ffff);
        }
    }
    Some((width, height, px))
}

/// Whether `image` (0xRRGGBB, `w` wide) appears somewhere on the screen.
fn on_screen(screen: &(usize, usize, Vec<u32>), image: &[u32], w: usize) -> bool {
    let (sw, sh, px) = screen;
    let h = image.len() / w;
    (0..=sh.saturating_sub(h)).any(|y0| {
        (0..=sw.saturating_sub(w)).any(|x0| {
            (0..h).all(|y| px[(y0 + y) * sw + x0..(y0 + y) * sw + x0 + w] == image[y * w..(y + 1) * w])
        })
    })
}

#[test]
#[ignore = "needs Xvfb and xwd: cargo test --release --test preview -- --ignored"]
fn the_window_shows_the_passes_under_xvfb() {
    let xvfb = Xvfb::start().unwrap_or_else(|e| {
        panic!("cannot run: no X server to show the window on ({e}); install Xvfb and xwd (xvfb, x11-apps)")
    });
    let dir = temp("xvfb");
    let shown = dir.join("shown.png");
    let (size, spp) = (64, 512);
    let mut child = pathwave(&shown, size, spp, &["--preview", "-q"])
        .env("DISPLAY", &xvfb.1)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let mut shots = Vec::new();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(120), "the render did not end");
        match screenshot(&xvfb.1) {
            Some(s) => shots.push(s),
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    }
    let mut log = String::new();
    child.stderr.take().unwrap().read_to_string(&mut log).unwrap();
    assert!(child.wait().unwrap().success(), "{log}");
    assert!(!log.contains("--preview:"), "no window: {log}");
    assert!(!shots.is_empty(), "no screenshot while the render ran");
    // What a pass of k samples shows is the PNG of a k-spp render (Sobol samples do not depend
    // on the count): some screenshot holds one of them, pixel for pixel.
    let mut k = spp;
    let mut seen = None;
    while k >= 1 && seen.is_none() {
        let png = dir.join(format!("plain-{k}.png"));
        assert!(pathwave(&png, size, k, &["-q"]).status().unwrap().success());
        let rgb = image::open(&png).unwrap().to_rgb8();
        let img: Vec<u32> = rgb.pixels().map(|p| u32::from_be_bytes([0, p[0], p[1], p[2]])).collect();
        if shots.iter().any(|s| on_screen(s, &img, size as usize)) {
            seen = Some(k);
        }
        k /= 2;
    }
    assert!(seen.is_some(), "none of {} screenshots shows a pass of the render", shots.len());
    println!("a screenshot shows the pass of {} spp", seen.unwrap());
    // The window changes nothing: the file is the plain render's.
    let plain = dir.join(format!("plain-{spp}.png"));
    if !plain.exists() {
        assert!(pathwave(&plain, size, spp, &["-q"]).status().unwrap().success());
    }
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
#[ignore = "needs Xvfb, xwd and xdotool: cargo test --release --test preview -- --ignored"]
fn esc_stops_the_render_and_keeps_what_it_has() {
    let xvfb = Xvfb::start().unwrap_or_else(|e| {
        panic!("cannot run: no X server to show the window on ({e}); install Xvfb (xvfb)")
    });
    assert!(
        Command::new("xdotool").arg("version").output().is_ok(),
        "cannot run: no xdotool to press Esc with; install it (xdotool)"
    );
    let dir = temp("esc");
    let shown = dir.join("shown.png");
    let spp = 4096;
    let mut child = pathwave(&shown, 64, spp, &["--preview", "--checkpoint-every", "1000"])
        .env("DISPLAY", &xvfb.1)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let xdotool =
        |args: &[&str]| Command::new("xdotool").args(args).env("DISPLAY", &xvfb.1).output().unwrap();
    let stderr = child.stderr.take().unwrap();
    let log = std::thread::spawn(move || std::io::read_to_string(stderr).unwrap());
    // Esc over the window (the keyboard goes where the pointer is) until the render ends.
    let start = Instant::now();
    let mut pressed = 0;
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(120), "the render did not end");
        let found = xdotool(&["search", "--name", "shown.png"]);
        if let Some(id) = String::from_utf8_lossy(&found.stdout).split_whitespace().next() {
            xdotool(&["mousemove", "--window", id, "10", "10"]);
            xdotool(&["key", "Escape"]);
            pressed += 1;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let log = log.join().unwrap();
    assert!(child.wait().unwrap().success(), "{log}");
    println!("Esc pressed {pressed} times");
    let stopped = log.lines().find_map(|l| l.strip_prefix("stopped at ")).unwrap_or_else(|| panic!("{log}"));
    let k: u32 = stopped.split_whitespace().next().unwrap().parse().unwrap();
    assert!(k < spp, "{log}");
    // What it has: the image of the first k samples (a k-spp render's), and their checkpoint.
    let ckpt = pathwave::checkpoint::Checkpoint::load(&dir.join("shown.png.ckpt")).unwrap();
    assert_eq!(ckpt.film.spp, k);
    let plain = dir.join("plain.png");
    assert!(pathwave(&plain, 64, k, &["-q"]).status().unwrap().success());
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}
