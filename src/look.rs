//! How linear radiance becomes an 8-bit picture (PNG, JPEG, GIF, the preview window): an
//! exposure, then a view transform, then sRGB encoding. EXR outputs stay linear and untouched.
//!
//! - `standard`: the sRGB transfer function of the exposed value, clipped to [0, 1] per channel
//!   (what pathwave always did, and Blender's "Standard").
//! - `filmic`: Narkowicz's fit of the ACES reference rendering and output transforms
//!   ("ACES Filmic Tone Mapping Curve", 2016): `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`
//!   per channel, a toe and a shoulder that roll highlights off instead of clipping them.
//! - `agx`: Troy Sobotka's AgX (github.com/sobotka/AgX; Blender's default view transform since
//!   4.0) in the form of Benjamin Wrensch's "Minimal AgX implementation" (iolite engine, 2023,
//!   MIT): the exposed Rec. 709 colour through AgX's inset matrix, its log2 clamped to
//!   [-12.47393, 4.026069] stops and mapped to [0, 1], a polynomial fit of AgX's default
//!   contrast sigmoid, the inverse (outset) matrix, and the 2.2 power that the sigmoid's output
//!   is encoded with, undone before the sRGB encoding. Bright saturated colours desaturate
//!   towards white as film does, rather than clipping to a hue shift.

use glam::{Mat3, Vec3};

/// A view transform (see the module documentation).
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ViewTransform {
    /// sRGB, clipped.
    #[default]
    Standard,
    /// Narkowicz's ACES fit.
    Filmic,
    /// AgX.
    Agx,
}

/// The flags that set how 8-bit outputs look.
#[derive(clap::Args, Clone, Copy, Debug, Default)]
pub struct LookArgs {
    /// Exposure in stops for 8-bit outputs (PNG, GIF, the preview window), within +-64: the
    /// linear image is scaled by 2^EV before the view transform. EXR outputs stay as rendered.
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = exposure)]
    pub exposure: f32,
    /// The view transform of 8-bit outputs: standard (sRGB, clipped), filmic (an ACES curve) or
    /// agx (as Blender's default): the last two roll highlights off instead of clipping them.
    #[arg(long, value_enum, default_value_t = ViewTransform::Standard)]
    pub view_transform: ViewTransform,
}

impl LookArgs {
    /// The look the flags ask for.
    pub fn look(&self) -> Look {
        Look { scale: self.exposure.exp2(), view: self.view_transform }
    }
}

/// The most stops `--exposure` takes either way (2^64 is beyond any sensible radiance scale).
const MAX_EXPOSURE: f32 = 64.0;

/// `--exposure`: a finite number of stops within +-[`MAX_EXPOSURE`].
fn exposure(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(ev) if ev.is_finite() && ev.abs() <= MAX_EXPOSURE => Ok(ev),
        _ => Err(format!("expected a number of stops within +-{MAX_EXPOSURE}, not {s:?}")),
    }
}

/// An exposure and a view transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// The factor on linear radiance: 2^EV.
    scale: f32,
    /// The view transform.
    view: ViewTransform,
}

impl Default for Look {
    /// No exposure change, `standard`.
    fn default() -> Self {
        Look { scale: 1.0, view: ViewTransform::Standard }
    }
}

impl Look {
    /// The sRGB-encoded value in [0, 1] of the linear colour `c`, and whether the transform
    /// clipped it (`standard` only: the others roll off, and clip nothing but rounding).
    pub fn encode(&self, c: Vec3) -> (Vec3, bool) {
        let c = c * self.scale;
        let display = match self.view {
            ViewTransform::Standard => c,
            ViewTransform::Filmic => {
                let c = c.max(Vec3::ZERO);
                (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14)
            }
            ViewTransform::Agx => agx(c),
        };
        let clipped = self.view == ViewTransform::Standard && display.max_element() > 1.0;
        (display.clamp(Vec3::ZERO, Vec3::ONE).to_array().map(srgb_oetf).into(), clipped)
    }

    /// 8-bit sRGB pixels (R, G, B each) of linear `pixels`, and how many were clipped.
    pub fn srgb8(&self, pixels: &[Vec3]) -> (Vec<u8>, usize) {
        let mut clipped = 0;
        let data = pixels
            .iter()
            .flat_map(|&p| {
                let (e, clip) = self.encode(p);
                clipped += clip as usize;
                e.to_array().map(|c| (c * 255.0 + 0.5) as u8)
            })
            .collect();
        (data, clipped)
    }
}

