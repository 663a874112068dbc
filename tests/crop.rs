//! `--crop`: the window's pixels, with the bits they have in the whole image, for both
//! integrators and for the guides; windows that hold no pixel are refused.

mod common;

use common::root;
use pathwave::io::read_exr_channels;
use std::process::Command;

fn render(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pathwave"))
        .args(["render", "scenes/cornell.ron", "--width", "48", "--height", "40", "--spp", "4", "-q", "-o"])
        .arg(out)
        .args(extra)
        .current_dir(root())
        .output()
        .unwrap()
}

#[test]
fn a_crop_is_the_window_of_the_whole_image() {
    let dir = std::env::temp_dir().join(format!("pathwave-crop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The Gaussian's samples are splatted over two pixels around their own: the crop renders
    // those of the pixels around it that reach into it.
    let runs = [("wavefront", "box"), ("oracle", "box"), ("wavefront", "gaussian"), ("oracle", "tent")];
    for (integrator, filter) in runs {
        let (whole, part) = (dir.join("whole.exr"), dir.join("part.exr"));
        for (out, extra) in [(&whole, vec![]), (&part, vec!["--crop", "0.25,0.75,0.1,0.6"])] {
            let mut args = vec!["--integrator", integrator, "--aov", "--filter", filter];
            args.extend(extra);
            let o = render(out, &args);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        // pbrt-v4's rounding: columns ceil(0.25 * 48) = 12 .. ceil(0.75 * 48) = 36, rows
        // ceil(0.1 * 40) = 4 .. ceil(0.6 * 40) = 24.
        // Every channel, the AOV layers' too.
        let (w, p) = (read_exr_channels(&whole).unwrap(), read_exr_channels(&part).unwrap());
        assert_eq!((p.width, p.height), (24, 20), "{integrator}");
        assert!(
            w.channels.iter().any(|(n, _)| n == "albedo.R")
                && w.channels.iter().any(|(n, _)| n == "normal.X")
        );
        for ((name, a), (_, b)) in p.channels.iter().zip(&w.channels) {
            for y in 0..20 {
                for x in 0..24 {
                    let (a, b) = (a[(y * 24 + x) as usize], b[((y + 4) * 48 + x + 12) as usize]);
                    assert_eq!(a, b, "{integrator} {filter} {name}: pixel {x},{y} of the crop");
                }
            }
        }
    }
    for bad in ["0.5,0.5,0,1", "0,1.5,0,1", "0.999,1,0,1"] {
        let o = render(&dir.join("bad.png"), &["--crop", bad]);
        assert!(!o.status.success(), "--crop {bad} was accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("crop window"), "{bad}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
