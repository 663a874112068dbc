//! The kinds whose lobes are all deltas ([`Shading::Sampled`](pathwave_engine::material::Shading::Sampled): smooth glass, thin panes)
//! sampled across lanes: the engine's `sample_plain` of each over [`LANES`] paths at a time,
//! the path's bookkeeping after path by path ([`crate::path::scatter_sampled`]). They have no
//! evaluation to do: a delta lobe takes no light sample.

use crate::lambert_vertex::{LANES, lanes};
use glam::Vec3;
use pathwave_engine::material::dielectric::{self, Dielectric, Fresnel};
use pathwave_engine::material::thin_dielectric::ThinDielectric;
use pathwave_engine::material::{BsdfSample, Material};

/// A delta kind whose sampling the wavefront runs across lanes.
pub trait DeltaLanes {
    /// The material as the kernel takes it; `None` where the kernel does not take it.
    fn lane_material(m: &Material) -> Option<Self>
    where
        Self: Sized;

    /// Sets lane `l`'s inputs: the material `m`, the unit direction back along the ray, the
    /// shading normal and the lobe's number.
    fn set(i: &mut DeltaInLanes, l: usize, m: &Self, wo: Vec3, n: Vec3, uc: f32);

    /// Runs the kernel on every lane.
    fn run(i: &DeltaInLanes, o: &mut DeltaOutLanes);
}

/// What a delta kernel reads for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct DeltaIn {
    /// Unit direction back along the ray.
    pub wo: Vec3,
    /// Unit shading normal.
    pub n: Vec3,
    /// The lobe's number.
    pub uc: f32,
    /// Index of refraction.
    pub ior: f32,
    /// Schlick's reflectance rather than the exact one (smooth glass).
    pub schlick: bool,
}

lanes!(pub DeltaInLanes for DeltaIn { wo: v3, n: v3, uc: f32, ior: f32, schlick: bool });

/// What a delta kernel writes for one path.
#[derive(Clone, Copy, Debug, Default)]
pub struct DeltaOut {
    /// The sampled unit direction.
    pub wi: Vec3,
    /// Its weight, `f cos / pdf` (grey).
    pub weight: f32,
    /// The probability of its lobe.
    pub pdf: f32,
    /// The relative IOR it crossed (1: reflected or straight on).
    pub eta: f32,
    /// It goes straight on (a null lobe).
    pub null: bool,
    /// A direction was sampled.
    pub sampled: bool,
}

lanes!(pub DeltaOutLanes for DeltaOut { wi: v3, weight: f32, pdf: f32, eta: f32, null: bool, sampled: bool });

impl DeltaOutLanes {
    /// Lane `l`'s sample, if any.
    #[inline(always)]
    pub fn sample(&self, l: usize) -> Option<BsdfSample> {
        let x = self.get(l);
        let s = BsdfSample {
            wi: x.wi.into(),
            weight: Vec3::splat(x.weight),
            pdf: x.pdf,
            eta: x.eta,
            delta: true,
            null: x.null,
        };
        x.sampled.then_some(s)
    }
}

/// Runs `$kernel` (a lane's outputs from its inputs `$x`) on every lane of `$i` into `$o`, in
/// the AVX-512 region where the CPU has it.
macro_rules! each_delta_lane {
    ($i:expr, $o:expr, |$x:ident| $kernel:expr) => {
        *$o = pathwave_engine::simd::lanes(
            #[inline(always)]
            || {
                let mut out = DeltaOutLanes::default();
                for l in 0..LANES {
                    let $x = $i.get(l);
                    out.set(l, &$kernel);
                }
                out
            },
        )
    };
}

impl DeltaLanes for Dielectric {
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<Self> {
        match m {
            Material::Dielectric(g) => Some(*g),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut DeltaInLanes, l: usize, m: &Self, wo: Vec3, n: Vec3, uc: f32) {
        i.set(l, &DeltaIn { wo, n, uc, ior: m.ior, schlick: m.fresnel == Fresnel::Schlick });
    }

    #[inline(never)]
    fn run(i: &DeltaInLanes, o: &mut DeltaOutLanes) {
        each_delta_lane!(i, o, |x| {
            let fresnel = if x.schlick { Fresnel::Schlick } else { Fresnel::Exact };
            let (s, sampled) = dielectric::sample_plain(x.ior, fresnel, x.wo, x.n, x.uc);
            DeltaOut { wi: s.wi, weight: s.weight, pdf: s.pdf, eta: s.eta, null: false, sampled }
        });
    }
}

impl DeltaLanes for ThinDielectric {
    #[inline(always)]
    fn lane_material(m: &Material) -> Option<Self> {
        match m {
            Material::ThinDielectric(g) => Some(*g),
            _ => None,
        }
    }

    #[inline(always)]
    fn set(i: &mut DeltaInLanes, l: usize, m: &Self, wo: Vec3, n: Vec3, uc: f32) {
        i.set(l, &DeltaIn { wo, n, uc, ior: m.ior, schlick: false });
    }

    #[inline(never)]
    fn run(i: &DeltaInLanes, o: &mut DeltaOutLanes) {
        each_delta_lane!(i, o, |x| {
            let (wi, pdf, null) = ThinDielectric { ior: x.ior }.sample_plain(x.wo, x.n, x.uc);
            DeltaOut { wi, weight: 1.0, pdf, eta: 1.0, null, sampled: true }
        });
    }
}
