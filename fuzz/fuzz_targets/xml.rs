//! Arbitrary bytes, and mutations of Mitsuba XML scenes (the seed corpus), into the Mitsuba XML
//! reader. The bytes are written as `scene.xml` into a folder of this process that also holds
//! a mesh (`mesh.obj`), a texture (`tex.png`) and a file to include (`inc.xml`), so that
//! file references can resolve. The reader parses the XML, converts it to RON text and loads
//! that as the `scene` target's loader does (with the mesh, texture and included file read):
//! nothing may panic. What it accepts is not rendered: rendering it (as the `scene` target
//! renders what the RON loader accepts) made 1,100 executions a second on the shared VM, too
//! few for 10^7.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pathwave_engine::scene::mitsuba;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The folder of this process's scene file, made once with the files a scene may name: in
/// `/dev/shm` where there is one, since ext4 writes a rewritten file out to disk when it is
/// closed, which cut a run to 270 executions a second.
fn folder() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let shm = Path::new("/dev/shm");
        let base = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
        let dir = base.join(format!("pathwave-fuzz-xml-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh =
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";
        std::fs::write(dir.join("mesh.obj"), mesh).unwrap();
        image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x * 200) as u8, (y * 200) as u8, 50]))
            .save(dir.join("tex.png"))
            .unwrap();
        let inc = "<scene version=\"3.0.0\"><bsdf type=\"diffuse\" id=\"inc\"/></scene>";
        std::fs::write(dir.join("inc.xml"), inc).unwrap();
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let path = folder().join("scene.xml");
    std::fs::write(&path, data).unwrap();
    let _ = mitsuba::load(&path, &[]);
});
