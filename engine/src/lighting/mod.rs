//! The lighting layer: [`lights`] holds the light table (area, punctual and sky emitters) and
//! how each is sampled, [`area`] what each material id's surfaces emit, [`punctual`] the registry of the lights a scene lists (their RON forms
//! and their conversion into the table's punctual lights), [`environment`] the environment map,
//! and [`distribution`] the piecewise-constant distributions both sample from.

pub mod area;
pub mod distribution;
pub mod environment;
pub mod lights;
pub mod punctual;
