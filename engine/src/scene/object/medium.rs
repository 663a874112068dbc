//! `medium: (..)`: what fills a volume object: a homogeneous medium, or one scaled by voxel
//! grids (files, or their frame sequences), with its phase function.

use crate::format::files::InputFile;
use crate::format::{Albedo, Radiance};
use crate::media::grid::VoxelGrid;
use crate::scene::assets::{GridFrames, GridPath};
use crate::scene::transform::{TransformOp, compose};
use serde::Deserialize;
use serde::de::Error;
use std::sync::Arc;

/// A medium with an isotropic phase function: homogeneous, or scaled by voxel grids.
#[derive(Deserialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields, rename = "Medium")]
pub struct MediumDesc {
    /// Extinction coefficient sigma_t per unit length: one number for every channel (> 0), or
    /// `(r, g, b)` per channel (each >= 0, one > 0).
    pub density: Density,
    /// Single-scattering albedo sigma_s / sigma_t, components in [0, 1].
    pub albedo: Albedo,
    /// `grid: (file: "smoke.vol", transform: [..])`: the density is `density` times the grid's
    /// value, inside the grid's cube only (default none: homogeneous). One number for
    /// `density` then.
    #[serde(default)]
    pub grid: Option<GridDesc>,
    /// `albedo_grid: (file: .., transform: [..])`: the albedo is `albedo` times the grid's
    /// colour (its edge values outside its cube), whose values lie in [0, 1] (default none).
    #[serde(default)]
    pub albedo_grid: Option<GridDesc>,
    /// The phase function (default `Isotropic`).
    #[serde(default)]
    pub phase: PhaseDesc,
    /// `emission: (r, g, b)`: the radiance the medium emits, `Le` (default none): a point
    /// emits `sigma_a Le` per unit length, where `sigma_a = (1 - albedo) sigma_t` is its
    /// absorption (pbrt-v4's convention: an opaque medium that absorbs everything shows `Le`,
    /// one that only scatters does not glow).
    #[serde(default)]
    pub emission: Option<Radiance>,
    /// `emission_grid: (file: .., name: "temperature", transform: [..])`: the emission is
    /// `emission` times the grid's colour (its edge values outside its cube), as a flame's
    /// temperature makes it glow (default none; only with `emission`).
    #[serde(default)]
    pub emission_grid: Option<GridDesc>,
}

/// A medium's phase function: `Isotropic` or `HenyeyGreenstein(g: 0.7)`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Default)]
#[serde(deny_unknown_fields, rename = "Phase")]
pub enum PhaseDesc {
    /// Every direction alike.
    #[default]
    Isotropic,
    /// Henyey-Greenstein's, of asymmetry `g` in (-1, 1): forwards for `g > 0`.
    HenyeyGreenstein {
        /// The mean cosine of the scattering angle.
        g: Asymmetry,
    },
}

/// A phase function's asymmetry, in (-1, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Asymmetry(pub f32);

impl<'de> Deserialize<'de> for Asymmetry {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let g = f32::deserialize(d)?;
        match g.abs() < 1.0 {
            true => Ok(Asymmetry(g)),
            false => Err(D::Error::custom(format!("expected an asymmetry g in (-1, 1), found {g}"))),
        }
    }
}

/// The largest extinction a grid medium may reach (`density` times the grid's largest value).
pub const MAX_GRID_EXTINCTION: f32 = 1e7;

/// A voxel grid placed in the object: `(file: "smoke.vol", transform: [..])`. The grid fills
/// the unit cube `[0, 1]^3`, which `transform` (default none) places in the object's space,
/// before the object's own transform.
///
/// An OpenVDB file's grid (`(file: "smoke.vdb", name: "density", transform: [..])`, `name`
/// by default "density") is the dense box over its active voxels, each a cell centred on its
/// index as OpenVDB samples them, placed by the grid's own transform: the grid's world space
/// is the medium's space before `transform`, which places it in the object.
///
/// A `file` with `{frame}` or `{frame:0N}` in it (`smoke_{frame:04}.vdb`, see
/// [`FramePattern`](crate::format::frames::FramePattern)) is a sequence, a file per frame, such
/// as a simulation writes: frame `n` of `pathwave animate` reads the file named for `n`, and
/// `render --time t` the file of the frame that `animate` renders at `t` (frame 0 without
/// `--time`). Within a frame, motion blur included, the grid is that frame's file: there is no
/// interpolation between files. A frame's file is read when the frame is rendered, and only if
/// it is another file than the previous frame's.
#[derive(Debug, Clone, PartialEq)]
pub struct GridDesc {
    /// The file as written (a sequence's pattern).
    pub file: std::path::PathBuf,
    /// The grid's name in an OpenVDB file.
    pub name: Option<String>,
    /// The values.
    pub grid: GridValues,
    /// Transforms applied in order, first to last: for an OpenVDB grid read, where its own
    /// transform puts the unit cube, then those written (a sequence's: those written only,
    /// each frame's file putting its cube first when it is read).
    pub transform: Vec<TransformOp>,
}

