//! `--tev HOST:PORT` against a fake tev on the loopback address: the packets parse as tev's
//! IPC protocol, the last update holds the film's pixels, and a connection that closes is
//! reported once while the render goes on.

mod common;
use common::root;
use std::io::Read;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-tev-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn pathwave(out: &Path, spp: u32, extra: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pathwave"));
    c.args(["render", "scenes/cornell.ron", "--width", "64", "--height", "48", "-o"])
        .arg(out)
        .arg("--spp")
        .arg(spp.to_string())
        .args(extra)
        .current_dir(root());
    c
}

/// A packet as tev reads it.
#[derive(Debug)]
enum Packet {
    Create { name: String, width: i32, height: i32, channels: Vec<String> },
    Update { name: String, channels: Vec<String>, rect: [i32; 4], planes: Vec<Vec<f32>> },
}

/// Reads tev's fields from a packet's bytes (after the length).
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        assert!(self.0.len() >= n, "the packet ends early");
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.0.iter().position(|&b| b == 0).expect("a NUL-terminated string");
        let s = String::from_utf8(self.take(end).to_vec()).unwrap();
        self.take(1);
        s
    }
}

fn parse(bytes: &[u8]) -> Packet {
    let mut f = Fields(bytes);
    let kind = f.u8();
    let grab = f.u8();
    assert!(grab <= 1, "a bool is 0 or 1");
    let name = f.string();
    match kind {
        4 => {
            let (width, height, n) = (f.i32(), f.i32(), f.i32());
            let channels = (0..n).map(|_| f.string()).collect();
            assert!(f.0.is_empty(), "bytes after CreateImage");
            Packet::Create { name, width, height, channels }
        }
        6 => {
            let n = f.i32() as usize;
            let channels: Vec<String> = (0..n).map(|_| f.string()).collect();
            let rect = [f.i32(), f.i32(), f.i32(), f.i32()];
            let offsets: Vec<i64> = (0..n).map(|_| f.i64()).collect();
            let strides: Vec<i64> = (0..n).map(|_| f.i64()).collect();
            let floats: Vec<f32> =
                f.0.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
            assert_eq!(f.0.len() % 4, 0);
            let pixels = (rect[2] * rect[3]) as i64;
            let needed = (0..n).map(|c| offsets[c] + (pixels - 1) * strides[c] + 1).max().unwrap();
            assert_eq!(floats.len() as i64, needed, "UpdateImage's data size");
            let planes = (0..n)
                .map(|c| (0..pixels).map(|i| floats[(offsets[c] + i * strides[c]) as usize]).collect())
                .collect();
            Packet::Update { name, channels, rect, planes }
        }
        k => panic!("packet type {k}: pathwave sends CreateImage (4) and UpdateImageV3 (6)"),
    }
}

/// A fake tev: accepts one connection and returns its packets, or closes it after `keep`.
fn fake_tev(keep: Option<usize>) -> (String, std::thread::JoinHandle<Vec<Packet>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut packets = Vec::new();
        loop {
            if keep == Some(packets.len()) {
                return packets;
            }
            let mut len = [0u8; 4];
            if s.read_exact(&mut len).is_err() {
                return packets;
            }
            let n = u32::from_le_bytes(len) as usize;
            assert!(n > 5, "a packet of {n} bytes");
            let mut body = vec![0u8; n - 4];
            s.read_exact(&mut body).unwrap();
            packets.push(parse(&body));
        }
    });
    (addr, server)
}

#[test]
fn tev_gets_every_pass_and_the_last_holds_the_film() {
    let dir = temp("passes");
    let (plain, shown) = (dir.join("plain.exr"), dir.join("shown.exr"));
    let crop = ["--crop", "0.25,0.75,0,0.5"];
    assert!(pathwave(&plain, 16, &crop).status().unwrap().success());
    let (addr, server) = fake_tev(None);
    let run = pathwave(&shown, 16, &crop).args(["--tev", &addr]).output().unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap(), "tev changed the image");
    let packets = server.join().unwrap();
    let Packet::Create { name, width, height, channels } = &packets[0] else {
        panic!("the first packet is not CreateImage: {:?}", packets[0])
    };
    assert_eq!((name.as_str(), *width, *height), (shown.to_str().unwrap(), 64, 48));
    assert_eq!(channels, &["R", "G", "B"]);
    // Passes of 1, 1, 2, 4 and 8 samples, each the crop window in one band.
    assert_eq!(packets.len(), 6, "{packets:?}");
    let film = pathwave::io::read_linear(&shown).unwrap();
    let Some(Packet::Update { name: n, channels: c, rect, planes }) = packets.last() else { panic!() };
    assert_eq!((n, c), (name, channels));
    assert_eq!(*rect, [16, 0, 32, 24], "the crop window's rectangle");
    assert_eq!((film.width, film.height), (32, 24));
    for (i, p) in film.pixels.iter().enumerate() {
        for k in 0..3 {
            assert_eq!(planes[k][i].to_bits(), p[k].to_bits(), "pixel {i} channel {k}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_denoiser_guides_go_to_tev_as_layers() {
    let dir = temp("aov");
    let (addr, server) = fake_tev(None);
    let run =
        pathwave(&dir.join("out.exr"), 2, &["--aov", "albedo,normal", "--tev", &addr]).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let packets = server.join().unwrap();
    let Packet::Create { channels, .. } = &packets[0] else { panic!("{:?}", packets[0]) };
    let want = ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z"];
    assert_eq!(channels, &want);
    assert!(matches!(&packets[1], Packet::Update { planes, .. } if planes.len() == 9));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_closed_connection_is_reported_once_and_the_render_goes_on() {
    let dir = temp("closed");
    let (plain, shown) = (dir.join("plain.exr"), dir.join("shown.exr"));
    assert!(pathwave(&plain, 64, &[]).status().unwrap().success());
    // tev goes away after the image is created and the first pass shown.
    let (addr, server) = fake_tev(Some(2));
    let run = pathwave(&shown, 64, &["--tev", &addr]).output().unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert_eq!(log.matches("the connection was lost").count(), 1, "{log}");
    assert_eq!(server.join().unwrap().len(), 2);
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap());
    // No tev at all: said once, the render goes on.
    let refused = pathwave(&shown, 1, &["--tev", "127.0.0.1:1"]).output().unwrap();
    let log = String::from_utf8_lossy(&refused.stderr);
    assert!(refused.status.success(), "{log}");
    assert!(log.contains("--tev 127.0.0.1:1: cannot connect"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}
