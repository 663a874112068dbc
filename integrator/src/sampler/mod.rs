//! Counter-based samples: every value is a function of (seed, pixel, sample index, dimension),
//! so an image does not depend on thread count, scheduling or batch size, and any range of
//! sample indices renders the same bits alone or as part of a larger render.
//!
//! Every decision of a path reads a fixed dimension ([`Dims`]): the pixel position, the lens and
//! the time, then per vertex the medium distance, the light choice, the light point, the BSDF's
//! two numbers and its lobe, and Russian roulette. Three ways to fill them ([`SamplerKind`]):
//!
//! - **Sobol** (the default): each 1D or 2D dimension is an Owen-scrambled (0,2)-sequence, the
//!   first two dimensions of Sobol's sequence, with its own scramble per pixel and dimension and
//!   its own shuffle of the sample indices, so that dimensions are not correlated: the "padded"
//!   construction of Burley, "Practical Hash-based Owen Scrambling" (JCGT 9(4), 2020), with the
//!   hash of pbrt-v4's `FastOwenScrambler`, and the indices put in a random order within each
//!   octave so that dimensions pair at random (`sobol::shuffle`). A pixel's first 2^k samples
//!   form a (0,k,2)-net in every such dimension. The exceptions (`layout`): the BSDF's
//!   direction is a randomly shifted rank-1 lattice (`lattice_2d`), which integrates the
//!   smooth indirect light over the hemisphere with less error than the net; the first light
//!   point shares the pixel's index as Sobol's dimensions 2 and 3; every later light point
//!   shares its direction's index as one 4D lattice with it. Every sample is uniform on its
//!   own (unbiased for any count), and the sequence is extensible: the first N samples are
//!   those of an N-spp render.
//! - **Stratified**: correlated multi-jittered samples (Kensler, "Correlated Multi-Jittered
//!   Sampling", Pixar TM 13-01, 2013) in every 2D dimension and jittered permuted strata in every
//!   1D one, as Mitsuba's `multijitter`; the pattern depends on the sample count.
//! - **Independent**: uniform hashes, the baseline.

use glam::Vec2;
use pathwave_engine::render_scene::SamplerKind;

mod cmj;
mod sobol;

use cmj::{cmj_2d, stratified_1d};
use sobol::{owen_reversed, owen_sobol, pascal, shuffle, sobol_2_3_reversed};

/// MurmurHash3's 64-bit finaliser: a bijective mixer with full avalanche.
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^ (x >> 33)
}

/// The dimensions a path reads, in a fixed layout: the camera's first, then [`Self::PER_VERTEX`]
/// per vertex. 1D and 2D dimensions each take one index.
pub struct Dims;

impl Dims {
    /// Position in the pixel (2D).
    pub const PIXEL: u32 = 0;
    /// Point on the lens (2D).
    pub const LENS: u32 = 1;
    /// Time in the shutter interval (1D).
    pub const TIME: u32 = 2;
    const CAMERA: u32 = 3;
    /// Distance sampled through a medium on the segment that leads to the vertex (1D).
    pub const MEDIUM: u32 = 0;
    /// Which light next-event estimation samples (1D).
    pub const LIGHT_PICK: u32 = 1;
    /// The point on that light (2D).
    pub const LIGHT: u32 = 2;
    /// The BSDF's or phase function's direction (2D).
    pub const BSDF: u32 = 3;
    /// The BSDF's choice of lobe (1D).
    pub const LOBE: u32 = 4;
    /// Russian roulette after the vertex (1D).
    pub const ROULETTE: u32 = 5;
    /// Dimensions per vertex.
    pub const PER_VERTEX: u32 = 6;

    /// Dimension `slot` of the vertex after `depth` bounces (the camera ray's hit is depth 0).
    #[inline]
    pub const fn vertex(depth: u32, slot: u32) -> u32 {
        Self::CAMERA + depth * Self::PER_VERTEX + slot
    }

    /// The first of the wrappers' numbers ([`Self::wrapper`]), far above any vertex's (a
    /// path of 2^28 vertices would reach it): scenes without wrappers keep their numbers.
    const WRAPPERS: u32 = 1 << 31;

    /// The number that resolves the `level`-th wrapper met at the vertex after `depth`
    /// bounces (1D; see `pathwave_engine::material::wrap`); levels from 256 on share the
    /// next vertex's numbers (no scene nests wrappers so deep).
    #[inline]
    pub const fn wrapper(depth: u32, level: u32) -> u32 {
        Self::WRAPPERS.wrapping_add(depth.wrapping_mul(256)).wrapping_add(level)
    }

    /// [`Self::vertex`] for `N` paths at once (a plain loop, which stays inline in a
    /// `simd::lanes` region where `std::array::from_fn`'s closure would not).
    #[inline(always)]
    pub fn vertex_lanes<const N: usize>(depths: &[u32; N], slot: u32) -> [u32; N] {
        let mut d = [0; N];
        for l in 0..N {
            d[l] = Self::vertex(depths[l], slot);
        }
        d
    }

