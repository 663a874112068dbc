//! The lighting layer: [`lights`] holds the light table (area, punctual and sky emitters) and
//! how each is sampled, [`area`] what each material id's surfaces emit, [`punctual`] the registry of the lights a scene lists (their RON forms
//! and their conversion into the table's punctual lights), [`environment`] the environment map,
//! [`distribution`] the piecewise-constant distributions both sample from, and [`tree`] the
//! light tree that chooses among many lights by their importance to a point.

pub mod area;
pub mod distribution;
pub mod environment;
pub mod lights;
pub mod punctual;
pub mod punctual_light;
pub mod tree;
