//! Seed mixing: how the engine derives the seed of each restart and thread from the user's seed.
//! `mbgc` mixes its seeds with the same function (it re-exports this one).

/// SplitMix64's output function (Steele et al. 2014): a bijection of u64 that scatters
/// neighbouring inputs, used to derive independent seeds from (seed, index) pairs.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
