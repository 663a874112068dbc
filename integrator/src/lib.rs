//! pathwave's integrators: how materials scatter light, samplers, the film, and the reference
//! (megakernel) path tracer that the wavefront integrator is tested against.
#![warn(missing_docs)]

pub mod aov;
pub mod denoise;
pub mod film;
pub mod lambert_vertex;
pub mod light_lanes;
pub mod material;
pub mod oracle;
pub mod path;
pub mod sampler;
pub mod tile;
pub mod wavefront;
