//! Next-event estimation's light samples for [`LANES`] shading points at once: what
//! `path::pick_light` computes for each, with the same operations in the same order (so the
//! same bits), run as branch-free kernels across lanes for the lanes whose picked light is a
//! quad, a sphere or an ellipsoid ([`LightTable::plain`](pathwave_engine::lighting::lights::LightTable::plain):
//! scenes without motion) in a scene without textures. Points close enough to a
//! rectangle for its spherical-rectangle sampling, points inside a sphere light, lanes that
//! picked another kind of light, and every point of other scenes take `path::pick_light`
//! itself.

use crate::lambert_vertex::{LANES, LambertInLanes, VertexSamplesLanes, lanes};
use crate::path;
use crate::plain::{dot, sel3};
use glam::{Vec2, Vec3, Vec3A};
use pathwave_engine::lighting::lights::{OtherLight, PlainLight};
use pathwave_engine::lighting::punctual_light::{PunctualLight, SpotFalloff, smoothstep, toward};
use pathwave_engine::render_scene::{Background, RenderScene};
use pathwave_engine::shape::{
    EllipsoidLight, QuadLight, SPHERICAL_MIN_ESTIMATE, SphereLight, cone_sample, ellipsoid_sample,
};

/// Samples the lights for groups of [`LANES`] shading points; one per shading loop.
pub struct LightSampler<'a> {
    scene: &'a RenderScene,
    /// The lights as plain numbers, when the lanes can sample some of them.
    plain: Option<&'a [PlainLight]>,
    /// The background's bottom and top radiance when it is a constant or sky sampled as a
    /// light (then the only light).
    sky: Option<(Vec3, Vec3)>,
    /// The quad kernel's inputs; with one quad light, its fields stay filled in from one group
    /// to the next.
    ins: QuadInLanes,
    /// The sphere and ellipsoid kernels' inputs.
    sphere_ins: SphereInLanes,
    ellipsoid_ins: EllipsoidInLanes,
    /// What the kernel that ran last wrote.
    outs: LightOutLanes,
    /// Per kernel (quad, sphere, ellipsoid) and lane, the light whose data its inputs hold
    /// (`u32::MAX`: none yet): a lane that picks the same light again keeps them.
    held: [[u32; LANES]; 3],
}

impl<'a> LightSampler<'a> {
    /// A sampler for `scene`'s lights.
    pub fn new(scene: &'a RenderScene) -> Self {
        let plain = &scene.lights.plain;
        let lanes = !scene.features.textures && plain.iter().any(|l| !matches!(l, PlainLight::Other));
        let plain = lanes.then_some(plain.as_slice());
        let sky = match scene.background {
            _ if scene.lights.environment.is_none() => None,
            Background::Constant(c) => Some((c, c)),
            Background::Sky { bottom, top } => Some((bottom, top)),
            Background::Environment(_) => None,
        };
        let mut me = Self {
            scene,
            plain,
            sky,
            ins: QuadInLanes::default(),
            outs: LightOutLanes::default(),
            sphere_ins: SphereInLanes::default(),
            ellipsoid_ins: EllipsoidInLanes::default(),
            held: [[u32::MAX; LANES]; 3],
        };
        if let Some([PlainLight::Quad(one)]) = plain {
            let pmf = scene.lights.pick(0.0, glam::Vec3A::ZERO, glam::Vec3A::ZERO).1;
            for l in 0..LANES {
                me.ins.hold(l, one);
                me.ins.pmf[l] = pmf;
            }
        }
        me
    }

