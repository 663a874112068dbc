//! A fake tev image viewer: parses tev's IPC packets (tev's `include/tev/Ipc.h`,
//! <https://github.com/Tom94/tev>) as tev does.

use std::io::Read;
use std::net::TcpListener;
use std::sync::{Arc, Mutex};

/// A packet as tev reads it.
#[derive(Debug)]
pub enum Packet {
    /// CreateImage.
    Create { name: String, width: i32, height: i32, channels: Vec<String> },
    /// UpdateImageV3.
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

pub fn parse(bytes: &[u8]) -> Packet {
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

/// The packets a fake tev received so far.
pub type Received = Arc<Mutex<Vec<Packet>>>;

/// A fake tev on the loopback address: accepts one connection and gathers its packets until
/// it closes, or closes it after `keep` packets. Returns its address, the packets as they come
/// and the thread, which ends with them.
pub fn fake_tev(keep: Option<usize>) -> (String, Received, std::thread::JoinHandle<Received>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let (tx, rx) = std::sync::mpsc::channel();
    let server = std::thread::spawn(move || {
        let packets = Received::default();
        tx.send(packets.clone()).unwrap();
        let (mut s, _) = listener.accept().unwrap();
        loop {
            if keep == Some(packets.lock().unwrap().len()) {
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
            packets.lock().unwrap().push(parse(&body));
        }
    });
    let received = rx.recv().unwrap();
    (addr, received, server)
}