    /// The first of the numbers of the light sampled apart ([`Self::apart`]), between the vertices'
    /// and the wrappers' (a path of 2^28 vertices would reach it).
    const APART: u32 = 1 << 30;

    /// The point on the light sampled apart from the others at the vertex after `depth`
    /// bounces (2D; `LightTable::apart`): numbers of their own, so that
    /// scenes without one keep theirs.
    #[inline]
    pub const fn apart(depth: u32) -> u32 {
        Self::APART.wrapping_add(depth)
    }

    /// [`Self::apart`] for `N` paths at once.
    #[inline(always)]
    pub fn apart_lanes<const N: usize>(depths: &[u32; N]) -> [u32; N] {
        let mut d = [0; N];
        for l in 0..N {
            d[l] = Self::apart(depths[l]);
        }
        d
    }
}

/// The samples of one pixel sample: a key and an index, immutable along the path.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    index: u32,
    spp: u32,
    kind: SamplerKind,
    /// The camera has a lens to sample: [`Dims::LENS`] shares the pixel's index ([`layout`]).
    lens: bool,
}

impl Sampler {
    /// Sample `index` of `spp` of pixel `pixel` (row-major index) under `seed`.
    #[inline]
    pub fn new(kind: SamplerKind, seed: u64, pixel: u32, index: u32, spp: u32) -> Self {
        Self { key: mix64(mix64(seed) ^ pixel as u64), index, spp: spp.max(1), kind, lens: false }
    }

    /// The same samples for a camera with a lens: the pixel position and the lens point form
    /// one 4D Sobol point (defocus blur integrates over both), and the first light sample is
    /// stratified alone.
    #[inline]
    pub fn with_lens(self) -> Self {
        Self { lens: true, ..self }
    }

    /// Dimension `dim` as one number in [0, 1) (Sobol's points: [`get_1d_lanes`]'s for one
    /// lane, so that the two are one definition).
    #[inline]
    pub fn get_1d(&self, dim: u32) -> f32 {
        let h = self.hash(dim);
        match self.kind {
            SamplerKind::Sobol => sobol_1d_lanes(&SamplerLanes::from(&[*self]), &[dim])[0],
            SamplerKind::Stratified => stratified_1d(self.index, self.spp, h),
            SamplerKind::Independent => to_unit((mix64(h ^ self.index as u64) >> 32) as u32),
        }
    }

    /// Dimension `dim` as two numbers in [0, 1) (Sobol's points: [`get_2d_lanes`]'s for one
    /// lane).
    #[inline]
    pub fn get_2d(&self, dim: u32) -> Vec2 {
        let h = self.hash(dim);
        match self.kind {
            SamplerKind::Sobol => sobol_2d_lanes(&SamplerLanes::from(&[*self]), &[dim])[0],
            SamplerKind::Stratified => cmj_2d(self.index, self.spp, h),
            SamplerKind::Independent => {
                let r = mix64(h ^ self.index as u64);
                Vec2::new(to_unit((r >> 32) as u32), to_unit(r as u32))
            }
        }
    }

    /// The hash of (pixel, dimension) that seeds a dimension's scramble.
    #[inline]
    fn hash(&self, dim: u32) -> u64 {
        dim_hash(self.key, dim)
    }
}

/// `N` samplers of one kind, one array per field: what [`get_1d_lanes`] and [`get_2d_lanes`]
/// read. Not `[Sampler; N]`: LLVM vectorises a loop that reads a field of an array of structs
/// as an interleaved access with a gap, which needs a scalar remainder as long as one vector,
/// and so ran half of the 16 lanes of every step one at a time.
#[derive(Clone, Copy, Debug)]
pub struct SamplerLanes<const N: usize> {
    key: [u64; N],
    index: [u32; N],
    spp: [u32; N],
    lens: [bool; N],
    kind: SamplerKind,
}

impl<const N: usize> SamplerLanes<N> {
    /// Sampler `l`.
    #[inline(always)]
    fn get(&self, l: usize) -> Sampler {
        Sampler {
            key: self.key[l],
            index: self.index[l],
            spp: self.spp[l],
            kind: self.kind,
            lens: self.lens[l],
        }
    }
}

impl<const N: usize> From<&[Sampler; N]> for SamplerLanes<N> {
    /// The samplers' fields side by side (they must be of one kind).
    #[inline]
    fn from(s: &[Sampler; N]) -> Self {
        let mut out = Self { key: [0; N], index: [0; N], spp: [0; N], lens: [false; N], kind: s[0].kind };
        for l in 0..N {
            debug_assert_eq!(s[l].kind, out.kind);
            (out.key[l], out.index[l], out.spp[l], out.lens[l]) = (s[l].key, s[l].index, s[l].spp, s[l].lens);
        }
        out
    }
}