    /// Sets the light sample fields (`wi`, `le`, `pdf_light`, `delta_light`, `target`) of every
    /// lane of `out` for its shading points (`out.p`), at the paths' `time`, with their numbers
    /// `u`: zero where there is none (no lights, or a light that sends nothing towards the
    /// point).
    #[inline]
    pub fn sample(&mut self, time: &[f32; LANES], u: &VertexSamplesLanes, out: &mut LambertInLanes) {
        let scene = self.scene;
        let from = out.p;
        let scalar = |out: &mut LambertInLanes, picked: (usize, f32), l: usize| {
            let p = Vec3::new(from[0][l], from[1][l], from[2][l]);
            let lp = path::sample_light(scene, picked, p.into(), time[l], u.get(l).light);
            let (wi, le, pdf, target, delta): (Vec3, Vec3, f32, Vec3, bool) =
                lp.map_or(Default::default(), |lp| (lp.wi.into(), lp.le, lp.pdf, lp.target.into(), lp.delta));
            for a in 0..3 {
                (out.wi[a][l], out.le[a][l], out.target[a][l]) = (wi[a], le[a], target[a]);
            }
            (out.pdf_light[l], out.delta_light[l]) = (pdf, delta);
        };
        if scene.lights.is_empty() {
            (out.wi, out.le, out.pdf_light, out.delta_light, out.target) = Default::default();
            return;
        }
        if let Some((bottom, top)) = self.sky {
            let lights = &scene.lights;
            let pmf = lights.pick(0.0, glam::Vec3A::ZERO, glam::Vec3A::ZERO).1;
            let (center, radius) = (Vec3::from(lights.center), lights.radius);
            let ins = SkyInLanes { from, uv: u.light };
            sky_lanes(&ins, bottom, top, pmf, center, radius, out);
            return;
        }
        let Some(plain) = self.plain else {
            let picks = scene.lights.pick_lanes(&u.light_pick, &from, &out.n);
            (0..LANES).for_each(|l| scalar(out, picks[l], l));
            return;
        };
        // Which kernel each lane takes; lanes whose light is of none of their kinds go to
        // `sample_light`. With one quad light its data stay in the quad kernel's inputs.
        let mut kind = [Kind::Other; LANES];
        let mut picks = [(0, 0.0); LANES];
        if let [PlainLight::Quad(_)] = plain {
            kind = [Kind::Quad; LANES];
        } else {
            picks = scene.lights.pick_lanes(&u.light_pick, &from, &out.n);
            for l in 0..LANES {
                let (light, pmf) = picks[l];
                let id = light as u32;
                // The light's data stay while the lane picks it again; its probability, which
                // the tree makes depend on the point, is set each time.
                kind[l] = match &plain[light] {
                    PlainLight::Quad(q) => {
                        if std::mem::replace(&mut self.held[0][l], id) != id {
                            self.ins.hold(l, q);
                        }
                        self.ins.pmf[l] = pmf;
                        Kind::Quad
                    }
                    PlainLight::Sphere(s) => {
                        if std::mem::replace(&mut self.held[1][l], id) != id {
                            self.sphere_ins.hold(l, s);
                        }
                        self.sphere_ins.pmf[l] = pmf;
                        Kind::Sphere
                    }
                    PlainLight::Ellipsoid(e) => {
                        if std::mem::replace(&mut self.held[2][l], id) != id {
                            self.ellipsoid_ins.hold(l, e);
                        }
                        self.ellipsoid_ins.pmf[l] = pmf;
                        Kind::Ellipsoid
                    }
                    PlainLight::Other => Kind::Other,
                };
            }
        }
        let uv = u.light;
        let mut done = [false; LANES];
        if kind.contains(&Kind::Quad) {
            (self.ins.from, self.ins.uv) = (from, uv);
            quads_by_area_lanes(&self.ins, &mut self.outs);
            self.outs.write(Kind::Quad, &kind, out, &mut done);
        }
        if kind.contains(&Kind::Sphere) {
            (self.sphere_ins.from, self.sphere_ins.uv) = (from, uv);
            spheres_by_cone_lanes(&self.sphere_ins, &mut self.outs);
            self.outs.write(Kind::Sphere, &kind, out, &mut done);
        }
        if kind.contains(&Kind::Ellipsoid) {
            (self.ellipsoid_ins.from, self.ellipsoid_ins.uv) = (from, uv);
            ellipsoids_by_area_lanes(&self.ellipsoid_ins, &mut self.outs);
            self.outs.write(Kind::Ellipsoid, &kind, out, &mut done);
        }
        out.delta_light = [false; LANES];
        for l in (0..LANES).filter(|&l| !done[l]) {
            // With one quad light the lanes did not pick.
            let picked = match plain {
                [PlainLight::Quad(_)] => {
                    let p = glam::Vec3A::new(from[0][l], from[1][l], from[2][l]);
                    let n = glam::Vec3A::new(out.n[0][l], out.n[1][l], out.n[2][l]);
                    scene.lights.pick(u.light_pick[l], p, n)
                }
                _ => picks[l],
            };
            scalar(out, picked, l);
        }
    }
}

/// Holds a light in a lane of a kernel's inputs (the engine's light as it is, one array per
/// field).
macro_rules! hold {
    ($($lanes:ident: $light:ident),*) => {$(
        impl $lanes {
            /// Lane `l` takes `light`.
            #[inline]
            fn hold(&mut self, l: usize, light: &$light) {
                self.light.set(l, light);
            }
        }
    )*};
}

hold!(QuadInLanes: QuadLight, SphereInLanes: SphereLight, EllipsoidInLanes: EllipsoidLight);

/// The kind of light a lane picked, and so the kernel that samples it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Quad,
    Sphere,
    Ellipsoid,
    /// Another kind: `path::pick_light`.
    Other,
}

