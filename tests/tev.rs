//! `--tev HOST:PORT` against a fake tev on the loopback address: the packets parse as tev's
//! IPC protocol, the last update holds the film's pixels, and a connection that closes is
//! reported once while the render goes on.

mod common;
use common::tev::{Packet, fake_tev};
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-tev-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn pathwave(out: &Path, spp: u32, extra: &[&str]) -> Command {
    common::render_cornell(out, (64, 48), spp, extra)
}

#[test]
fn tev_gets_every_pass_and_the_last_holds_the_film() {
    let dir = temp("passes");
    let (plain, shown) = (dir.join("plain.exr"), dir.join("shown.exr"));
    let crop = ["--crop", "0.25,0.75,0,0.5"];
    assert!(pathwave(&plain, 16, &crop).status().unwrap().success());
    let (addr, _, server) = fake_tev(None);
    let run = pathwave(&shown, 16, &crop).args(["--tev", &addr]).output().unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap(), "tev changed the image");
    let packets = server.join().unwrap();
    let packets = packets.lock().unwrap();
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
    let (addr, _, server) = fake_tev(None);
    let run =
        pathwave(&dir.join("out.exr"), 2, &["--aov", "albedo,normal", "--tev", &addr]).output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let packets = server.join().unwrap();
    let packets = packets.lock().unwrap();
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
    let (addr, _, server) = fake_tev(Some(2));
    let run = pathwave(&shown, 64, &["--tev", &addr]).output().unwrap();
    let log = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{log}");
    assert_eq!(log.matches("the connection was lost").count(), 1, "{log}");
    assert_eq!(server.join().unwrap().lock().unwrap().len(), 2);
    assert_eq!(std::fs::read(&shown).unwrap(), std::fs::read(&plain).unwrap());
    // No tev at all: said once, the render goes on.
    let refused = pathwave(&shown, 1, &["--tev", "127.0.0.1:1"]).output().unwrap();
    let log = String::from_utf8_lossy(&refused.stderr);
    assert!(refused.status.success(), "{log}");
    assert!(log.contains("--tev 127.0.0.1:1: cannot connect"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A tev that accepts and never reads holds up the render by at most one send timeout (3 s):
/// the packets are written by a thread of their own. Before, every pass waited for its writes
/// to time out (10 s each: a 0.1 s render took 31 s). The images (1024 x 1024, 12 MB each) are
/// larger than the loopback socket's buffers, so the writes do block.
#[test]
fn a_tev_that_never_reads_does_not_hold_up_the_render() {
    let dir = temp("stuck");
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let held = std::thread::spawn(move || {
        let (s, _) = listener.accept().unwrap();
        std::thread::sleep(std::time::Duration::from_secs(30));
        drop(s);
    });
    let render = |extra: &[&str]| {
        let start = std::time::Instant::now();
        let out = common::render_cornell(&dir.join("o.exr"), (1024, 1024), 2, extra).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (start.elapsed().as_secs_f64(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (plain, _) = render(&[]);
    let (shown, log) = render(&["--tev", &addr]);
    assert!(log.contains("the connection was lost"), "{log}");
    assert!(shown - plain < 7.0, "the render took {shown:.1} s with tev, {plain:.1} s without");
    drop(held);
    std::fs::remove_dir_all(&dir).unwrap();
}
