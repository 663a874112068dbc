//! Spectra as the RGB that Mitsuba 3's RGB variants make of them (its `spectrum_list_to_srgb`
//! and `Properties`' handling of `<spectrum>`): wavelength:value pairs are integrated against
//! the CIE 1931 2-degree colour matching functions (weighted by illuminant D65 for reflectances,
//! not for emission) at 1,000 evenly spaced wavelengths from 360 to 830 nm, linearly
//! interpolated between the given pairs and zero outside them, then taken from XYZ to linear
//! sRGB; a constant spectrum is that constant for reflectances and the constant times the sRGB
//! of equal-energy white (XYZ = (1, 1, 1)) for emission.
//!
//! Data: the CIE 1931 standard observer and the relative spectral power of illuminant D65 at
//! 5 nm from 360 to 830 nm (CIE 015:2018, "Colorimetry", 4th edition, tables), as Mitsuba 3
//! tabulates them; sampled by linear interpolation.

use super::xml::At;
use crate::scene::SceneError;
use glam::DVec3;

/// A `<spectrum>`: one constant, or wavelengths (nm, increasing) and their values.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f64),
    /// `(wavelength, value)` pairs, at least two, wavelengths increasing.
    Pairs(Vec<(f64, f64)>),
}

/// What a spectrum describes, which decides its RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Use {
    /// A reflectance: D65-weighted, clamped to [0, 1].
    Reflectance,
    /// A quantity without bounds (an index of refraction): D65-weighted, clamped at 0.
    Unbounded,
    /// Emitted radiance: not weighted, clamped at 0.
    Emission,
}

/// The most pairs a spectrum may have (a 1 nm table over 360-830 nm has 471).
pub const MAX_PAIRS: usize = 100_000;

const MIN: f64 = 360.0;
const MAX: f64 = 830.0;
const SAMPLES: usize = 95;
/// Scales the matching functions so that a spectrum of 1 has luminance 1 (Mitsuba's
/// `MI_CIE_Y_NORMALIZATION`, the sum of the sampled y-bar).
const Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// Scales D65 so that it has luminance 1.
const D65_NORMALIZATION: f64 = 1.0 / 98.99741751876255;

/// x-bar at 360, 365, ..., 830 nm.
const CIE_X: [f32; SAMPLES] = [
    0.0001299,
    0.0002321,
    0.0004149,
    0.0007416,
    0.001368,
    0.002236,
    0.004243,
    0.00765,
    0.01431,
    0.02319,
    0.04351,
    0.07763,
    0.13438,
    0.21477,
    0.2839,
    0.3285,
    0.34828,
    0.34806,
    0.3362,
    0.3187,
    0.2908,
    0.2511,
    0.19536,
    0.1421,
    0.09564,
    0.05795001,
    0.03201,
    0.0147,
    0.0049,
    0.0024,
    0.0093,
    0.0291,
    0.06327,
    0.1096,
    0.1655,
    0.2257499,
    0.2904,
    0.3597,
    0.4334499,
    0.5120501,
    0.5945,
    0.6784,
    0.7621,
    0.8425,
    0.9163,
    0.9786,
    1.0263,
    1.0567,
    1.0622,
    1.0456,
    1.0026,
    0.9384,
    0.8544499,
    0.7514,
    0.6424,
    0.5419,
    0.4479,
    0.3608,
    0.2835,
    0.2187,
    0.1649,
    0.1212,
    0.0874,
    0.0636,
    0.04677,
    0.0329,
    0.0227,
    0.01584,
    0.01135916,
    0.008110916,
    0.005790346,
    0.004109457,
    0.002899327,
    0.00204919,
    0.001439971,
    0.0009999493,
    0.0006900786,
    0.0004760213,
    0.0003323011,
    0.0002348261,
    0.0001661505,
    0.000117413,
    8.307527e-05,
    5.870652e-05,
    4.150994e-05,
    2.935326e-05,
    2.067383e-05,
    1.455977e-05,
    1.025398e-05,
    7.221456e-06,
    5.085868e-06,
    3.581652e-06,
    2.522525e-06,
    1.776509e-06,
    1.251141e-06,
];
/// y-bar.
const CIE_Y: [f32; SAMPLES] = [
    3.917e-06, 6.965e-06, 1.239e-05, 2.202e-05, 3.9e-05, 6.4e-05, 0.00012, 0.000217, 0.000396, 0.00064,
    0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684, 0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098,
    0.1126, 0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082, 0.71, 0.7932, 0.862, 0.9148501,
    0.954, 0.9803, 0.9949501, 1.0, 0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949, 0.631, 0.5668,
    0.503, 0.4412, 0.381, 0.321, 0.265, 0.217, 0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484, 0.001047, 0.00074, 0.00052,
    0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-05, 6e-05, 4.24e-05, 3e-05, 2.12e-05, 1.499e-05,
    1.06e-05, 7.4657e-06, 5.2578e-06, 3.7029e-06, 2.6078e-06, 1.8366e-06, 1.2934e-06, 9.1093e-07, 6.4153e-07,
    4.5181e-07,
];
/// z-bar.
const CIE_Z: [f32; SAMPLES] = [
    0.0006061,
    0.001086,
    0.001946,
    0.003486,
    0.006450001,
    0.01054999,
    0.02005001,
    0.03621,
    0.06785001,
    0.1102,
    0.2074,
    0.3713,
    0.6456,
    1.0390501,
    1.3856,
    1.62296,
    1.74706,
    1.7826,
    1.77211,
    1.7441,
    1.6692,
    1.5281,
    1.28764,
    1.0419,
    0.8129501,
    0.6162,
    0.46518,
    0.3533,
    0.272,
    0.2123,
    0.1582,
    0.1117,
    0.07824999,
    0.05725001,
    0.04216,
    0.02984,
    0.0203,
    0.0134,
    0.008749999,
    0.005749999,
    0.0039,
    0.002749999,
    0.0021,
    0.0018,
    0.001650001,
    0.0014,
    0.0011,
    0.001,
    0.0008,
    0.0006,
    0.00034,
    0.00024,
    0.00019,
    0.0001,
    4.999999e-05,
    3e-05,
    2e-05,
    1e-05,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
];
/// D65, relative to 100 at 560 nm.
const D65: [f32; SAMPLES] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486,
    92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861,
    115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296, 104.79, 106.239,
    107.689, 106.047, 104.405, 104.225, 104.046, 102.023, 100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368,
    88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992,
    81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091,
    72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054, 46.4182,
    56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054, 51.959, 54.6998, 57.4406,
    58.8765, 60.3125,
];

