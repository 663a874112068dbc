//! `--exposure` and `--view-transform`: how 8-bit outputs show the image. They change the PNG
//! (which is the look applied to the EXR of the same render, byte for byte) and the JPEG, never
//! the EXR, and `agx` and `filmic` roll off what `standard` clips.

mod common;
use common::*;
use pathwave::look::{LookArgs, ViewTransform};

#[test]
fn looks_change_the_png_and_leave_the_exr_as_rendered() {
    let dir = std::env::temp_dir().join(format!("pathwave-looks-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let render = |name: &str, flags: &[&str]| {
        let out = dir.join(name);
        let o = render_cornell(&out, (24, 24), 4, flags).output().unwrap();
        let log = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{log}");
        (std::fs::read(&out).unwrap(), log)
    };
    let (plain, _) = render("plain.exr", &[]);
    let (looked, _) = render("looked.exr", &["--exposure", "-1.5", "--view-transform", "agx"]);
    assert_eq!(plain, looked, "the EXR changed with the look");

    let linear = pathwave::io::read_linear(&dir.join("plain.exr")).unwrap();
    for (view, name, ev) in [
        (ViewTransform::Standard, "standard", 0.0),
        (ViewTransform::Filmic, "filmic", 0.5),
        (ViewTransform::Agx, "agx", -1.5),
    ] {
        let (_, log) =
            render(&format!("{name}.png"), &["--view-transform", name, "--exposure", &ev.to_string()]);
        let png = image::open(dir.join(format!("{name}.png"))).unwrap().into_rgb8().into_raw();
        let (want, clipped) = LookArgs { exposure: ev, view_transform: view }.look().srgb8(&linear.pixels);
        assert_eq!(png, want, "{name}: the PNG is not the look of the render");
        // The light (and its reflections) clip under standard only.
        assert_eq!(
            log.contains("clamped to 1 in the 8-bit image"),
            view == ViewTransform::Standard,
            "{name}: {log}"
        );
        assert_eq!(clipped > 0, view == ViewTransform::Standard, "{name}");
    }
    // JPEG: the same look, compressed (within a few codes of the PNG's).
    let (_, log) = render("agx.jpg", &["--view-transform", "agx", "--exposure", "-1.5"]);
    assert!(!log.contains("clamped"), "{log}");
    let jpg = image::open(dir.join("agx.jpg")).unwrap().into_rgb8().into_raw();
    let png = image::open(dir.join("agx.png")).unwrap().into_rgb8().into_raw();
    let mean_diff = jpg.iter().zip(&png).map(|(a, b)| a.abs_diff(*b) as f64).sum::<f64>() / png.len() as f64;
    assert!(mean_diff < 4.0, "JPEG off the PNG by {mean_diff} codes on average");
    let bad = render_cornell(&dir.join("x.png"), (8, 8), 1, &["--exposure", "1e9"]).output().unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("expected a number of stops within +-64"));
    std::fs::remove_dir_all(&dir).unwrap();
}