#[inline]
fn dim_hash(key: u64, dim: u32) -> u64 {
    mix64(key ^ (dim as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// Whether `dim` is a vertex's BSDF direction ([`Dims::BSDF`]), which [`lattice_2d`] fills.
#[inline]
fn is_direction(dim: u32) -> bool {
    (dim >= Dims::CAMERA) & (dim.wrapping_sub(Dims::CAMERA) % Dims::PER_VERTEX == Dims::BSDF)
}

/// The generators of the BSDF direction's lattice: point i of 2^k is (i / 2^k, i * 1051 / 2^k)
/// mod 1 in index order. 1051 maximises the worst ratio, over 2^2 to 2^12 points, of the
/// lattice's shortest vector to that of the hexagonal lattice of equal density (0.66; its 64-
/// and 256-point lattices reach 0.71 and 0.92); checked in the tests.
const DIRECTION_LATTICE: [u32; 2] = [1, 1051];

/// The generators of a later light point's lattice, which shares the index of the direction
/// that led to its vertex: together they are one 4D rank-1 lattice (1, 1051, g2, g3). Chosen by
/// a random search for the worst ratio, over the six 2D projections and 2^4 to 2^12 points, of
/// the shortest vector to the hexagonal lattice's (below 16 points four odd generators cannot
/// all be apart); checked in the tests.
const LIGHT_LATTICE: [u32; 2] = [35699, 19783];

/// How a 2D dimension is filled ([`layout`]): plain numbers, so that lanes at different
/// dimensions compute it and act on it without branches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    /// The dimension whose shuffled index it shares (itself when alone).
    group: u32,
    /// A net of Sobol's dimensions 2 and 3 of that index, whose partner (the dimension that
    /// shares it) takes 0 and 1: one 4D Sobol point. Otherwise a net of 0 and 1, Owen-scrambled:
    /// a (0,2)-sequence.
    hi: bool,
    /// Not a net but a shifted rank-1 lattice with the generators `g` ([`lattice_2d`]).
    lattice: bool,
    /// The lattice's generators.
    g: [u32; 2],
}

/// The dimension whose shuffled index `dim` shares (itself when alone) and the points that
/// fill it:
///
/// - a BSDF direction: the lattice of [`DIRECTION_LATTICE`], alone;
/// - the first light point: Sobol's dimensions 2 and 3 of the pixel position's index (or,
///   under a `lens`, the lens point takes them and the first light point is a net alone), so
///   that direct light is stratified over the pixel in 4D: relMSE at 64 spp -1.6% on
///   cornell-diffuse, -3% on mesh; the lens with the pixel -7% on spheres-sky;
/// - a later light point: the lattice of [`LIGHT_LATTICE`] over the index of the direction
///   that led to its vertex, so that a light sample seen over the directions of the previous
///   bounce is stratified in 4D. relvar over seeds -1.8% at 64 spp and -0.4% at 256 on
///   cornell-diffuse against these light points as nets alone; as Sobol's dimensions 2 and 3
///   beside the direction's lattice (no 4D structure) they lost 0.5-0.9% at 256 spp
///   (benches/results/sampling.md);
/// - anything else: a net, alone.
///
/// The three cases are disjoint, and each is a comparison: the function is selects only.
#[inline(always)]
fn layout(dim: u32, lens: bool) -> Layout {
    let light0 = Dims::vertex(0, Dims::LIGHT);
    let direction = is_direction(dim);
    // `&` and `|`, not `&&` and `||`: no branches.
    let hi = (dim == Dims::LENS) & lens | (dim == light0) & !lens;
    let later_light = (dim > light0) & dim.wrapping_sub(light0).is_multiple_of(Dims::PER_VERTEX);
    let later_group = dim.wrapping_sub(Dims::PER_VERTEX + Dims::LIGHT - Dims::BSDF);
    let group = if hi {
        Dims::PIXEL
    } else if later_light {
        later_group
    } else {
        dim
    };
    let g = if direction { DIRECTION_LATTICE } else { LIGHT_LATTICE };
    Layout { group, hi, lattice: direction || later_light, g }
}

/// Sample `i` (an already shuffled index) of an extensible rank-1 lattice sequence in base 2
/// (Hickernell, Hong, L'Ecuyer and Lemieux, "Extensible lattice sequences for quasi-Monte Carlo
/// quadrature", SIAM J. Sci. Comput. 22(3), 2000): the radical inverse of `i` times the
/// generators `g` modulo 1, in 32-bit fixed point, shifted by a random vector from `h` (Cranley
/// and Patterson 1976), so that every sample is uniform. The first 2^k indices of an aligned
/// block form a shifted lattice of 2^k points, stratified in both 1D projections (odd
/// generators).
///
/// Used for the BSDF's direction, where it beats the Owen-scrambled (0,2)-net: relMSE at 64 spp
/// -8.6% on cornell-diffuse, -4.5% on cornell, -2.7% on mesh and -2.8% on spheres-sky (see
/// benches/results/sampling.md), and for later light points beside it ([`layout`]).
/// The shift is `(sx, sy)`, the dimension's [`coordinate_seeds`].
#[inline]
fn lattice_2d(i: u32, sx: u32, sy: u32, g: [u32; 2]) -> Vec2 {
    let r = i.reverse_bits();
    let x = r.wrapping_mul(g[0]).wrapping_add(sx);
    let y = r.wrapping_mul(g[1]).wrapping_add(sy);
    Vec2::new(to_unit(x), to_unit(y))
}

/// The two 32-bit seeds of a 2D dimension's coordinates (a lattice's shift or a net's
/// scrambles), from its hash `h`.
#[inline(always)]
fn coordinate_seeds(h: u64) -> (u32, u32) {
    ((h >> 32) as u32, mix64(h) as u32)
}

/// [`Sampler::get_1d`] for `N` samplers of one kind at once, each at its own dimension: the
/// same integer operations lane by lane (so the same bits), in loops that LLVM vectorises.
#[inline(always)]
pub fn get_1d_lanes<const N: usize>(s: &SamplerLanes<N>, dim: &[u32; N]) -> [f32; N] {
    match s.kind {
        SamplerKind::Sobol => sobol_1d_lanes(s, dim),
        _ => std::array::from_fn(|l| s.get(l).get_1d(dim[l])),
    }
}

/// [`get_1d_lanes`] of Sobol samplers.
#[inline(always)]
fn sobol_1d_lanes<const N: usize>(s: &SamplerLanes<N>, dim: &[u32; N]) -> [f32; N] {
    // Plain loops, not `std::array::from_fn`: LLVM leaves its closures out of line, and so
    // outside the instruction set of the caller's `simd::lanes` region.
    let (mut h, mut i, mut out) = ([0u64; N], [0u32; N], [0.0f32; N]);
    for l in 0..N {
        h[l] = dim_hash(s.key[l], dim[l]);
    }
    // The 32-bit seeds apart from the 64-bit hashes: a loop that mixes the two widths runs as
    // many lanes per vector as 64-bit numbers fit (8 in AVX-512), one on 32-bit numbers alone
    // twice as many.
    let (mut seed, mut scramble) = ([0u32; N], [0u32; N]);
    for l in 0..N {
        (seed[l], scramble[l]) = (h[l] as u32, (h[l] >> 32) as u32);
    }
    for l in 0..N {
        i[l] = shuffle(s.index[l], seed[l]);
    }
    for l in 0..N {
        out[l] = to_unit(owen_sobol(i[l], false, scramble[l]));
    }
    out
}

/// [`Sampler::get_2d`] for `N` samplers of one kind at once (see [`get_1d_lanes`]). Each step
/// runs over all lanes before the next, as plain integer loops that LLVM vectorises (the 64-bit
/// hashes included; Sobol's dimensions 2 and 3 as four table look-ups per coordinate,
/// gathers). Lanes may mix the kinds of points a dimension takes (`layout`: paths at different
/// depths): where they do, every lane computes both the net and the lattice, and keeps its own
/// by a select, not a branch per lane.
#[inline(always)]
pub fn get_2d_lanes<const N: usize>(s: &SamplerLanes<N>, dim: &[u32; N]) -> [Vec2; N] {
    match s.kind {
        SamplerKind::Sobol => sobol_2d_lanes(s, dim),
        _ => std::array::from_fn(|l| s.get(l).get_2d(dim[l])),
    }
}

/// [`get_2d_lanes`] of Sobol samplers.
#[inline(always)]
fn sobol_2d_lanes<const N: usize>(s: &SamplerLanes<N>, dim: &[u32; N]) -> [Vec2; N] {
    let (key, index) = (&s.key, &s.index);
    let (mut group, mut hi, mut lattice) = ([0u32; N], [false; N], [false; N]);
    let (mut g0, mut g1) = ([0u32; N], [0u32; N]);
    for l in 0..N {
        let lay = layout(dim[l], s.lens[l]);
        (group[l], hi[l], lattice[l], g0[l], g1[l]) = (lay.group, lay.hi, lay.lattice, lay.g[0], lay.g[1]);
    }
    let mut h = [0u64; N];
    for l in 0..N {
        h[l] = dim_hash(key[l], dim[l]);
    }
    // The hash that shuffles the index: that of the dimension whose index it shares (its own
    // when alone).
    let mut hs = h;
    if (0..N).any(|l| group[l] != dim[l]) {
        for l in 0..N {
            hs[l] = dim_hash(key[l], group[l]);
        }
    }
    // The 32-bit seeds apart from the 64-bit hashes (see `get_1d_lanes`).
    let (mut seed, mut sx, mut sy) = ([0u32; N], [0u32; N], [0u32; N]);
    for l in 0..N {
        seed[l] = hs[l] as u32;
        (sx[l], sy[l]) = coordinate_seeds(h[l]);
    }
    let mut i = [0u32; N];
    for l in 0..N {
        i[l] = shuffle(index[l], seed[l]);
    }
    let mut out = [Vec2::ZERO; N];
    for l in 0..N {
        out[l] = lattice_2d(i[l], sx[l], sy[l], [g0[l], g1[l]]);
    }
    // BSDF directions and later light points, the common calls: no net to compute.
    if lattice.iter().all(|&x| x) {
        return out;
    }
    // The unscrambled coordinates, digits least significant first: Sobol's dimensions 0 and 1,
    // or 2 and 3 for `hi` lanes.
    let (mut ax, mut ay) = ([0u32; N], [0u32; N]);
    for l in 0..N {
        (ax[l], ay[l]) = (i[l], pascal(i[l]));
    }
    if hi.iter().any(|&x| x) {
        let (mut bx, mut by) = ([0u32; N], [0u32; N]);
        for l in 0..N {
            (bx[l], by[l]) = (sobol_2_3_reversed(i[l], false), sobol_2_3_reversed(i[l], true));
        }
        for l in 0..N {
            (ax[l], ay[l]) = (if hi[l] { bx[l] } else { ax[l] }, if hi[l] { by[l] } else { ay[l] });
        }
    }
    for l in 0..N {
        let x = owen_reversed(ax[l], sx[l]).reverse_bits();
        let y = owen_reversed(ay[l], sy[l]).reverse_bits();
        let net = Vec2::new(to_unit(x), to_unit(y));
        out[l] = if lattice[l] { out[l] } else { net };
    }
    out
}

/// The top 24 bits of `x` as a float in [0, 1).
#[inline]
fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// A stream of independent uniform numbers: a Weyl sequence through [`mix64`] (splitmix64's
/// construction; Steele, Lea and Flood 2014), for the light tracer's paths and for tests that
/// need many numbers.
pub(crate) struct Stream(u64);

impl Stream {
    /// The stream of `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        Self(mix64(seed ^ 0x2545_f491_4f6c_dd1d))
    }

    /// The next number, in [0, 1).
    pub(crate) fn next_1d(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        to_unit((mix64(self.0) >> 32) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [SamplerKind; 3] = [SamplerKind::Sobol, SamplerKind::Stratified, SamplerKind::Independent];

    /// The 2D points of dimension `dim` of samples `0..n` of a pixel.
    fn points(kind: SamplerKind, pixel: u32, dim: u32, n: u32) -> Vec<Vec2> {
        (0..n).map(|i| Sampler::new(kind, 3, pixel, i, n).get_2d(dim)).collect()
    }

    #[test]
    fn sobol_generator_is_pascals_triangle_mod_2() {
        // Columns of Sobol's second generator matrix: v_0 = 1 (as the top bit), v_k = v_{k-1}
        // xor v_{k-1} / 2; without scrambling a point is the xor of the columns of its bits.
        let mut v = [0u32; 32];
        v[0] = 1 << 31;
        for k in 1..32 {
            v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        }
        let unscrambled = |i: u32, second: bool| if second { pascal(i) } else { i }.reverse_bits();
        for i in [0u32, 1, 2, 3, 5, 12, 255, 1 << 20, 0xdead_beef, u32::MAX] {
            let expect = (0..32).filter(|&k| i >> k & 1 == 1).fold(0, |x, k| x ^ v[k]);
            assert_eq!(unscrambled(i, true), expect, "{i}");
            assert_eq!(unscrambled(i, false), i.reverse_bits());
        }
        // Owen scrambling keeps the 1D projection a (0,1)-sequence: the first 2^12 points take
        // each of the 2^12 strata once.
        let mut seen: Vec<u32> = (0..4096).map(|i| owen_sobol(i, true, 77) >> 20).collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..4096).collect::<Vec<_>>());
    }

    #[test]
    fn sobol_2d_points_form_nets_in_every_elementary_interval() {
        // 2^k points of a 2D dimension of any pixel (but the BSDF's direction, a lattice):
        // every elementary interval of area 2^-k (2^a by 2^(k-a) boxes) holds exactly one
        // point, a (0,k,2)-net; the first light point, which takes Sobol's dimensions 2 and 3,
        // forms a (1,k,2)-net (two points in every interval of area 2^(1-k)). Later light
        // points are lattices (below).
        for k in [4u32, 6, 8] {
            let n = 1u32 << k;
            for (pixel, dim, t) in
                [(0, Dims::PIXEL, 0), (17, Dims::vertex(0, Dims::LIGHT), 1), (999, Dims::LENS, 0)]
            {
                let pts: Vec<(f32, f32)> =
                    points(SamplerKind::Sobol, pixel, dim, n).iter().map(|p| (p.x, p.y)).collect();
                assert!(
                    net_quality(&pts, k) <= t,
                    "k {k} pixel {pixel} dim {dim}: t {}",
                    net_quality(&pts, k)
                );
            }
        }
    }

    #[test]
    fn sobol_1d_points_are_stratified_and_the_sequence_extends() {
        let n = 64;
        let mut count = vec![0; n];
        for i in 0..n as u32 {
            count[(Sampler::new(SamplerKind::Sobol, 1, 5, i, 64).get_1d(Dims::TIME) * n as f32) as usize] +=
                1;
        }
        assert!(count.iter().all(|&c| c == 1), "{count:?}");
        // A sample's values do not depend on the sample count: the first 16 of 1024 are the 16.
        for i in 0..16 {
            let (a, b) = (
                Sampler::new(SamplerKind::Sobol, 1, 5, i, 16),
                Sampler::new(SamplerKind::Sobol, 1, 5, i, 1024),
            );
            assert_eq!(a.get_2d(Dims::LENS), b.get_2d(Dims::LENS));
        }
    }

    #[test]
    fn stratified_points_fill_every_stratum_for_any_count() {
        for n in [1u32, 4, 7, 16, 33, 64] {
            let pts = points(SamplerKind::Stratified, 42, Dims::vertex(2, Dims::LIGHT), n);
            // 1D projections: one sample per stratum of width 1/n, up to the toroidal shift,
            // which moves every point by the same amount: strata counts stay at most 2.
            for axis in 0..2 {
                let mut count = vec![0; n as usize];
                for p in &pts {
                    count[((p[axis] * n as f32) as usize).min(n as usize - 1)] += 1;
                }
                assert!(count.iter().all(|&c| c <= 2), "n {n} axis {axis} {count:?}");
            }
            let mut count = vec![0; n as usize];
            for i in 0..n {
                count[(Sampler::new(SamplerKind::Stratified, 3, 42, i, n).get_1d(Dims::TIME) * n as f32)
                    as usize] += 1;
            }
            assert!(count.iter().all(|&c| c == 1), "n {n} 1D {count:?}");
        }
    }

    #[test]
    fn every_sample_is_uniform_over_pixels_and_values_stay_below_one() {
        // Averaged over many pixels, every sample index of every kind is uniform: mean 1/2,
        // variance 1/12 in each coordinate (an unbiased estimator whatever the count).
        for kind in KINDS {
            for (s, n) in [(0u32, 1u32), (2, 3), (5, 10), (100, 256)] {
                let m = 20_000;
                let (mut sum, mut sq) = (Vec2::ZERO, Vec2::ZERO);
                for px in 0..m {
                    let u = Sampler::new(kind, 5, px, s, n).get_2d(Dims::vertex(1, Dims::BSDF));
                    assert!(u.x < 1.0 && u.y < 1.0 && u.x >= 0.0 && u.y >= 0.0);
                    (sum, sq) = (sum + u, sq + u * u);
                }
                let (mean, var) = (sum / m as f32, sq / m as f32 - (sum / m as f32).powf(2.0));
                assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.01, "{kind:?} {s}/{n}: {mean}");
                assert!(
                    (var - Vec2::splat(1.0 / 12.0)).abs().max_element() < 0.005,
                    "{kind:?} {s}/{n}: {var}"
                );
            }
        }
    }

    #[test]
    fn lanes_give_the_bits_of_one_sampler_at_a_time() {
        // Light points (the first of Sobol's dimensions 2 and 3, paired; the later ones 0 and
        // 1), BSDF directions (lattices), and with a lens the lens paired instead.
        // Slot u32::MAX: lanes that alternate light points and directions; CAMERA_AND_LIGHT:
        // the camera's pixel and lens dimensions and the first light point, in turn.
        const CAMERA_AND_LIGHT: u32 = u32::MAX - 1;
        for (kind, lens, slot) in KINDS.into_iter().flat_map(|k| {
            [
                (k, false, Dims::LIGHT),
                (k, true, Dims::LIGHT),
                (k, false, Dims::BSDF),
                (k, true, u32::MAX),
                (k, false, CAMERA_AND_LIGHT),
                (k, true, CAMERA_AND_LIGHT),
            ]
        }) {
            let s: [Sampler; 8] = std::array::from_fn(|l| {
                let s = Sampler::new(kind, 4, 100 + l as u32, 3 * l as u32, 64);
                if lens { s.with_lens() } else { s }
            });
            let dim: [u32; 8] = std::array::from_fn(|l| match slot {
                u32::MAX => Dims::vertex(l as u32, [Dims::LIGHT, Dims::BSDF][l % 2]),
                CAMERA_AND_LIGHT => [Dims::PIXEL, Dims::LENS, Dims::vertex(0, Dims::LIGHT)][l % 3],
                _ => Dims::vertex(l as u32, slot),
            });
            let lanes = SamplerLanes::from(&s);
            let (one, two) = (get_1d_lanes(&lanes, &dim), get_2d_lanes(&lanes, &dim));
            for l in 0..8 {
                assert_eq!(one[l].to_bits(), s[l].get_1d(dim[l]).to_bits());
                assert_eq!(two[l], s[l].get_2d(dim[l]), "{kind:?} lens {lens} slot {slot} lane {l}");
            }
        }
    }

    /// Asserts that `pts` (2^k points, each a list of coordinates) minus the first is the
    /// lattice j * `gens` / 2^k mod 1, one point for each j in 0..2^k (a whole shifted lattice).
    fn assert_shifted_lattice(pts: &[Vec<f32>], gens: &[u32], k: u32) {
        let fixed = |v: f32| (v * (1u32 << 24) as f32) as u32;
        let mut seen = vec![false; 1 << k];
        for p in pts {
            let d: Vec<u32> =
                p.iter().zip(&pts[0]).map(|(&a, &b)| fixed(a).wrapping_sub(fixed(b)) & 0xff_ffff).collect();
            // d[0] = j * gens[0] * 2^(24 - k) mod 2^24 with gens[0] odd: solve for j.
            assert_eq!(d[0] % (1 << (24 - k)), 0, "k {k}: {p:?}");
            let inv = (0..1u32 << k).find(|&x| x.wrapping_mul(gens[0]) & ((1 << k) - 1) == 1).unwrap();
            let j = (d[0] >> (24 - k)).wrapping_mul(inv) & ((1 << k) - 1);
            for (c, &g) in gens.iter().enumerate() {
                assert_eq!(d[c], j.wrapping_mul(g) << (24 - k) & 0xff_ffff, "k {k} j {j} coordinate {c}");
            }
            assert!(!std::mem::replace(&mut seen[j as usize], true), "k {k}: j {j} twice");
        }
    }

    /// The shortest vector of the 2D lattice j (a, b) / 2^k mod 1 over that of the hexagonal
    /// lattice of equal density (the densest packing).
    fn lattice_merit(a: u32, b: u32, k: u32) -> f64 {
        let n = 1u32 << k;
        let shortest = (1..n)
            .map(|j| {
                let (x, y) =
                    ((j.wrapping_mul(a) % n) as f64 / n as f64, (j.wrapping_mul(b) % n) as f64 / n as f64);
                x.min(1.0 - x).hypot(y.min(1.0 - y))
            })
            .fold(f64::MAX, f64::min);
        shortest / (2.0 / (3f64.sqrt() * n as f64)).sqrt()
    }

    #[test]
    fn directions_form_shifted_lattices_of_good_generator() {
        // 2^k directions of a pixel are a whole shifted lattice of the generators (1, 1051),
        // whose shortest vector is at least 0.65 of the hexagonal lattice's.
        let [a, b] = DIRECTION_LATTICE;
        for k in 2u32..=12 {
            let pts = points(SamplerKind::Sobol, 77, Dims::vertex(2, Dims::BSDF), 1 << k);
            assert_shifted_lattice(&pts.iter().map(|p| vec![p.x, p.y]).collect::<Vec<_>>(), &[a, b], k);
            assert!(lattice_merit(a, b, k) > 0.65, "k {k}: {}", lattice_merit(a, b, k));
        }
    }

    #[test]
    fn later_lights_and_their_directions_form_4d_lattices() {
        // A direction and the light point of the vertex it leads to: 2^k of them are a whole
        // shifted 4D lattice (1, 1051, g2, g3), with or without a lens, and each of its six 2D
        // projections keeps its shortest vector at least half the hexagonal lattice's from 16
        // to 4096 points.
        let gens = [DIRECTION_LATTICE[0], DIRECTION_LATTICE[1], LIGHT_LATTICE[0], LIGHT_LATTICE[1]];
        for lens in [false, true] {
            for k in 2u32..=12 {
                let pts: Vec<Vec<f32>> = (0..1u32 << k)
                    .map(|i| {
                        let s = Sampler::new(SamplerKind::Sobol, 6, 1234, i, 1 << k);
                        let s = if lens { s.with_lens() } else { s };
                        let (d, l) =
                            (s.get_2d(Dims::vertex(1, Dims::BSDF)), s.get_2d(Dims::vertex(2, Dims::LIGHT)));
                        vec![d.x, d.y, l.x, l.y]
                    })
                    .collect();
                assert_shifted_lattice(&pts, &gens, k);
            }
        }
        for k in 4u32..=12 {
            for a in 0..4 {
                for b in a + 1..4 {
                    let m = lattice_merit(gens[a], gens[b], k);
                    assert!(m > 0.5, "k {k}, coordinates {a} and {b}: {m}");
                }
            }
        }
    }

    /// The smallest t for which `pts` (2^k of them) is a (t, k, 2)-net: every elementary
    /// interval of area 2^(t-k) holds 2^t points.
    fn net_quality(pts: &[(f32, f32)], k: u32) -> u32 {
        (0..=k)
            .find(|&t| {
                (0..=k - t).all(|a| {
                    let (nx, ny) = (1usize << a, 1usize << (k - t - a));
                    let mut count = vec![0u32; nx * ny];
                    for &(x, y) in pts {
                        count[(x * nx as f32) as usize * ny + (y * ny as f32) as usize] += 1;
                    }
                    count.iter().all(|&c| c == 1 << t)
                })
            })
            .unwrap()
    }

    #[test]
    fn the_first_light_and_the_pixel_form_4d_sobol_points() {
        // The first light point and the pixel position are one 4D point: any coordinate of one
        // against any of the other is a net of small t. Unpaired dimensions are independent:
        // no such structure.
        let k = 8;
        let coords = |lens: bool, d: u32| -> Vec<Vec2> {
            (0..1u32 << k)
                .map(|i| {
                    let s = Sampler::new(SamplerKind::Sobol, 2, 31, i, 1 << k);
                    (if lens { s.with_lens() } else { s }).get_2d(d)
                })
                .collect()
        };
        let worst = |a: &[Vec2], b: &[Vec2]| {
            (0..2)
                .flat_map(|i| (0..2).map(move |j| (i, j)))
                .map(|(i, j)| net_quality(&a.iter().zip(b).map(|(p, q)| (p[i], q[j])).collect::<Vec<_>>(), k))
                .max()
                .unwrap()
        };
        let (pixel, light0) = (coords(false, Dims::PIXEL), coords(false, Dims::vertex(0, Dims::LIGHT)));
        let bsdf2 = coords(false, Dims::vertex(2, Dims::BSDF));
        assert!(worst(&pixel, &light0) <= 2, "pixel and first light: t {}", worst(&pixel, &light0));
        assert!(worst(&pixel, &bsdf2) >= 5, "unpaired: t {}", worst(&pixel, &bsdf2));
        // With a lens, the lens shares the pixel's index and the first light is alone.
        let (pixel, lens) = (coords(true, Dims::PIXEL), coords(true, Dims::LENS));
        assert!(worst(&pixel, &lens) <= 2, "pixel and lens: t {}", worst(&pixel, &lens));
        assert!(worst(&pixel, &coords(true, Dims::vertex(0, Dims::LIGHT))) >= 5);
    }

    #[test]
    fn dimensions_are_not_correlated() {
        // Two dimensions of one pixel sample, over many pixels and indices: the correlation of
        // their values is about zero (padding decorrelates the dimensions).
        for kind in KINDS {
            let (mut sxy, mut sx, mut sy, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for px in 0..200 {
                for i in 0..64 {
                    let s = Sampler::new(kind, 9, px, i, 64);
                    let (a, b) = (
                        s.get_2d(Dims::vertex(0, Dims::LIGHT)).x as f64,
                        s.get_2d(Dims::vertex(0, Dims::BSDF)).x as f64,
                    );
                    (sxy, sx, sy, n) = (sxy + a * b, sx + a, sy + b, n + 1.0);
                }
            }
            let cov = sxy / n - sx / n * sy / n;
            assert!((cov * 12.0).abs() < 0.02, "{kind:?}: correlation {}", cov * 12.0);
        }
    }

    #[test]
    fn dimensions_are_paired_at_random_within_octaves() {
        // The product of the halves two dimensions fall in (+-1 each) integrates to zero; over
        // a pixel's 256 samples its mean should err no more than with independent pairs
        // (variance 1/256). A nested scramble of the index alone keeps sibling samples siblings
        // in every dimension, their products equal, and doubles that variance.
        let (n, pixels) = (256u32, 3000u32);
        let (a, b) = (Dims::vertex(0, Dims::ROULETTE), Dims::vertex(1, Dims::LIGHT_PICK));
        let half = |x: f32| if x < 0.5 { -1.0 } else { 1.0 };
        let mut var = 0.0f64;
        for px in 0..pixels {
            let sum: f64 = (0..n)
                .map(|i| {
                    let s = Sampler::new(SamplerKind::Sobol, 4, px, i, n);
                    half(s.get_1d(a)) * half(s.get_1d(b))
                })
                .sum();
            var += (sum / n as f64).powi(2) / pixels as f64;
        }
        assert!(var * (n as f64) < 1.25, "variance {} x 1/256", var * n as f64);
    }
}