/// A grid's values: read with the scene, or a file per frame.
#[derive(Debug, Clone, PartialEq)]
pub enum GridValues {
    /// Read when the scene was loaded.
    Read(Arc<VoxelGrid>),
    /// A file per frame, read by [`GridDesc::at_frame`].
    Frames(Box<GridFrames>),
}

/// A grid as written, before its file's grid is picked.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Grid")]
struct GridFields {
    /// A Mitsuba `.vol` file of 1 or 3 channels or an OpenVDB file, relative to the scene file,
    /// or a pattern of such files numbered by frame.
    file: GridPath,
    /// The grid of an OpenVDB file (default "density").
    #[serde(default)]
    name: Option<String>,
    /// Transforms applied in order, first to last.
    #[serde(default)]
    transform: Vec<TransformOp>,
}

impl<'de> Deserialize<'de> for GridDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let f = GridFields::deserialize(d)?;
        match f.file {
            GridPath::File(file) => {
                let (grid, unit) = file.pick(f.name.as_deref()).map_err(D::Error::custom)?;
                let transform = unit.map(TransformOp).into_iter().chain(f.transform).collect();
                Ok(GridDesc { file: file.path, name: f.name, grid: GridValues::Read(grid), transform })
            }
            GridPath::Frames(frames) => Ok(GridDesc {
                file: frames.written.clone().into(),
                name: f.name,
                grid: GridValues::Frames(Box::new(frames)),
                transform: f.transform,
            }),
        }
    }
}

impl GridDesc {
    /// The grid, placed in the object: `None` for a sequence (see [`Self::at_frame`]).
    pub fn placed(&self) -> Option<crate::media::PlacedGrid> {
        match &self.grid {
            GridValues::Read(grid) => Some(crate::media::PlacedGrid {
                grid: grid.clone(),
                grid_from_object: compose(&self.transform).inverse(),
            }),
            GridValues::Frames(_) => None,
        }
    }

    /// The grid of frame `frame`: a sequence's file for the frame, read (with the hash of its
    /// bytes), as a grid read at load; a grid read at load, as it is.
    pub fn at_frame(&self, frame: u32) -> Result<(GridDesc, Option<InputFile>), String> {
        let GridValues::Frames(frames) = &self.grid else { return Ok((self.clone(), None)) };
        let (file, input) = frames.read(frame)?;
        let (grid, unit) = file
            .pick(self.name.as_deref())
            .map_err(|e| format!("the grid sequence \"{}\": {e}", frames.written))?;
        let transform = unit.map(TransformOp).into_iter().chain(self.transform.iter().cloned()).collect();
        let read =
            GridDesc { file: file.path, name: self.name.clone(), grid: GridValues::Read(grid), transform };
        Ok((read, Some(input)))
    }
}

impl MediumDesc {
    /// The medium it describes: `None` where a grid is a sequence, whose medium is that of a
    /// frame ([`Self::at_frame`]).
    pub fn medium(&self) -> Option<crate::media::Medium> {
        let placed = |g: &Option<GridDesc>| match g {
            None => Some(None),
            Some(g) => g.placed().map(Some),
        };
        Some(self.with_grids([placed(&self.grid)?, placed(&self.albedo_grid)?, placed(&self.emission_grid)?]))
    }

    /// The medium with these grids (density, albedo, emission).
    fn with_grids(
        &self,
        [density_grid, albedo_grid, emission_grid]: [Option<crate::media::PlacedGrid>; 3],
    ) -> crate::media::Medium {
        crate::media::Medium {
            sigma_t: self.density.0,
            albedo: self.albedo.0,
            density_grid,
            albedo_grid,
            g: match self.phase {
                PhaseDesc::Isotropic => 0.0,
                PhaseDesc::HenyeyGreenstein { g } => g.0,
            },
            emission: self.emission.map_or(glam::Vec3::ZERO, |e| e.0),
            emission_grid,
        }
    }