impl LightOutLanes {
    /// Copies the samples of the lanes of kind `k` to `out` and marks them `done`, except
    /// those the kernel left to `pick_light`.
    #[inline]
    fn write(&self, k: Kind, kind: &[Kind; LANES], out: &mut LambertInLanes, done: &mut [bool; LANES]) {
        // Selects over all lanes as bit masks, not a loop over the chosen ones: it vectorises.
        // (`if take { a } else { b }` on array elements became a select of the two addresses
        // and a scalar load per lane.)
        let mut take = [0u32; LANES];
        for l in 0..LANES {
            take[l] = 0u32.wrapping_sub(((kind[l] == k) & !self.scalar[l]) as u32);
        }
        let pick = |new: &[f32; LANES], old: &mut [f32; LANES]| {
            for l in 0..LANES {
                old[l] = f32::from_bits(new[l].to_bits() & take[l] | old[l].to_bits() & !take[l]);
            }
        };
        for a in 0..3 {
            pick(&self.wi[a], &mut out.wi[a]);
            pick(&self.le[a], &mut out.le[a]);
            pick(&self.target[a], &mut out.target[a]);
        }
        pick(&self.pdf, &mut out.pdf_light);
        for l in 0..LANES {
            done[l] |= take[l] != 0;
        }
    }
}

/// What [`sky_lanes`] reads per lane: the shading point and the two numbers.
#[derive(Clone, Copy, Debug, Default)]
struct SkyIn {
    from: Vec3,
    uv: [f32; 2],
}

lanes!(SkyInLanes for SkyIn { from: v3, uv: f2 });

/// The light samples of a constant or sky background alone in the light table, as
/// `path::pick_light` takes them (`Background::smooth_sample`, the choice's `pmf`, a target
/// beyond the sphere of `center` and `radius` that holds the scene), branch-free.
#[inline(never)]
fn sky_lanes(
    i: &SkyInLanes,
    bottom: Vec3,
    top: Vec3,
    pmf: f32,
    center: Vec3,
    radius: f32,
    out: &mut LambertInLanes,
) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            for l in 0..LANES {
                let SkyIn { from, uv } = i.get(l);
                let (wi, le, pdf) = Background::smooth_sample_lane(bottom, top, uv);
                let pdf = pdf * pmf;
                let ok = (le.x != 0.0 || le.y != 0.0 || le.z != 0.0) && pdf > 0.0;
                // `LightTable::beyond`.
                let c = Vec3::new(from.x - center.x, from.y - center.y, from.z - center.z);
                let s = 2.0 * (dot(c, c).sqrt() + radius) + 1.0;
                let target = Vec3::new(from.x + wi.x * s, from.y + wi.y * s, from.z + wi.z * s);
                for a in 0..3 {
                    out.wi[a][l] = if ok { wi[a] } else { 0.0 };
                    out.le[a][l] = if ok { le[a] } else { 0.0 };
                    out.target[a][l] = if ok { target[a] } else { 0.0 };
                }
                out.pdf_light[l] = if ok { pdf } else { 0.0 };
                out.delta_light[l] = false;
            }
        },
    )
}

/// What [`quad_by_area`] reads: the lane's light, its pick probability, the shading point and
/// the two numbers.
#[derive(Clone, Copy, Debug)]
struct QuadIn {
    light: QuadLight,
    pmf: f32,
    from: Vec3,
    uv: [f32; 2],
}

/// What the kernels write: the light sample (zero when the light sends nothing), or `scalar`
/// when the lane takes `path::pick_light` instead (a point the quad samples by spherical
/// rectangle, or one inside a sphere).
#[derive(Clone, Copy, Debug, Default)]
struct LightOut {
    wi: Vec3,
    le: Vec3,
    pdf: f32,
    target: Vec3,
    scalar: bool,
}

lanes!(QuadLightLanes for QuadLight {
    q: f3, u: f3, v: f3, n: f3, center: f3, area: f32, inv_area: f32, err: f32, rect: bool, emit: f3,
    two_sided: bool,
});

lanes!(QuadInLanes for QuadIn { light: (lanes QuadLightLanes), pmf: f32, from: v3, uv: f2 });

lanes!(LightOutLanes for LightOut { wi: v3, le: v3, pdf: f32, target: v3, scalar: bool });

/// [`quad_by_area`] on all lanes.
#[inline(never)]
fn quads_by_area_lanes(i: &QuadInLanes, o: &mut LightOutLanes) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            for l in 0..LANES {
                o.set(l, &quad_by_area(&i.get(l)));
            }
        },
    )
}

