//! pathwave's integrators: the per-vertex steps of a path, samplers, the film, the wavefront
//! integrator and the reference (megakernel) path tracer it is tested against. How each
//! material scatters light is the engine's (`pathwave_engine::material`).
#![warn(missing_docs)]

pub mod aov;
pub mod costs;
pub mod delta_lanes;
pub mod denoise;
pub mod diagnose;
pub mod film;
pub mod glossy_lanes;
pub mod guide_training;
pub mod guided;
pub mod lambert_vertex;
pub mod light_lanes;
pub mod light_tracer;
pub mod metal_lanes;
pub mod oracle;
pub mod path;
mod plain;
pub mod plastic_lanes;
pub mod principled_lanes;
pub mod sampler;
pub mod tile;
pub mod wavefront;
