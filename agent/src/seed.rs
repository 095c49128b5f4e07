//! Seed derivation: every random stream of a run comes from the experiment seed.

/// SplitMix64 finaliser: a bijective mix of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of run `run` of an experiment seeded with `seed`.
pub fn run_seed(seed: u64, run: u32) -> u64 {
    mix(mix(seed) ^ u64::from(run))
}

#[cfg(test)]
mod tests {
    #[test]
    fn runs_get_distinct_seeds() {
        let seeds: std::collections::HashSet<u64> =
            (0..1000).map(|r| super::run_seed(1, r)).collect();
        assert_eq!(seeds.len(), 1000);
        assert_ne!(super::run_seed(1, 0), super::run_seed(2, 0));
    }
}