/// A point of the quad sampled by area as `Quad::sample_solid_angle` and `LightTable::sample`
/// do, and what `path::pick_light` derives from it, branch-free.
#[inline(always)]
fn quad_by_area(i: &QuadIn) -> LightOut {
    let (from, light) = (i.from, &i.light);
    let (q, u, v, n) = (Vec3::from(light.q), Vec3::from(light.u), Vec3::from(light.v), Vec3::from(light.n));
    let (center, emit) = (Vec3::from(light.center), Vec3::from(light.emit));
    // `Quad::spherical`'s bound, from the quad's centre.
    let c = Vec3::new(center.x - from.x, center.y - from.y, center.z - from.z);
    let d2 = dot(c, c);
    let spherical = light.rect && !(light.area * dot(n, c).abs() < SPHERICAL_MIN_ESTIMATE * d2 * d2.sqrt());
    // The point (`+ 0.0`: the light's zero motion offset that `LightTable::sample` adds) and
    // its density by area, in solid angle.
    let [a, b] = i.uv;
    let lp = Vec3::new(
        q.x + a * u.x + b * v.x + 0.0,
        q.y + a * u.y + b * v.y + 0.0,
        q.z + a * u.z + b * v.z + 0.0,
    );
    let d = Vec3::new(lp.x - from.x, lp.y - from.y, lp.z - from.z);
    let dist2 = dot(d, d);
    let dist = dist2.sqrt();
    let cos = (dot(n, d) / dist).abs();
    let pdf_area = if cos <= 0.0 { 0.0 } else { light.inv_area * dist2 / cos };
    light_out(lp, n, pdf_area, light.err, emit, light.two_sided, i.pmf, from, spherical)
}

/// What [`sphere_by_cone`] reads: the lane's light, its pick probability, the shading point
/// and the two numbers.
#[derive(Clone, Copy, Debug)]
struct SphereIn {
    light: SphereLight,
    pmf: f32,
    from: Vec3,
    uv: [f32; 2],
}

lanes!(SphereLightLanes for SphereLight { center: f3, radius: f32, err: f32, emit: f3, two_sided: bool });

lanes!(SphereInLanes for SphereIn { light: (lanes SphereLightLanes), pmf: f32, from: v3, uv: f2 });

/// [`sphere_by_cone`] on all lanes.
#[inline(never)]
fn spheres_by_cone_lanes(i: &SphereInLanes, o: &mut LightOutLanes) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            for l in 0..LANES {
                o.set(l, &sphere_by_cone(&i.get(l)));
            }
        },
    )
}

/// A point of the sphere sampled in the cone it subtends as `Sphere::sample_solid_angle` and
/// `LightTable::sample` do, and what `path::pick_light` derives from it, branch-free.
#[inline(always)]
fn sphere_by_cone(i: &SphereIn) -> LightOut {
    let (from, light) = (i.from, &i.light);
    let (center, radius) = (Vec3::from(light.center), light.radius);
    let (n, pdf_cone, inside) = cone_sample(light.center, radius, from.to_array(), i.uv);
    let n = Vec3::from(n);
    // The point (`+ 0.0`: the light's zero motion offset that `LightTable::sample` adds).
    let lp = Vec3::new(
        center.x + radius * n.x + 0.0,
        center.y + radius * n.y + 0.0,
        center.z + radius * n.z + 0.0,
    );
    light_out(lp, n, pdf_cone, light.err, light.emit.into(), light.two_sided, i.pmf, from, inside)
}

/// [`path::seen_from`] of a light emitting `emit` (on both sides if `two_sided`), zero where
/// the sample does not count; `scalar` passes through.
#[expect(
    clippy::too_many_arguments,
    reason = "a light sample's parts, each a value the lane loop holds in registers"
)]
#[inline(always)]
fn light_out(
    lp: Vec3,
    n: Vec3,
    pdf_solid: f32,
    err: f32,
    emit: Vec3,
    two_sided: bool,
    pmf: f32,
    from: Vec3,
    scalar: bool,
) -> LightOut {
    let emitted = |cos: f32| sel3(two_sided || cos > 0.0, emit, Vec3::ZERO);
    let s = path::seen_from(lp, n, pdf_solid, err, pmf, from, emitted);
    LightOut {
        wi: sel3(s.ok, s.wi, Vec3::ZERO),
        le: sel3(s.ok, s.le, Vec3::ZERO),
        pdf: if s.ok { s.pdf } else { 0.0 },
        target: sel3(s.ok, s.target, Vec3::ZERO),
        scalar,
    }
}

/// What [`ellipsoid_by_area`] reads: the lane's light, its pick probability, the shading point
/// and the two numbers.
#[derive(Clone, Copy, Debug)]
struct EllipsoidIn {
    light: EllipsoidLight,
    pmf: f32,
    from: Vec3,
    uv: [f32; 2],
}

lanes!(EllipsoidLightLanes for EllipsoidLight {
    center: f3, radius: f32, world: [f3; 4], normal: [f3; 3], det: f32, scale: f32, shift: f32,
    sphere_err: f32, emit: f3, two_sided: bool,
});

lanes!(EllipsoidInLanes for EllipsoidIn { light: (lanes EllipsoidLightLanes), pmf: f32, from: v3, uv: f2 });

