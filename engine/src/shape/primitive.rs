//! The scene's primitives: every kind the primitive BVH holds, behind one enum whose methods
//! dispatch to the kind's own file. The `primitives!` invocation in the module above is the
//! one list of kinds; a kind is a type implementing [`PrimitiveShape`].

use super::{LightSample, SurfacePoint};
use glam::{Vec2, Vec3A};
use obvhs::aabb::Aabb;

/// What the BVH, the integrators and the light table ask of a shape placed in world space.
pub trait PrimitiveShape: Copy + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// World-space bounds.
    fn aabb(&self) -> Aabb;
    /// Smallest `t` in `(0, tmax)` of the ray `o + t d` (`d` need not be unit length), or
    /// `f32::INFINITY`.
    fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32;
    /// Surface data at a point found by [`Self::intersect`]; texture coordinates that cost
    /// something may be left at zero unless `uv`.
    fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint;
    /// Surface area (an emitter's power is its radiance times its area).
    fn area(&self) -> f32;
    /// A point sampled for next-event estimation from `from`, with its solid-angle density.
    fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample;
    /// The solid-angle density with which [`Self::sample_solid_angle`] from `from` gives the
    /// point `p` (unit normal `n`).
    fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, n: Vec3A) -> f32;
    /// A point uniform over the surface (area density `1 / area`, in `pdf`), where light
    /// tracing emits from it; `None` for kinds that give none (their light is left to the path
    /// tracer).
    fn sample_area(&self, u: Vec2) -> Option<LightSample> {
        let _ = u;
        None
    }
    /// The derivatives `(dp/du, dp/dv)` of the point along the texture coordinates at `sp`:
    /// the tangent of an anisotropic material and the frame of bump and normal maps; `None`
    /// where the kind does not give them (an anisotropic material then takes an arbitrary
    /// tangent about the normal, and maps leave the normal as it is).
    fn derivatives(&self, sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
        let _ = sp;
        None
    }
}

/// Generates [`Primitive`], one variant per kind, and its methods, each a `match` that calls
/// the kind's [`PrimitiveShape`] method.
macro_rules! primitives {
    ($($(#[$attr:meta])* $variant:ident($ty:ty),)+) => {
        /// One primitive of the scene, in world space.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Primitive {
            $($(#[$attr])* #[doc = concat!("A [`", stringify!($ty), "`].")] $variant($ty),)+
        }

        impl Primitive {
            /// World-space bounds.
            pub fn aabb(&self) -> Aabb {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::aabb(s),)+
                }
            }

            /// Smallest `t` in `(0, tmax)` or `f32::INFINITY`.
            #[inline]
            pub fn intersect(&self, o: Vec3A, d: Vec3A, tmax: f32) -> f32 {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::intersect(s, o, d, tmax),)+
                }
            }

            /// Surface data at a point found by [`Self::intersect`]; spheres leave their
            /// texture coordinates at zero unless `uv` (quads and triangles have theirs for
            /// free).
            #[inline(always)]
            pub fn surface(&self, p: Vec3A, uv: bool) -> SurfacePoint {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::surface(s, p, uv),)+
                }
            }

            /// Surface area.
            pub fn area(&self) -> f32 {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::area(s),)+
                }
            }

            /// See [`PrimitiveShape::sample_solid_angle`].
            #[inline]
            pub fn sample_solid_angle(&self, from: Vec3A, u: Vec2) -> LightSample {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::sample_solid_angle(s, from, u),)+
                }
            }

            /// See [`PrimitiveShape::sample_area`].
            pub fn sample_area(&self, u: Vec2) -> Option<LightSample> {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::sample_area(s, u),)+
                }
            }

            /// See [`PrimitiveShape::derivatives`].
            pub fn derivatives(&self, sp: &SurfacePoint) -> Option<(Vec3A, Vec3A)> {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::derivatives(s, sp),)+
                }
            }

            /// See [`PrimitiveShape::pdf_solid_angle`].
            #[inline]
            pub fn pdf_solid_angle(&self, from: Vec3A, p: Vec3A, n: Vec3A) -> f32 {
                match self {
                    $($(#[$attr])* Primitive::$variant(s) => PrimitiveShape::pdf_solid_angle(s, from, p, n),)+
                }
            }
        }

        $($(#[$attr])*
        impl From<$ty> for Primitive {
            fn from(s: $ty) -> Self {
                Primitive::$variant(s)
            }
        })+
    };
}
pub(super) use primitives;
