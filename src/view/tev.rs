//! `--tev HOST:PORT`: streams the render to the tev image viewer over its TCP protocol, as
//! pbrt-v4's `--display-server` does.
//!
//! The protocol is tev's IPC (tev's `include/tev/Ipc.h` and `src/Ipc.cpp`,
//! <https://github.com/Tom94/tev>): each packet is its length in bytes (`u32`, counting
//! itself), a type byte, then fields, little-endian: a bool is one byte, a string its bytes and
//! a NUL, integers and floats as they are, lists one item after the other. pathwave sends
//! `CreateImage` (type 4: grab focus, name, width, height, channel count, channel names) once,
//! then after each pass `UpdateImageV3` (type 6: grab focus, name, channel count, names, the
//! rectangle x, y, width, height, per channel an `i64` offset and stride into the floats, the
//! floats) over the rendered rectangle, in bands of rows that keep packets near a mebibyte
//! (tev's receive buffer).

use super::{Pass, Viewer};
use crate::integrator::film::Film;
use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::mpsc::{SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use std::time::Duration;

/// `CreateImage`'s type byte.
pub const CREATE_IMAGE: u8 = 4;
/// `UpdateImageV3`'s type byte.
pub const UPDATE_IMAGE_V3: u8 = 6;
/// Floats per packet, about (whole rows are sent).
const BAND_FLOATS: usize = 1 << 18;
/// How long one packet may take before tev counts as gone (a packet is about a mebibyte, which
/// a tev that reads takes in milliseconds). A socket's own write timeout does not bound it: a
/// write that times out after sending part returns that part, and the next one waits again.
const SEND_TIMEOUT: Duration = Duration::from_secs(3);
/// The socket's write timeout: how often a stalled write gets to check [`SEND_TIMEOUT`].
const WRITE_TIMEOUT: Duration = Duration::from_secs(1);

/// Writes one packet within [`SEND_TIMEOUT`].
fn send(stream: &mut TcpStream, packet: &[u8]) -> std::io::Result<()> {
    let start = std::time::Instant::now();
    let mut rest = packet;
    while !rest.is_empty() {
        if start.elapsed() > SEND_TIMEOUT {
            let e = format!("tev took no packet for {} s", SEND_TIMEOUT.as_secs());
            return Err(std::io::Error::new(std::io::ErrorKind::TimedOut, e));
        }
        match stream.write(rest) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(n) => rest = &rest[n..],
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::Interrupted
                        | std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Images queued for the sending thread: a tev that reads gets every pass (they come no faster
/// than their samples double), and memory stays bounded when it does not.
const QUEUED: usize = 4;

/// A packet being written.
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Self {
        let mut p = Packet(vec![0; 4]);
        p.0.push(kind);
        p
    }
    fn bool(&mut self, b: bool) -> &mut Self {
        self.0.push(b as u8);
        self
    }
    fn str(&mut self, s: &str) -> &mut Self {
        // tev reads up to the NUL: a name cannot hold one.
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
        self
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn i64(&mut self, v: i64) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f32s(&mut self, v: &[f32]) -> &mut Self {
        self.0.extend(v.iter().flat_map(|f| f.to_le_bytes()));
        self
    }
    /// The bytes, length first.
    fn finish(&mut self) -> &[u8] {
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        &self.0
    }
}

/// The channels sent: the image, and the denoiser's guides when the render records them.
fn channels(film: &Film) -> Vec<(&'static str, Vec<f32>)> {
    let mean = film.mean();
    let plane = |v: &[glam::Vec3], k: usize| v.iter().map(|p| p[k]).collect::<Vec<f32>>();
    let mut out = vec![("R", plane(&mean, 0)), ("G", plane(&mean, 1)), ("B", plane(&mean, 2))];
    if let Some(g) = &film.guides {
        for (k, name) in ["albedo.R", "albedo.G", "albedo.B"].into_iter().enumerate() {
            out.push((name, plane(&g.albedo, k)));
        }
        for (k, name) in ["normal.X", "normal.Y", "normal.Z"].into_iter().enumerate() {
            out.push((name, plane(&g.normal, k)));
        }
    }
    out
}

/// A connection to tev. Its packets are written by a thread of their own, so that a tev that
/// reads slowly, or not at all, never holds up the render: up to [`QUEUED`] passes' images
/// queue for it, beyond that the newest waits here (replacing an older one that waited), and
/// the last image is handed over when the viewer is dropped (the thread gives up on a tev that
/// takes nothing for [`SEND_TIMEOUT`]).
pub struct Tev {
    addr: String,
    name: String,
    /// The whole image's size and where the film lies in it.
    image: (u32, u32),
    at: (u32, u32),
    link: Option<Link>,
    /// The channels of the image last handed to the thread (it creates tev's image first).
    created: Option<Vec<&'static str>>,
    /// The newest image not yet handed over, and its channels.
    waiting: Option<(Vec<Vec<u8>>, Vec<&'static str>)>,
}

/// The sending thread and the way to it (one image's packets at a time).
struct Link {
    tx: SyncSender<Vec<Vec<u8>>>,
    thread: JoinHandle<()>,
}

impl Link {
    fn new(mut stream: TcpStream, addr: &str) -> std::io::Result<Self> {
        let (tx, rx) = sync_channel::<Vec<Vec<u8>>>(QUEUED);
        let addr = addr.to_string();
        let thread = std::thread::Builder::new().name("tev".into()).spawn(move || {
            for packets in rx {
                if let Err(e) = packets.iter().try_for_each(|p| send(&mut stream, p)) {
                    eprintln!("--tev {addr}: the connection was lost ({e}); rendering on without tev");
                    return;
                }
            }
        })?;
        Ok(Self { tx, thread })
    }
}

impl Tev {
    /// Connects to tev at `addr` (HOST:PORT) to show an image called `name` of `image` pixels
    /// (width, height), of which the film holds the rectangle at `at`. When tev cannot be
    /// reached, says so once; the render goes on without it.
    pub fn connect(addr: &str, name: &str, image: (u32, u32), at: (u32, u32)) -> Self {
        let link = Self::open(addr).and_then(|s| Link::new(s, addr).map_err(|e| e.to_string()));
        if let Err(e) = &link {
            eprintln!("--tev {addr}: {e}; rendering without tev");
        }
        let (addr, name) = (addr.to_string(), name.to_string());
        Self { addr, name, image, at, link: link.ok(), created: None, waiting: None }
    }

    fn open(addr: &str) -> Result<TcpStream, String> {
        let addrs: Vec<_> = addr
            .to_socket_addrs()
            .map_err(|e| format!("not a HOST:PORT address tev listens on ({e})"))?
            .collect();
        let mut last = "no address".to_string();
        for a in addrs {
            match TcpStream::connect_timeout(&a, Duration::from_secs(5)) {
                Ok(s) => {
                    s.set_write_timeout(Some(WRITE_TIMEOUT)).map_err(|e| e.to_string())?;
                    s.set_nodelay(true).map_err(|e| e.to_string())?;
                    return Ok(s);
                }
                Err(e) => last = format!("cannot connect to {a} ({e}; is tev running?)"),
            }
        }
        Err(last)
    }

    /// The packets that show `film`: the image created first (again when its channels
    /// changed since the last image handed over), then the film's rectangle in bands of rows;
    /// and the channels.
    fn packets(&self, film: &Film) -> (Vec<Vec<u8>>, Vec<&'static str>) {
        let chans = channels(film);
        let names: Vec<&'static str> = chans.iter().map(|(n, _)| *n).collect();
        let mut out = Vec::new();
        if self.created.as_ref() != Some(&names) {
            let mut p = Packet::new(CREATE_IMAGE);
            p.bool(true).str(&self.name).i32(self.image.0 as i32).i32(self.image.1 as i32);
            p.i32(names.len() as i32);
            for n in &names {
                p.str(n);
            }
            out.push(p.finish().to_vec());
        }
        let w = film.width as usize;
        let rows = (BAND_FLOATS / (w * chans.len()).max(1)).max(1);
        for y0 in (0..film.height as usize).step_by(rows) {
            let h = rows.min(film.height as usize - y0);
            let mut p = Packet::new(UPDATE_IMAGE_V3);
            p.bool(false).str(&self.name).i32(chans.len() as i32);
            for n in &names {
                p.str(n);
            }
            p.i32(self.at.0 as i32).i32((self.at.1 as usize + y0) as i32).i32(w as i32).i32(h as i32);
            // Channel after channel, each contiguous.
            for c in 0..chans.len() {
                p.i64((c * w * h) as i64);
            }
            for _ in 0..chans.len() {
                p.i64(1);
            }
            for (_, plane) in &chans {
                p.f32s(&plane[y0 * w..(y0 + h) * w]);
            }
            out.push(p.finish().to_vec());
        }
        (out, names)
    }
}

impl Viewer for Tev {
    fn show(&mut self, film: &Film, _pass: &Pass) -> bool {
        let Some(link) = &self.link else { return true };
        let (packets, names) = self.packets(film);
        match link.tx.try_send(packets) {
            Ok(()) => (self.created, self.waiting) = (Some(names), None),
            // Still sending older images: this one waits, the newest.
            Err(TrySendError::Full(packets)) => self.waiting = Some((packets, names)),
            // The thread said why.
            Err(TrySendError::Disconnected(_)) => self.link = None,
        }
        true
    }
}

impl Drop for Tev {
    /// Hands over the last image and waits for the thread to send it or to give up on tev.
    fn drop(&mut self) {
        let Some(Link { tx, thread }) = self.link.take() else { return };
        if let Some((packets, _)) = self.waiting.take() {
            let _ = tx.send(packets);
        }
        drop(tx);
        if thread.join().is_err() {
            eprintln!("--tev {}: the sending thread panicked", self.addr);
        }
    }
}