/// Linear interpolation in a 5 nm table at `w` in [360, 830] nm.
fn table(t: &[f32; SAMPLES], w: f64) -> f64 {
    let x = (w - MIN) * ((SAMPLES - 1) as f64 / (MAX - MIN));
    let i = (x as usize).min(SAMPLES - 2);
    let f = x - i as f64;
    (1.0 - f) * t[i] as f64 + f * t[i + 1] as f64
}

/// CIE XYZ to linear sRGB (Rec. 709 primaries, D65 white), the matrix Mitsuba uses.
pub fn xyz_to_srgb(c: DVec3) -> DVec3 {
    DVec3::new(
        3.240479 * c.x - 1.537150 * c.y - 0.498535 * c.z,
        -0.969256 * c.x + 1.875991 * c.y + 0.041556 * c.z,
        0.055648 * c.x - 0.204043 * c.y + 1.057311 * c.z,
    )
}

impl Spectrum {
    /// Parses Mitsuba's `value` text: one number, or `wavelength:value` pairs separated by
    /// commas or spaces.
    pub fn parse(text: &str, at: &At) -> Result<Self, SceneError> {
        let tokens: Vec<&str> =
            text.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).collect();
        let number = |s: &str| match s.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(at.error(format!("<spectrum>: expected a finite number, found \"{s}\""))),
        };
        if let [one] = tokens.as_slice()
            && !one.contains(':')
        {
            return Ok(Spectrum::Constant(number(one)?));
        }
        if tokens.len() > MAX_PAIRS {
            return Err(at.error(format!("<spectrum> has more than {MAX_PAIRS} pairs")));
        }
        let pairs = tokens
            .iter()
            .map(|t| match t.split_once(':') {
                Some((w, v)) => Ok((number(w)?, number(v)?)),
                None => Err(at.error(format!("<spectrum>: \"{t}\" is not a wavelength:value pair"))),
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::pairs(pairs, at)
    }

    /// Reads an `.spd` file's text: a `wavelength value` pair per line, `#` comments.
    pub fn parse_file(text: &str, at: &At) -> Result<Self, SceneError> {
        let mut pairs = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let mut it = line.split_whitespace().map(str::parse::<f64>);
            match (it.next(), it.next(), it.next()) {
                (Some(Ok(w)), Some(Ok(v)), None) if w.is_finite() && v.is_finite() => pairs.push((w, v)),
                _ => {
                    return Err(at.error(format!(
                        "spectrum file line {}: expected \"wavelength value\", found \"{line}\"",
                        n + 1
                    )));
                }
            }
            if pairs.len() > MAX_PAIRS {
                return Err(at.error(format!("the spectrum file has more than {MAX_PAIRS} pairs")));
            }
        }
        Self::pairs(pairs, at)
    }

    fn pairs(pairs: Vec<(f64, f64)>, at: &At) -> Result<Self, SceneError> {
        if pairs.len() < 2 {
            return Err(at.error("a spectrum of wavelength:value pairs needs at least two"));
        }
        if pairs.windows(2).any(|w| !(w[1].0 > w[0].0)) {
            return Err(at.error("a spectrum's wavelengths must increase"));
        }
        Ok(Spectrum::Pairs(pairs))
    }

    /// The linear sRGB colour Mitsuba's RGB variants use for this spectrum.
    pub fn to_rgb(&self, usage: Use) -> DVec3 {
        let rgb = match self {
            Spectrum::Constant(v) if usage == Use::Emission => *v * xyz_to_srgb(DVec3::ONE),
            Spectrum::Constant(v) => DVec3::splat(*v),
            Spectrum::Pairs(p) => {
                const STEPS: usize = 1000;
                let (first, last) = (p[0].0, p[p.len() - 1].0);
                let mut xyz = DVec3::ZERO;
                for i in 0..STEPS {
                    let w = MIN + (i as f64 / (STEPS - 1) as f64) * (MAX - MIN);
                    if w < first || w > last {
                        continue;
                    }
                    // The pair interval holding w (the last one for w at the last wavelength).
                    let k = p.partition_point(|q| q.0 <= w).clamp(1, p.len() - 1) - 1;
                    let ((w0, v0), (w1, v1)) = (p[k], p[k + 1]);
                    let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
                    let weight = match usage {
                        Use::Emission => 1.0,
                        _ => table(&D65, w) * D65_NORMALIZATION,
                    };
                    xyz += DVec3::new(table(&CIE_X, w), table(&CIE_Y, w), table(&CIE_Z, w)) * v * weight;
                }
                xyz_to_srgb(xyz * ((MAX - MIN) * Y_NORMALIZATION / STEPS as f64))
            }
        };
        match usage {
            Use::Reflectance => rgb.clamp(DVec3::ZERO, DVec3::ONE),
            _ => rgb.max(DVec3::ZERO),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn at() -> At {
        At { file: Arc::new("t.xml".into()), line: 1, col: 1 }
    }

    #[test]
    fn a_flat_reflectance_is_grey_and_flat_emission_is_equal_energy_white() {
        let flat = Spectrum::parse("360:0.5, 830:0.5", &at()).unwrap().to_rgb(Use::Reflectance);
        // D65-weighted flat reflectance: grey, to the tables' precision.
        assert!((flat - DVec3::splat(0.5)).abs().max_element() < 0.01, "{flat}");
        let e = Spectrum::parse("1", &at()).unwrap().to_rgb(Use::Emission);
        assert!((e - xyz_to_srgb(DVec3::ONE)).abs().max_element() < 1e-12);
        assert!(e.x > e.y && e.y > e.z, "equal-energy white is reddish in sRGB: {e}");
        assert_eq!(Spectrum::parse("0.25", &at()).unwrap().to_rgb(Use::Reflectance), DVec3::splat(0.25));
    }

    #[test]
    fn a_red_spectrum_is_red_and_luminance_is_kept() {
        let red = Spectrum::parse("400:0, 580:0, 600:1, 700:1", &at()).unwrap().to_rgb(Use::Emission);
        assert!(red.x > 3.0 * red.y && red.x > 3.0 * red.z, "{red}");
        // Flat emission of 1 over the whole range has luminance 1 (Y normalisation).
        let flat = Spectrum::parse("360:1, 830:1", &at()).unwrap().to_rgb(Use::Emission);
        let y = 0.212671 * flat.x + 0.715160 * flat.y + 0.072169 * flat.z;
        assert!((y - 1.0).abs() < 0.01, "{y}");
    }

    /// Values printed by Mitsuba 3.9.1's `mi.spectrum_list_to_srgb` (scalar_rgb variant).
    #[test]
    fn matches_mitsuba() {
        let e = Spectrum::parse("400:0, 500:8, 600:15.6, 700:18.4", &at()).unwrap().to_rgb(Use::Emission);
        assert!((e - DVec3::new(20.7108, 10.8546, 2.77115)).abs().max_element() < 2e-4, "{e}");
        let r = Spectrum::parse("400:0.78, 500:0.78, 600:0.78, 700:0.78", &at())
            .unwrap()
            .to_rgb(Use::Reflectance);
        assert!((r - DVec3::new(0.776368, 0.779809, 0.776029)).abs().max_element() < 2e-6, "{r}");
    }

    #[test]
    fn malformed_spectra_are_refused() {
        for bad in ["400:1", "500:1, 400:2", "400:1, 500", "a:1, 500:2", "400:1, 500:inf"] {
            assert!(Spectrum::parse(bad, &at()).is_err(), "{bad}");
        }
        assert!(Spectrum::parse_file("# c\n400 1\n500 2 3\n", &at()).is_err());
        assert_eq!(
            Spectrum::parse_file("# c\n400 1\n500 2\n", &at()).unwrap(),
            Spectrum::Pairs(vec![(400.0, 1.0), (500.0, 2.0)])
        );
    }
}