/// [`ellipsoid_by_area`] on all lanes.
#[inline(never)]
fn ellipsoids_by_area_lanes(i: &EllipsoidInLanes, o: &mut LightOutLanes) {
    pathwave_engine::simd::lanes(
        #[inline(always)]
        || {
            for l in 0..LANES {
                o.set(l, &ellipsoid_by_area(&i.get(l)));
            }
        },
    )
}

/// A point of the ellipsoid sampled by the area of its sphere as
/// `TransformedSphere::sample_solid_angle` and `LightTable::sample` do, and what
/// `path::pick_light` derives from it, branch-free.
#[inline(always)]
fn ellipsoid_by_area(i: &EllipsoidIn) -> LightOut {
    let light = &i.light;
    let (p, n, pdf, err) = ellipsoid_sample(light, i.from.to_array(), i.uv);
    // `+ 0.0`: the light's zero motion offset that `LightTable::sample` adds.
    let lp = Vec3::new(p[0] + 0.0, p[1] + 0.0, p[2] + 0.0);
    light_out(lp, n.into(), pdf, err, light.emit.into(), light.two_sided, i.pmf, i.from, false)
}

/// [`path::sample_light`] for [`LANES`] points `from` at once, with each lane's pick, time and
/// numbers (lanes not `active` give `None`): the picks of point lights and of spots with the
/// smooth falloff and no texture (the glTF scenes' punctual lights) across the lanes, the others
/// one by one. A lane's sample has [`path::sample_light`]'s bits, the same operations in the same
/// order (`punctual_lanes_give_the_bits_of_sample_light`). One by one, a spot's square root and
/// three divisions waited on one another: 6% of the glTF shot's time in `pick_other`.
pub(crate) fn sample_lights_lanes(
    scene: &RenderScene,
    picks: &[(usize, f32); LANES],
    active: &[bool; LANES],
    from: &[[f32; LANES]; 3],
    time: &[f32; LANES],
    u: &[Vec2; LANES],
) -> [Option<path::LightPick>; LANES] {
    let mut out: [Option<path::LightPick>; LANES] = std::array::from_fn(|_| None);
    let point = |l: usize| Vec3A::new(from[0][l], from[1][l], from[2][l]);
    let mut i = PunctualLanes { from: *from, ..Default::default() };
    let mut taken = [false; LANES];
    for l in (0..LANES).filter(|&l| active[l]) {
        let (position, axis, intensity, cone) = match scene.lights.other(picks[l].0) {
            Some(&OtherLight::Punctual(PunctualLight::Point { position, intensity })) => {
                (position, Vec3A::ZERO, intensity, None)
            }
            Some(&OtherLight::Punctual(PunctualLight::Spot {
                position,
                axis,
                intensity,
                cos_falloff,
                cos_total,
                falloff: SpotFalloff::Smoothstep,
                texture: None,
            })) => (position, axis, intensity, Some((cos_total, cos_falloff))),
            _ => {
                out[l] = path::sample_light(scene, picks[l], point(l), time[l], u[l]);
                continue;
            }
        };
        taken[l] = true;
        for c in 0..3 {
            (i.position[c][l], i.axis[c][l], i.intensity[c][l]) = (position[c], axis[c], intensity[c]);
        }
        (i.spot[l], (i.cos_total[l], i.cos_falloff[l])) = (cone.is_some(), cone.unwrap_or((0.0, 0.0)));
    }
    if !taken.contains(&true) {
        return out;
    }
    let o = pathwave_engine::simd::lanes(
        #[inline(always)]
        || punctual_lanes(&i),
    );
    for l in (0..LANES).filter(|&l| taken[l]) {
        let (wi, le, d) = (
            Vec3A::new(o.wi[0][l], o.wi[1][l], o.wi[2][l]),
            Vec3::new(o.le[0][l], o.le[1][l], o.le[2][l]),
            o.d[l],
        );
        let pmf = picks[l].1;
        if le == Vec3::ZERO || !(d > 0.0) || !(pmf > 0.0) {
            continue;
        }
        let (target, light) = (point(l) + wi * d, picks[l].0 as u32);
        out[l] = Some(path::LightPick { wi, le, pdf: pmf, target, delta: true, light });
    }
    out
}

/// Point lights and smooth spots seen from a point per lane ([`sample_lights_lanes`]).
#[derive(Default)]
struct PunctualLanes {
    position: [[f32; LANES]; 3],
    /// The spot's axis (zero for a point light).
    axis: [[f32; LANES]; 3],
    intensity: [[f32; LANES]; 3],
    from: [[f32; LANES]; 3],
    spot: [bool; LANES],
    cos_total: [f32; LANES],
    cos_falloff: [f32; LANES],
}

/// What [`PunctualLanes`] give: the unit direction to the light, the distance and
/// [`PunctualLight::illuminate`]'s radiance-like factor.
#[derive(Default)]
struct PunctualOut {
    wi: [[f32; LANES]; 3],
    d: [f32; LANES],
    le: [[f32; LANES]; 3],
}

