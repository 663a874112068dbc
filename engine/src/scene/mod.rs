//! The RON scene format: serde types with validation, and the loader that reports
//! `file:line:col: message` for every error.

mod assets;
mod camera;
mod desc;
mod error;
pub mod gltf;
mod light;
mod load;
mod material;
pub mod mitsuba;
mod object;
mod params;
mod ply;
mod serialized;
mod texture;
mod transform;

pub use crate::format::*;
pub use assets::*;
pub use camera::*;
pub use desc::*;
pub use error::SceneError;
pub use light::*;
pub use load::{load, load_with, parse, parse_defines, parse_with};
pub use material::*;
pub use object::*;
pub use ply::parse_ply;
pub use serialized::SerializedFile;
pub use texture::*;
pub use transform::*;
