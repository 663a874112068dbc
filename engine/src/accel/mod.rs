//! The acceleration layer: what answers "which surface does this ray meet first, and is this
//! segment blocked". [`mesh`] holds triangle meshes and their BLAS, [`bvh8`] the 8-wide BVH
//! they and the scene's primitives are traversed with, [`flat`] the flat ray streams small
//! scenes take instead of a tree, [`geometry`] the list of world-space primitives and its
//! queries, and [`instances`] the TLAS over placed meshes. [`queue`] answers a queue of rays
//! at once, choosing among these how to trace them.

pub mod bvh8;
pub mod flat;
pub mod geometry;
pub mod instances;
pub mod mesh;
pub mod queue;
