//! The lighting layer: [`lights`] holds the light table (area, punctual and sky emitters) and
//! how each is sampled, [`environment`] the environment map, and [`distribution`] the
//! piecewise-constant distributions both sample from.

pub mod distribution;
pub mod environment;
pub mod lights;
