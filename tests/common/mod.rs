//! Helpers shared by the integration tests.
#![allow(dead_code, reason = "each test binary uses a part of the shared helpers")]

use glam::Vec3;
use pathwave::engine::scene::{SceneDesc, load, parse};
use pathwave::engine::world::SceneWorld;
use pathwave::integrator::{film::Film, oracle};
use pathwave::io::{LinearImage, read_linear};
use std::path::{Path, PathBuf};

pub mod tev;

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `pathwave render scenes/cornell.ron` at `width` x `height` and `spp` into `out`, with `extra`
/// flags, from the repository root.
pub fn render_cornell(
    out: &Path,
    (width, height): (u32, u32),
    spp: u32,
    extra: &[&str],
) -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"));
    c.args([
        "render",
        "scenes/cornell.ron",
        "--width",
        &width.to_string(),
        "--height",
        &height.to_string(),
        "-o",
    ])
    .arg(out)
    .arg("--spp")
    .arg(spp.to_string())
    .args(extra)
    .current_dir(root());
    c
}

/// The `pathwave` binary of this build, as a command.
pub fn pathwave() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_pathwave"))
}

/// An empty folder `pathwave-{prefix}-{name}-{pid}` in the system's temporary folder.
pub fn temp(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-{prefix}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `cmd`, which must succeed, and returns what it wrote to stderr.
pub fn run(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    err
}

/// A scene from `scenes/`.
pub fn scene(name: &str) -> SceneDesc {
    load(&root().join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// A scene written inline.
pub fn inline(text: &str) -> SceneDesc {
    parse(text, Path::new("<test>")).unwrap_or_else(|e| panic!("{e}"))
}

/// A reference image from `tests/references`.
pub fn reference(name: &str) -> LinearImage {
    read_linear(&root().join("tests/references").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders with the reference path tracer on the current rayon pool.
pub fn render(desc: &SceneDesc) -> Film {
    let scene = SceneWorld::render_scene(desc);
    oracle::render(&scene, &|_, _| {})
}

/// Renders on a pool of `threads` threads.
pub fn render_threads(desc: &SceneDesc, threads: usize) -> Film {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| render(desc))
}

/// Sets one named material's albedo (Lambertian or Metal) to `f(albedo)`.
pub fn scale_albedo(desc: &mut SceneDesc, name: &str, factor: f32) {
    use pathwave::engine::scene::{Albedo, Color, MaterialDesc};
    let (_, m) = desc.materials.0.iter_mut().find(|(n, _)| n == name).expect("material exists");
    let albedo = match m {
        MaterialDesc::Lambertian(d) => &mut d.albedo,
        MaterialDesc::Metal(d) => &mut d.albedo,
        _ => panic!("{name} is neither Lambertian nor Metal"),
    };
    let Color::Value(a) = albedo else { panic!("{name}'s albedo is a texture") };
    *a = Albedo((a.0 * factor).min(Vec3::ONE));
}

/// Block-mean comparison of a render with a reference: the image is cut into `block` x `block`
/// pixel blocks; for each block and channel, z = (mean - reference mean) / sigma, where sigma^2
/// is the variance of our block mean (from the per-pixel sample variance) plus the reference's
/// own (the same estimator's variance scaled by spp / ref_spp).
pub fn block_z(film: &Film, reference: &LinearImage, block: u32, ref_spp: u32) -> BlockStats {
    assert_eq!((film.width, film.height), (reference.width, reference.height));
    let mean = film.mean();
    let var = film.variance_of_mean();
    let scale_ref = film.spp as f64 / ref_spp as f64;
    let (bw, bh) = (film.width / block, film.height / block);
    let (mut chi2, mut max_z, mut n, mut worst) = (0.0, 0.0f64, 0, String::new());
    for by in 0..bh {
        for bx in 0..bw {
            for c in 0..3 {
                let (mut m, mut r, mut v) = (0.0f64, 0.0f64, 0.0f64);
                for y in by * block..(by + 1) * block {
                    for x in bx * block..(bx + 1) * block {
                        let i = (y * film.width + x) as usize;
                        m += mean[i][c] as f64;
                        r += reference.pixels[i][c] as f64;
                        v += var[i][c] as f64;
                    }
                }
                let k = (block * block) as f64;
                let (m, r, v) = (m / k, r / k, v / (k * k));
                let sigma2 = v * (1.0 + scale_ref);
                if sigma2 == 0.0 {
                    // A block with no variance (e.g. pure background) must match exactly-ish.
                    assert!(
                        (m - r).abs() <= 1e-4 * r.abs().max(1e-3),
                        "noise-free block differs: {m} vs {r}"
                    );
                    continue;
                }
                // Two f32 renderers agree on noise-free features (a mirror reflecting the sky) to
                // about 1e-4 relative: differences below 0.1% of the value are not errors.
                let sigma2 = sigma2 + (1e-3 * r).powi(2);
                let z = (m - r) / sigma2.sqrt();
                chi2 += z * z;
                if z.abs() > max_z {
                    max_z = z.abs();
                    worst = format!(
                        "block ({bx}, {by}) channel {c}: {m:.6} vs {r:.6}, sigma {:.2e}",
                        sigma2.sqrt()
                    );
                }
                n += 1;
            }
        }
    }
    BlockStats { chi2_dof: chi2 / n as f64, max_z, blocks: n, worst }
}

/// Result of [`block_z`].
#[derive(Debug)]
pub struct BlockStats {
    /// Chi-square per degree of freedom: 1 in expectation for an unbiased renderer.
    pub chi2_dof: f64,
    /// Largest |z|.
    pub max_z: f64,
    /// Number of (block, channel) pairs.
    pub blocks: usize,
    /// Description of the block with the largest |z|.
    pub worst: String,
}

impl BlockStats {
    /// Chi-square per dof within 5 sigma of 1 and no block beyond 6 sigma.
    pub fn agrees(&self) -> bool {
        self.chi2_dof < 1.0 + 5.0 * (2.0 / self.blocks as f64).sqrt() && self.max_z < 6.0
    }
}

/// A UV sphere of radius 1 with `rings` x `segments` quads as triangles, with or without
/// vertex normals (`vn`).
pub fn sphere_obj(rings: u32, segments: u32, normals: bool) -> String {
    let mut s = String::new();
    let mut verts = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            verts.push([theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()]);
        }
    }
    for v in &verts {
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        if normals {
            s += &format!("vn {} {} {}\n", v[0], v[1], v[2]);
        }
    }
    let at = |i: u32, j: u32| i * segments + j % segments + 1;
    let face = |a: u32, b: u32, c: u32| {
        if normals { format!("f {a}//{a} {b}//{b} {c}//{c}\n") } else { format!("f {a} {b} {c}\n") }
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // Outward winding: (b - a) x (c - a) points away from the centre.
            s += &face(a, c, b);
            s += &face(a, d, c);
        }
    }
    s
}