/// The sRGB transfer function (linear to encoded).
pub fn srgb_oetf(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// AgX's inset matrix (rows: the output channels).
#[expect(clippy::excessive_precision, reason = "the digits as published")]
const AGX_INSET: [[f32; 3]; 3] = [
    [0.842_479_06, 0.078_433_6, 0.079_223_745],
    [0.042_328_242, 0.878_468_6, 0.079_166_13],
    [0.042_375_655, 0.078_433_6, 0.879_142_97],
];

/// Its outset matrix, the inverse that brings the sigmoid's output back to Rec. 709.
const AGX_OUTSET: [[f32; 3]; 3] = [
    [1.196_879, -0.098_020_88, -0.099_029_74],
    [-0.052_896_85, 1.151_903_1, -0.098_961_18],
    [-0.052_971_635, -0.098_043_45, 1.151_073_7],
];

/// The stops below and above middle grey that AgX's log encoding spans.
const AGX_MIN_EV: f32 = -12.47393;
const AGX_MAX_EV: f32 = 4.026069;

/// A matrix written by rows.
fn rows(m: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(&m).transpose()
}

/// AgX of an exposed linear Rec. 709 colour: display-linear values in [0, 1].
fn agx(c: Vec3) -> Vec3 {
    let v = rows(AGX_INSET) * c.max(Vec3::ZERO);
    // log2 of 0 is -inf, clamped to the bottom of the range.
    let v = v.to_array().map(|x| {
        let ev = x.log2().clamp(AGX_MIN_EV, AGX_MAX_EV);
        let t = (ev - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV);
        // The sixth-order fit of AgX's default contrast curve.
        let (t2, t4) = (t * t, t * t * t * t);
        15.5 * t4 * t2 - 40.14 * t4 * t + 31.96 * t4 - 6.868 * t2 * t + 0.4298 * t2 + 0.1191 * t - 0.00232
    });
    let v = rows(AGX_OUTSET) * Vec3::from(v);
    v.max(Vec3::ZERO).to_array().map(|x| x.powf(2.2)).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_is_srgb_clipped_and_counts_what_it_clips() {
        let look = Look::default();
        let white = srgb_oetf(1.0);
        assert_eq!(look.encode(Vec3::new(0.5, 0.0, 1.0)).0, Vec3::new(srgb_oetf(0.5), 0.0, white));
        assert_eq!(look.encode(Vec3::new(2.0, 0.0, 0.0)), (Vec3::new(white, 0.0, 0.0), true));
        // One stop up doubles, before the transform.
        let up = LookArgs { exposure: 1.0, view_transform: ViewTransform::Standard }.look();
        assert_eq!(up.encode(Vec3::splat(0.25)).0, look.encode(Vec3::splat(0.5)).0);
        assert_eq!(exposure("-2.5"), Ok(-2.5));
        assert!(exposure("nan").is_err() && exposure("100").is_err() && exposure("x").is_err());
    }

    /// Both curves keep black black, rise monotonically, roll highlights off below white
    /// without clipping them, and map middle grey near the middle of the display range.
    #[test]
    fn filmic_and_agx_roll_off_instead_of_clipping() {
        for view in [ViewTransform::Filmic, ViewTransform::Agx] {
            let look = Look { scale: 1.0, view };
            let grey = |x: f32| look.encode(Vec3::splat(x)).0.x;
            assert!(grey(0.0) < 0.01, "{view:?}: black is {}", grey(0.0));
            let mut last = grey(0.0);
            for k in 1..200 {
                let x = 1e-3 * 1.06f32.powi(k);
                let y = grey(x);
                assert!(y >= last - 1e-6 && y <= 1.0, "{view:?}: {x} gives {y} after {last}");
                last = y;
            }
            assert!(grey(4.0) < 0.999 && grey(4.0) > grey(1.0), "{view:?}: no roll-off");
            assert!((0.3..0.65).contains(&grey(0.18)), "{view:?}: middle grey at {}", grey(0.18));
            assert!(!look.encode(Vec3::splat(100.0)).1, "{view:?}: counted as clipped");
        }
        // AgX's matrices are each other's inverse.
        let id = rows(AGX_OUTSET) * rows(AGX_INSET);
        assert!(id.abs_diff_eq(Mat3::IDENTITY, 1e-5), "{id}");
        // A saturated highlight goes towards white rather than staying pure red.
        let red = Look { scale: 1.0, view: ViewTransform::Agx }.encode(Vec3::new(50.0, 0.0, 0.0)).0;
        assert!(red.y > 0.2 && red.z > 0.2 && red.x > red.y, "{red}");
    }
}