/// [`PunctualLight::illuminate`] of a point light or a smooth spot without texture, across
/// lanes: its own definitions (`punctual_light::toward`, `smoothstep`) lane by lane.
#[inline(always)]
fn punctual_lanes(i: &PunctualLanes) -> PunctualOut {
    let mut o = PunctualOut::default();
    for l in 0..LANES {
        let at = |a: &[[f32; LANES]; 3]| [a[0][l], a[1][l], a[2][l]];
        let (wi, d, d2, cos) = toward(at(&i.position), at(&i.from), at(&i.axis));
        let spot = smoothstep(i.cos_total[l], i.cos_falloff[l], cos) / d2;
        for c in 0..3 {
            o.wi[c][l] = wi[c];
            o.le[c][l] = if i.spot[l] { i.intensity[c][l] * spot } else { i.intensity[c][l] / d2 };
        }
        o.d[l] = d;
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::Stream;
    use pathwave_engine::scene::parse;
    use pathwave_engine::world::SceneWorld;

    /// Three quad lights of different power (a rectangle, a two-sided rectangle and a
    /// parallelogram) in a box, chosen by the light tree (`Auto` with more than one light).
    const LIGHTS: &str = r#"Scene(
        camera: (look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 40),
        render: (width: 8, height: 8),
        materials: {
            "white": Lambertian(albedo: (0.7, 0.7, 0.7)),
            "a": DiffuseLight(emit: (10, 10, 10)),
            "b": DiffuseLight(emit: (2, 3, 4), two_sided: true),
            "c": DiffuseLight(emit: (1, 0, 0)),
        },
        objects: [
            (shape: Quad(q: (-2, -2, 2), u: (4, 0, 0), v: (0, 4, 0)), material: "white"),
            (shape: Quad(q: (-0.5, 1.9, -0.5), u: (1, 0, 0), v: (0, 0, 1)), material: "a"),
            (shape: Quad(q: (1, -1, 0), u: (0, 1, 0), v: (0, 0, 0.5)), material: "b"),
            (shape: Quad(q: (-1.5, -1.9, 0), u: (1, 0, 0.2), v: (0.3, 0, 1)), material: "c"),
        ],
    )"#;

    #[test]
    fn lanes_give_the_bits_of_pick_light() {
        check_against_pick_light(LIGHTS, (3, 0, 0));
        // One light: its data stay in the lanes from one group to the next.
        let one = LIGHTS
            .replace(r#"material: "b""#, r#"material: "white""#)
            .replace(r#"material: "c""#, r#"material: "white""#);
        check_against_pick_light(&one, (1, 0, 0));
        // A sphere light among quads: its lanes take the sphere kernel (points inside it
        // `pick_light`).
        let sphere = LIGHTS.replace(
            r#"Quad(q: (-1.5, -1.9, 0), u: (1, 0, 0.2), v: (0.3, 0, 1))"#,
            r#"Sphere(center: (-1, -1.5, 0.5), radius: 0.3)"#,
        );
        check_against_pick_light(&sphere, (2, 1, 0));
        // Sphere lights alone, one two-sided, one large enough to hold many of the points,
        // and one so small that its cones take the Taylor expansion.
        let spheres = sphere
            .replace(
                r#"Quad(q: (-0.5, 1.9, -0.5), u: (1, 0, 0), v: (0, 0, 1))"#,
                r#"Sphere(center: (0.5, 1.2, 0), radius: 0.8)"#,
            )
            .replace(
                r#"Quad(q: (1, -1, 0), u: (0, 1, 0), v: (0, 0, 0.5))"#,
                r#"Sphere(center: (1.5, -1, 1), radius: 0.01)"#,
            );
        check_against_pick_light(&spheres, (0, 3, 0));
        // Ellipsoid lights (a sheared one and a squashed one) beside a quad.
        let ellipsoids = sphere
            .replace(
                r#"(shape: Quad(q: (1, -1, 0), u: (0, 1, 0), v: (0, 0, 0.5)), material: "b"),"#,
                r#"(shape: Sphere(center: (0, 0, 0), radius: 0.3), material: "b",
                    transform: [Scale((1, 2, 0.5)), Shear(xy: 0.4), RotateY(30), Translate((1, -1, 0.5))]),"#,
            )
            .replace(
                r#"(shape: Sphere(center: (-1, -1.5, 0.5), radius: 0.3), material: "c"),"#,
                r#"(shape: Sphere(center: (0, 0, 0), radius: 0.4), material: "c",
                    transform: [Scale((2, 0.3, 1)), Translate((-1, -1.5, 0.5))]),"#,
            );
        check_against_pick_light(&ellipsoids, (1, 0, 2));
    }

    /// A sky alone is sampled as a light, across lanes, with the bits of `pick_light`.
    #[test]
    fn sky_lanes_give_the_bits_of_pick_light() {
        let sky = LIGHTS
            .replace(
                r#""a": DiffuseLight(emit: (10, 10, 10))"#,
                r#""a": Lambertian(albedo: (0.5, 0.5, 0.5))"#,
            )
            .replace(
                r#""b": DiffuseLight(emit: (2, 3, 4), two_sided: true)"#,
                r#""b": Lambertian(albedo: (0.5, 0.5, 0.5))"#,
            )
            .replace(r#""c": DiffuseLight(emit: (1, 0, 0))"#, r#""c": Lambertian(albedo: (0.5, 0.5, 0.5))"#)
            .replace(
                "render: (width: 8, height: 8),",
                "render: (width: 8, height: 8),\n background: Sky(bottom: (1, 1, 1), top: (0.5, 0.7, 1)),",
            );
        check_against_pick_light(&sky, (0, 0, 0));
    }

    /// Compares the lanes with `pick_light` in the scene `text`, which has `kinds` (quad,
    /// sphere, ellipsoid) lights.
    fn check_against_pick_light(text: &str, kinds: (usize, usize, usize)) {
        let (lights, spheres_wanted, ellipsoids_wanted) = kinds;
        let desc = parse(text, std::path::Path::new("<test>")).unwrap();
        let scene = SceneWorld::render_scene(&desc);
        let quads = scene.lights.plain.iter().filter(|l| matches!(l, PlainLight::Quad(_))).count();
        assert_eq!(quads, lights, "the quad lights");
        assert_eq!(scene.lights.tree.is_some(), scene.lights.len() > 1, "the tree chooses among several");
        let mut rng = Stream::new(11);
        let mut sampler = LightSampler::new(&scene);
        let (mut lit, mut spherical) = (0, 0);
        for _ in 0..4000 {
            // Points anywhere in the box, some of them close to a light.
            let p: [Vec3; LANES] = std::array::from_fn(|_| {
                let near = rng.next_1d() < 0.3;
                let s = if near { 0.3 } else { 2.0 };
                let c = if near { Vec3::new(0.0, 1.7, 0.0) } else { Vec3::ZERO };
                c + s * Vec3::new(
                    rng.next_1d() * 2.0 - 1.0,
                    rng.next_1d() * 2.0 - 1.0,
                    rng.next_1d() * 2.0 - 1.0,
                )
            });
            let mut u = VertexSamplesLanes::default();
            for l in 0..LANES {
                u.light_pick[l] = rng.next_1d();
                (u.light[0][l], u.light[1][l]) = (rng.next_1d(), rng.next_1d());
            }
            // Surfaces facing every way, and points in a medium (no normal): the light tree
            // weighs the lights by the normal.
            let n: [Vec3; LANES] = std::array::from_fn(|l| match l % 4 {
                0 => Vec3::ZERO,
                _ => Vec3::new(rng.next_1d() - 0.5, rng.next_1d() - 0.5, rng.next_1d() - 0.5).normalize(),
            });
            let mut got = LambertInLanes::default();
            for l in 0..LANES {
                (got.p[0][l], got.p[1][l], got.p[2][l]) = (p[l].x, p[l].y, p[l].z);
                (got.n[0][l], got.n[1][l], got.n[2][l]) = (n[l].x, n[l].y, n[l].z);
            }
            sampler.sample(&[0.0; LANES], &u, &mut got);
            for l in 0..LANES {
                let u = u.get(l);
                let want = path::pick_light(&scene, p[l].into(), n[l].into(), 0.0, u.light_pick, u.light);
                let bits = |v: [f32; 3]| v.map(f32::to_bits);
                let lane = |a: &[[f32; LANES]; 3]| [a[0][l], a[1][l], a[2][l]];
                match want {
                    Some(w) => {
                        assert_eq!(bits(lane(&got.wi)), bits(w.wi.to_array()), "wi at {}", p[l]);
                        assert_eq!(bits(lane(&got.le)), bits(w.le.to_array()), "le at {}", p[l]);
                        assert_eq!(got.pdf_light[l].to_bits(), w.pdf.to_bits(), "pdf at {}", p[l]);
                        assert_eq!(bits(lane(&got.target)), bits(w.target.to_array()), "target at {}", p[l]);
                        lit += 1;
                    }
                    None => assert_eq!(got.pdf_light[l], 0.0, "no sample at {}", p[l]),
                }
                // Which lanes the spherical rectangle took, as the kernel decided.
                if let PlainLight::Quad(q) =
                    &scene.lights.plain[scene.lights.pick(u.light_pick, p[l].into(), n[l].into()).0]
                {
                    let c = Vec3::from(q.center) - p[l];
                    spherical += (q.rect
                        && q.area * Vec3::from(q.n).dot(c).abs() >= c.length_squared() * c.length())
                        as u32;
                }
            }
        }
        assert!(lit > 5_000 && (lights == 0 || spherical > 500), "lit {lit}, spherical {spherical}");
        let kinds = |k: fn(&PlainLight) -> bool| scene.lights.plain.iter().filter(|l| k(l)).count();
        let (spheres, ellipsoids) =
            (kinds(|l| matches!(l, PlainLight::Sphere(_))), kinds(|l| matches!(l, PlainLight::Ellipsoid(_))));
        assert_eq!((spheres, ellipsoids), (spheres_wanted, ellipsoids_wanted), "sphere and ellipsoid lights");
    }

    /// Every kind of light the lanes take (a point light, smooth spots, one of them with equal
    /// cone and falloff angles) and some they leave to `sample_light` (a spot with Mitsuba's
    /// linear falloff, a quad light, a sun), chosen by the light tree: each lane's sample has
    /// the bits of `sample_light`'s, for points inside and outside the cones and on the
    /// lights' own spots.
    #[test]
    fn punctual_lanes_give_the_bits_of_sample_light() {
        let text = r#"Scene(
            camera: (look_from: (0, 0, -5), look_at: (0, 0, 0), vfov: 40),
            render: (width: 8, height: 8),
            materials: {
                "white": Lambertian(albedo: (0.7, 0.7, 0.7)),
                "lamp": DiffuseLight(emit: (4, 4, 4)),
            },
            objects: [
                (shape: Quad(q: (-0.5, 1.9, -0.5), u: (1, 0, 0), v: (0, 0, 1)), material: "lamp"),
            ],
            lights: [
                Point(position: (1, 1, 0), intensity: (3, 2, 1)),
                Spot(position: (0, 1.5, 0), look_at: (0, 0, 0), intensity: (5, 5, 5), cone_angle: 40, falloff_start: 20),
                Spot(position: (-1, 1, 1), look_at: (-1, 0, 0), intensity: (1, 2, 3), cone_angle: 30, falloff_start: 30),
                Spot(position: (1, -1, 1), look_at: (0, 0, 0), intensity: (2, 2, 2), cone_angle: 50, falloff_start: 10, falloff: Linear),
                Directional(direction: (0.2, -1, 0.3), irradiance: (1, 1, 1)),
            ],
        )"#;
        let desc = parse(text, std::path::Path::new("<test>")).unwrap();
        let scene = SceneWorld::render_scene(&desc);
        let mut rng = Stream::new(5);
        let (mut taken, mut lit) = (0, 0);
        for round in 0..3000 {
            let points: [Vec3A; LANES] = std::array::from_fn(|l| match (round + l) % 7 {
                // On a light's position: no direction, no sample.
                0 => Vec3A::new(1.0, 1.0, 0.0),
                _ => Vec3A::new(
                    rng.next_1d() * 4.0 - 2.0,
                    rng.next_1d() * 4.0 - 2.0,
                    rng.next_1d() * 4.0 - 2.0,
                ),
            });
            let picks: [(usize, f32); LANES] = std::array::from_fn(|l| {
                let n = Vec3A::new(rng.next_1d() - 0.5, rng.next_1d() - 0.5, rng.next_1d() - 0.5).normalize();
                scene.lights.pick(rng.next_1d(), points[l], n)
            });
            let active = std::array::from_fn(|l| (round + l) % 5 != 0);
            let u: [Vec2; LANES] = std::array::from_fn(|_| Vec2::new(rng.next_1d(), rng.next_1d()));
            let from = [0, 1, 2].map(|c| points.map(|p| p[c]));
            let got = sample_lights_lanes(&scene, &picks, &active, &from, &[0.0; LANES], &u);
            for l in 0..LANES {
                let want =
                    active[l].then(|| path::sample_light(&scene, picks[l], points[l], 0.0, u[l])).flatten();
                let bits = |p: &path::LightPick| {
                    let v = |a: [f32; 3]| a.map(f32::to_bits);
                    (v(p.wi.into()), v(p.le.into()), p.pdf.to_bits(), v(p.target.into()), p.delta)
                };
                assert_eq!(
                    got[l].as_ref().map(bits),
                    want.as_ref().map(bits),
                    "lane {l} at {} (light {})",
                    points[l],
                    picks[l].0
                );
                taken += (active[l]
                    && matches!(
                        scene.lights.other(picks[l].0),
                        Some(OtherLight::Punctual(
                            PunctualLight::Point { .. }
                                | PunctualLight::Spot { falloff: SpotFalloff::Smoothstep, .. }
                        ))
                    )) as u32;
                lit += got[l].as_ref().is_some_and(|p| p.le != Vec3::ZERO) as u32;
            }
        }
        assert!(taken > 10000 && lit > 10000, "the lanes took {taken} samples, {lit} of them lit");
    }
}
