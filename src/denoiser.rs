//! The denoisers behind `--denoise`: Intel Open Image Denoise's `RT` filter in a build with
//! `--features oidn` (module `oidn`), and pathwave's own edge-avoiding à-trous filter
//! ([`crate::integrator::denoise`]) in every build. Both take the render's per-pixel means and
//! the guides of [`crate::integrator::aov`] (the à-trous filter also the variance of each mean).

use crate::integrator::{aov::Aovs, denoise as atrous};
use glam::Vec3;

#[cfg(feature = "oidn")]
pub mod oidn;

/// Which denoiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Denoiser {
    /// Intel Open Image Denoise (a build with `--features oidn`).
    Oidn,
    /// pathwave's à-trous filter.
    Atrous,
}

/// Why `--denoise oidn` is refused by a build without the feature.
pub const NOT_BUILT: &str = "this pathwave was built without Intel Open Image Denoise: install it once \
     with `eval \"$(scripts/setup-oidn.sh)\"` (sets OIDN_DIR), then build with \
     `cargo build --release --features oidn` (README, \"Denoising\"); `--denoise atrous` works in \
     every build";

impl Denoiser {
    /// What a bare `--denoise` means: OIDN in a build with it, else the à-trous filter.
    pub const DEFAULT: Self = if cfg!(feature = "oidn") { Self::Oidn } else { Self::Atrous };

    /// [`Self::DEFAULT`]'s name, for the command line.
    pub const DEFAULT_NAME: &str = if cfg!(feature = "oidn") { "oidn" } else { "atrous" };

    /// The denoisers this build has.
    pub const AVAILABLE: &[Self] =
        if cfg!(feature = "oidn") { &[Self::Oidn, Self::Atrous] } else { &[Self::Atrous] };

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Oidn => "oidn",
            Self::Atrous => "atrous",
        }
    }

    /// Parses `oidn` or `atrous` (also `à-trous`, `a-trous`), refusing `oidn` in a build without it.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "oidn" if cfg!(feature = "oidn") => Ok(Self::Oidn),
            "oidn" => Err(NOT_BUILT.to_string()),
            "atrous" | "a-trous" | "à-trous" => Ok(Self::Atrous),
            // `render --denoise scene.ron`: the scene went to --denoise.
            _ if s.contains(['.', '/']) => Err(format!(
                "unknown denoiser {s:?}: oidn or atrous (a bare --denoise takes the next word as \
                 the denoiser: put it after the scene, or write --denoise={})",
                Self::DEFAULT_NAME
            )),
            _ => Err(format!("unknown denoiser {s:?}: oidn or atrous")),
        }
    }
}

/// Checks before a render that `which` can run on `threads` threads (OIDN: makes its device).
pub fn prepare(which: Denoiser, threads: usize) -> Result<(), String> {
    match which {
        Denoiser::Atrous => Ok(()),
        #[cfg(feature = "oidn")]
        Denoiser::Oidn => oidn::ready(threads),
        #[cfg(not(feature = "oidn"))]
        Denoiser::Oidn => {
            let _ = threads;
            Err(NOT_BUILT.to_string())
        }
    }
}

/// Denoises `color` (per-pixel means; `variance`, the variance of each mean, only guides the
/// à-trous filter) with the guides `aovs`. The à-trous filter runs on the current rayon pool,
/// OIDN on `threads` threads of its own (0: all cores).
pub fn denoise(
    which: Denoiser,
    color: &[Vec3],
    variance: &[Vec3],
    aovs: &Aovs,
    threads: usize,
) -> Result<Vec<Vec3>, String> {
    match which {
        Denoiser::Atrous => Ok(atrous::denoise(color, variance, aovs, &atrous::Options::default())),
        #[cfg(feature = "oidn")]
        Denoiser::Oidn => oidn::denoise(color, aovs, &oidn::Options { threads, ..Default::default() }),
        #[cfg(not(feature = "oidn"))]
        Denoiser::Oidn => {
            let _ = threads;
            Err(NOT_BUILT.to_string())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_oidn_needs_the_feature() {
        assert_eq!(Denoiser::parse("atrous"), Ok(Denoiser::Atrous));
        assert_eq!(Denoiser::parse("à-trous"), Ok(Denoiser::Atrous));
        assert!(Denoiser::parse("bilateral").unwrap_err().contains("oidn or atrous"));
        assert_eq!(Denoiser::parse(Denoiser::DEFAULT_NAME), Ok(Denoiser::DEFAULT));
        assert!(Denoiser::AVAILABLE.contains(&Denoiser::DEFAULT));
        match cfg!(feature = "oidn") {
            true => assert_eq!(Denoiser::parse("OIDN"), Ok(Denoiser::Oidn)),
            false => assert!(Denoiser::parse("oidn").unwrap_err().contains("--features oidn")),
        }
    }
}
