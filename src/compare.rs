//! `pathwave compare`: relMSE, RMSE and means of two images.

use crate::io::{self, LinearImage};
use crate::metrics;
use std::path::{Path, PathBuf};

/// `pathwave compare`'s flags.
#[derive(clap::Args, Debug)]
pub struct CompareCommand {
    /// The image to judge.
    pub a: PathBuf,
    /// The reference.
    pub b: PathBuf,
    /// How to read an 8-bit file compared with a linear one: `decode` its sRGB values to
    /// linear, or compare them `as-stored` (in [0, 1]).
    #[arg(long, value_enum)]
    pub encoded: Option<Encoded>,
}

/// How `compare` reads an sRGB-encoded file beside a linear one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Encoded {
    /// Decode sRGB to linear.
    Decode,
    /// Compare the stored values.
    AsStored,
}

/// Prints how far image `a` is from the reference `b`.
pub fn run(c: &CompareCommand) -> Result<(), String> {
    let (a, b, encoded) = (c.a.as_path(), c.b.as_path(), c.encoded);
    let linear = |p: &Path| {
        let e = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        e == "exr" || e == "hdr"
    };
    let read = |p: &Path| -> Result<LinearImage, String> {
        let mut img = io::read_linear(p)?;
        if !linear(p) && encoded == Some(Encoded::Decode) {
            img.pixels.iter_mut().for_each(|c| *c = c.map(crate::engine::texture::srgb_to_linear));
        }
        Ok(img)
    };
    if linear(a) != linear(b) && encoded.is_none() {
        let (enc, lin) = if linear(a) { (b, a) } else { (a, b) };
        return Err(format!(
            "{} is sRGB-encoded and {} linear: pass --encoded decode to decode the first to linear, \
             or --encoded as-stored to compare the stored values",
            enc.display(),
            lin.display()
        ));
    }
    let (x, r) = (read(a)?, read(b)?);
    if (x.width, x.height) != (r.width, r.height) {
        return Err(format!("sizes differ: {}x{} vs {}x{}", x.width, x.height, r.width, r.height));
    }
    let (mx, mr) = (metrics::mean(&x.pixels), metrics::mean(&r.pixels));
    // Against a black reference a relative difference of means says nothing.
    let relative = match mr > 0.0 {
        true => format!(" ({:+.3}%)", 100.0 * (mx / mr - 1.0)),
        false => String::new(),
    };
    println!(
        "relMSE {:.6}  RMSE {:.6}  mean {mx:.6} vs {mr:.6}{relative}",
        metrics::rel_mse(&x.pixels, &r.pixels),
        metrics::rmse(&x.pixels, &r.pixels),
    );
    Ok(())
}
