//! Light tracing's division of the paths ([`pathwave_engine::lighting::light_paths`]): which
//! of a path's light samples and emitter hits the light tracer counts instead.

use super::{LightPick, PathState, tilted};
use pathwave_engine::lighting::light_paths::VertexClass;
use pathwave_engine::render_scene::RenderScene;
use pathwave_engine::shape::SurfacePoint;

/// Light tracing's division of the paths ([`pathwave_engine::lighting::light_paths`]) at a
/// surface vertex at `sp` of class `class` (`LightPaths::class`), in scenes where it is on. A path whose first vertex is
/// rough, whose later ones are all rough or sharp, and whose last vertex before a punctual
/// light is sharp is the light tracer's: a punctual light sampled at such a vertex
/// (`st.traced_here`) is left out (`shade_glossy`). A vertex after the first whose normal a
/// bump or normal map tilted counts as neither rough nor sharp (the tilt may depend on the
/// direction the path arrived from, which a light path does not know there). Null crossings
/// are no vertices of either.
#[inline]
pub fn divide_for_light_paths(st: &mut PathState, class: VertexClass, sp: &SurfacePoint) {
    if st.bounces() == 0 {
        (st.caustic, st.traced_here) = (class == VertexClass::Rough, false);
        return;
    }
    st.caustic = st.caustic && class != VertexClass::Other && !tilted(sp);
    st.traced_here = st.caustic && class == VertexClass::Sharp;
}

/// Whether the light sample `lp` at a vertex of the path `st` ends a path the light tracer
/// counts ([`divide_for_light_paths`]): one of a light it emits from, at a sharp vertex of a
/// caustic's path.
#[inline(always)]
pub(crate) fn light_traced(scene: &RenderScene, st: &PathState, lp: &LightPick) -> bool {
    st.traced_here && scene.light_paths.as_deref().is_some_and(|t| t.traces(lp.light))
}

/// Whether primitive `prim` is a light light tracing emits from (out of line: a scene without
/// light tracing never asks).
#[inline(never)]
pub(crate) fn emitter_traced(scene: &RenderScene, prim: u32) -> bool {
    let light = scene.lights.light_of_prim.get(prim as usize).copied();
    scene.light_paths.as_deref().zip(light).is_some_and(|(t, l)| t.traces(l))
}
