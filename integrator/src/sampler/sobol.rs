//! Owen-scrambled Sobol points in base 2: the scrambler, the index shuffle and Sobol's first
//! four dimensions (the sampler's [`Sampler`](super::Sampler) pairs them per dimension).

use super::cmj::permute_pow2;

/// Owen scrambling of the bit-reversed `v` (whose lowest bit is the most significant digit):
/// each output bit is flipped by a hash of the bits below it. The hash is pbrt-v4's
/// `FastOwenScrambler` (after Laine and Karras 2011 and Vegdahl's improvement).
#[inline]
pub(super) fn owen_reversed(mut v: u32, seed: u32) -> u32 {
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v
}

/// A shuffle of the sample indices: a bijection under which the first 2^k indices map onto one
/// aligned block of 2^k indices for every k, so that a pixel's first 2^k samples still form one
/// net, and two dimensions shuffled by different seeds are paired at random within each octave.
///
/// Burley 2020's nested uniform scramble of the index alone keeps the block structure at every
/// scale: samples 2j and 2j + 1 land on sibling points (opposite halves of the first digit) in
/// every dimension, so products of dimensions, a light sample seen over the direction that led
/// to it, add their errors instead of averaging them. A random order within each octave [2^(k-1),
/// 2^k) of indices first ([`permute_pow2`]) keeps the prefixes' blocks and pairs the rest at
/// random: relvar across seeds at 256 spp -1.0% on cornell-diffuse, -1.7% on mesh and
/// spheres-sky (benches/results/sampling.md).
#[inline]
pub(super) fn shuffle(index: u32, seed: u32) -> u32 {
    // The highest set bit of an index above 1, by smearing the bits down: a leading-zero
    // count has no instruction across lanes in AVX2 (nor in AVX-512 without its CD part).
    let mut m = index;
    for s in [1, 2, 4, 8, 16] {
        m |= m >> s;
    }
    let half = m ^ (m >> 1);
    let p = seed.wrapping_mul(0x9e37_79b9) ^ half.wrapping_mul(0x85eb_ca6b);
    // Computed for every index and then selected: a branch would keep LLVM from vectorising
    // the shuffle across lanes.
    let permuted = half.wrapping_add(permute_pow2(index.wrapping_sub(half), half.wrapping_sub(1), p));
    let i = if index > 1 { permuted } else { index };
    owen_reversed(i.reverse_bits(), seed).reverse_bits()
}

/// Owen-scrambled Sobol dimension 0 (`second` false) or 1 of sample `i`, as 32 fixed-point bits.
///
/// Dimension 0 is the van der Corput sequence (the bits of `i` reversed). Dimension 1's
/// generator is Pascal's triangle mod 2: output digit j is the parity of the bits k of `i` with
/// C(k, j) odd, that is (Lucas) with j a bit-subset of k, which a superset-sum transform over
/// the five bits of the digit position computes in five steps.
#[inline]
pub(super) fn owen_sobol(i: u32, second: bool, seed: u32) -> u32 {
    let a = if second { pascal(i) } else { i };
    // `a` holds the digits least significant first (bit j is digit j of the fraction), which is
    // the order the scrambler takes.
    owen_reversed(a, seed).reverse_bits()
}

/// Columns of the generator matrices of Sobol's dimensions 2 and 3 (primitive polynomials
/// x^2 + x + 1 and x^3 + x + 1, initial direction numbers 1, 3 and 1, 3, 1: Joe and Kuo,
/// "Constructing Sobol sequences with better two-dimensional projections", SIAM J. Sci.
/// Comput. 30, 2008), column k for bit k of the index, the first digit in the top bit.
const SOBOL_2_3: [[u32; 32]; 2] = [
    [
        0x8000_0000,
        0xc000_0000,
        0x6000_0000,
        0x9000_0000,
        0xe800_0000,
        0x5c00_0000,
        0x8e00_0000,
        0xc500_0000,
        0x6880_0000,
        0x9cc0_0000,
        0xee60_0000,
        0x5590_0000,
        0x8068_0000,
        0xc09c_0000,
        0x60ee_0000,
        0x9055_0000,
        0xe880_8000,
        0x5cc0_c000,
        0x8e60_6000,
        0xc590_9000,
        0x6868_e800,
        0x9c9c_5c00,
        0xeeee_8e00,
        0x5555_c500,
        0x8000_e880,
        0xc000_5cc0,
        0x6000_8e60,
        0x9000_c590,
        0xe800_6868,
        0x5c00_9c9c,
        0x8e00_eeee,
        0xc500_5555,
    ],
    [
        0x8000_0000,
        0xc000_0000,
        0x2000_0000,
        0x5000_0000,
        0xf800_0000,
        0x7400_0000,
        0xa200_0000,
        0x9300_0000,
        0xd880_0000,
        0x2540_0000,
        0x59e0_0000,
        0xe6d0_0000,
        0x7808_0000,
        0xb40c_0000,
        0x8202_0000,
        0xc305_0000,
        0x208f_8000,
        0x5147_4000,
        0xfbea_2000,
        0x75d9_3000,
        0xa085_8800,
        0x914e_5400,
        0xdbe7_9e00,
        0x25db_6d00,
        0x5880_0080,
        0xe540_00c0,
        0x79e0_0020,
        0xb6d0_0050,
        0x8008_00f8,
        0xc00c_0074,
        0x2002_00a2,
        0x5005_0093,
    ],
];

/// [`SOBOL_2_3`] as byte tables, each entry's bits reversed (the first digit in the lowest
/// bit): entry (d, b, v) is the xor of dimension 2 + d's columns for the set bits of byte value
/// v at byte b of the index, so that a point takes four look-ups per coordinate.
static SOBOL_2_3_REVERSED_BYTES: [[[u32; 256]; 4]; 2] = {
    let mut t = [[[0u32; 256]; 4]; 2];
    let mut d = 0;
    while d < 2 {
        let mut b = 0;
        while b < 4 {
            let mut v = 0;
            while v < 256 {
                let mut x = 0u32;
                let mut k = 0;
                while k < 8 {
                    if v >> k & 1 == 1 {
                        x ^= SOBOL_2_3[d][8 * b + k];
                    }
                    k += 1;
                }
                t[d][b][v] = x.reverse_bits();
                v += 1;
            }
            b += 1;
        }
        d += 1;
    }
    t
};

/// Sobol's dimension 2 (`second` false) or 3 of index `i` before scrambling, its digits least
/// significant first (the order [`owen_reversed`] takes): four look-ups, which vectorise as
/// gathers across lanes.
#[inline(always)]
pub(super) fn sobol_2_3_reversed(i: u32, second: bool) -> u32 {
    let t = &SOBOL_2_3_REVERSED_BYTES[second as usize];
    t[0][(i & 0xff) as usize]
        ^ t[1][(i >> 8 & 0xff) as usize]
        ^ t[2][(i >> 16 & 0xff) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// Sobol's dimension 1 before bit reversal: bit j of the result is the parity of the bits k of
/// `i` with j a bit-subset of k.
#[inline]
pub(super) fn pascal(mut a: u32) -> u32 {
    a ^= (a >> 1) & 0x5555_5555;
    a ^= (a >> 2) & 0x3333_3333;
    a ^= (a >> 4) & 0x0f0f_0f0f;
    a ^= (a >> 8) & 0x00ff_00ff;
    a ^= (a >> 16) & 0x0000_ffff;
    a
}