    /// Its grids that are sequences.
    pub fn sequences(&self) -> impl Iterator<Item = &GridFrames> {
        [&self.grid, &self.albedo_grid, &self.emission_grid].into_iter().flatten().filter_map(|g| {
            match &g.grid {
                GridValues::Frames(f) => Some(&**f),
                GridValues::Read(_) => None,
            }
        })
    }

    /// The medium of frame `frame`, its sequences' files for the frame read and checked as
    /// grids read at load are, and the files read, with their hashes.
    pub fn at_frame(&self, frame: u32) -> Result<(crate::media::Medium, Vec<InputFile>), String> {
        let mut read = Vec::new();
        let mut at = |g: &Option<GridDesc>| -> Result<Option<GridDesc>, String> {
            let Some(g) = g else { return Ok(None) };
            let (g, input) = g.at_frame(frame)?;
            read.extend(input);
            Ok(Some(g))
        };
        let m = MediumDesc {
            grid: at(&self.grid)?,
            albedo_grid: at(&self.albedo_grid)?,
            emission_grid: at(&self.emission_grid)?,
            ..self.clone()
        };
        m.check()?;
        let placed = |g: &Option<GridDesc>| g.as_ref().and_then(GridDesc::placed);
        Ok((m.with_grids([placed(&m.grid), placed(&m.albedo_grid), placed(&m.emission_grid)]), read))
    }

    /// Refuses a grid too dense to track through, an albedo grid with values above 1, and an
    /// emission grid without an `emission` or whose values take it beyond
    /// [`crate::format::MAX_EMISSION`] (a sequence's values when a frame is read).
    pub(super) fn check(&self) -> Result<(), String> {
        let values = |g: &Option<GridDesc>| match g {
            Some(GridDesc { file, grid: GridValues::Read(v), .. }) => Some((file.clone(), v.clone())),
            _ => None,
        };
        if let Some((file, grid)) = values(&self.grid) {
            let peak = self.density.0.max_element() * grid.max();
            if !(peak <= MAX_GRID_EXTINCTION) {
                return Err(format!(
                    "`density` times the grid {}'s largest value is {peak}: at most {MAX_GRID_EXTINCTION} (a medium that dense is opaque, and tracking through it would take that many steps per unit length)",
                    file.display()
                ));
            }
        }
        if let Some((file, grid)) = values(&self.albedo_grid) {
            let max = grid.max();
            if max > 1.0 {
                return Err(format!(
                    "the albedo grid {} holds {max}: an albedo grid's values lie in [0, 1]",
                    file.display()
                ));
            }
        }
        if self.emission_grid.is_some() && self.emission.is_none() {
            return Err("an `emission_grid` scales the medium's `emission`: give it an `emission` too".into());
        }
        if let (Some((file, grid)), Some(e)) = (values(&self.emission_grid), self.emission) {
            let peak = e.0.max_element() * grid.max();
            let limit = crate::format::MAX_EMISSION;
            if !(peak <= limit) {
                return Err(format!(
                    "`emission` times the emission grid {}'s largest value is {peak}: at most {limit:e}",
                    file.display()
                ));
            }
        }
        Ok(())
    }
}

/// A medium's extinction: `0.5` (every channel) or `(0.1, 0.9, 0.1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Density(pub glam::Vec3);

impl<'de> Deserialize<'de> for Density {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Density;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a density: a number > 0, or (r, g, b) with each >= 0 and one > 0")
            }
            fn visit_f64<E: Error>(self, x: f64) -> Result<Density, E> {
                let x = x as f32;
                match x.is_finite() && x > 0.0 {
                    true => Ok(Density(glam::Vec3::splat(x))),
                    false => Err(E::custom(format!("expected a density > 0, found {x}"))),
                }
            }
            fn visit_i64<E: Error>(self, x: i64) -> Result<Density, E> {
                self.visit_f64(x as f64)
            }
            fn visit_u64<E: Error>(self, x: u64) -> Result<Density, E> {
                self.visit_f64(x as f64)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Density, A::Error> {
                let mut c = [0.0f32; 3];
                for (i, c) in c.iter_mut().enumerate() {
                    *c = seq.next_element()?.ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f32>()?.is_some() {
                    return Err(A::Error::invalid_length(4, &self));
                }
                let v = glam::Vec3::from(c);
                match v.is_finite() && v.min_element() >= 0.0 && v.max_element() > 0.0 {
                    true => Ok(Density(v)),
                    false => Err(A::Error::custom(format!(
                        "expected a density with components >= 0 and one > 0, found {v}"
                    ))),
                }
            }
        }
        d.deserialize_any(Visit)
    }
}
