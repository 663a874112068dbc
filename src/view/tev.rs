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
use std::time::Duration;

/// `CreateImage`'s type byte.
pub const CREATE_IMAGE: u8 = 4;
/// `UpdateImageV3`'s type byte.
pub const UPDATE_IMAGE_V3: u8 = 6;
/// Floats per packet, about (whole rows are sent).
const BAND_FLOATS: usize = 1 << 18;
/// How long a send may block before tev counts as gone.
const SEND_TIMEOUT: Duration = Duration::from_secs(10);

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

/// A connection to tev.
pub struct Tev {
    addr: String,
    name: String,
    /// The whole image's size and where the film lies in it.
    image: (u32, u32),
    at: (u32, u32),
    stream: Option<TcpStream>,
    /// The channels tev's image was created with.
    created: Option<Vec<&'static str>>,
}

impl Tev {
    /// Connects to tev at `addr` (HOST:PORT) to show an image called `name` of `image` pixels
    /// (width, height), of which the film holds the rectangle at `at`. When tev cannot be
    /// reached, says so once; the render goes on without it.
    pub fn connect(addr: &str, name: &str, image: (u32, u32), at: (u32, u32)) -> Self {
        let stream = Self::open(addr);
        if let Err(e) = &stream {
            eprintln!("--tev {addr}: {e}; rendering without tev");
        }
        Self { addr: addr.to_string(), name: name.to_string(), image, at, stream: stream.ok(), created: None }
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
                    s.set_write_timeout(Some(SEND_TIMEOUT)).map_err(|e| e.to_string())?;
                    s.set_nodelay(true).map_err(|e| e.to_string())?;
                    return Ok(s);
                }
                Err(e) => last = format!("cannot connect to {a} ({e}; is tev running?)"),
            }
        }
        Err(last)
    }

    /// The packets that show `film`: the image created first (again when its channels
    /// changed), then the film's rectangle in bands of rows.
    fn packets(&mut self, film: &Film) -> Vec<Vec<u8>> {
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
            self.created = Some(names.clone());
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
        out
    }
}

impl Viewer for Tev {
    fn show(&mut self, film: &Film, _pass: &Pass) -> bool {
        if self.stream.is_none() {
            return true;
        }
        let packets = self.packets(film);
        let sent = self.stream.as_mut().map(|s| packets.iter().try_for_each(|p| s.write_all(p)));
        if let Some(Err(e)) = sent {
            eprintln!("--tev {}: the connection was lost ({e}); rendering on without tev", self.addr);
            self.stream = None;
        }
        true
    }
}
