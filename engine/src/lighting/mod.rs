//! The lighting layer: [`lights`] holds the light table (area, punctual and sky emitters) and
//! how each is sampled, [`area`] what each material id's surfaces emit, [`punctual`] the registry of the lights a scene lists (their RON forms
//! and their conversion into the table's punctual lights), [`environment`] the environment map,
//! [`distribution`] the piecewise-constant distributions both sample from, [`tree`] the
//! light tree that chooses among many lights by their importance to a point, and
//! [`light_paths`] the lights light tracing emits from and the paths it takes.

pub mod area;
pub mod distribution;
pub mod environment;
pub mod light_paths;
pub mod lights;
pub mod punctual;
pub mod punctual_light;
pub mod tree;
