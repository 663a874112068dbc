//! The RON scene format: serde types with validation, and the loader that reports
//! `file:line:col: message` for every error.

mod desc;
mod error;
pub mod files;
mod load;
mod params;
mod values;

pub use desc::*;
pub use error::SceneError;
pub use load::{load, load_with, parse, parse_defines, parse_with};
pub use values::*;
