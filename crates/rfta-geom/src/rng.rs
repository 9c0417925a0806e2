//! A small seeded random number generator and a hash for per-item streams.
//!
//! rfta derives every random choice from the user's seed and the item's index, never from
//! shared generator state, so results do not depend on the thread count.

/// Mixes a 64-bit value (the SplitMix64 finaliser, Steele, Lea and Flood 2014).
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A well-mixed 64-bit hash of a seed and an index, for a per-item stream: `Rng::new(hash(seed, i))`.
pub fn hash(seed: u64, index: u64) -> u64 {
    mix64(mix64(seed) ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03))
}

/// The xoshiro256++ generator (Blackman and Vigna 2021), seeded through SplitMix64.
#[derive(Debug, Clone)]
pub struct Rng {
    s: [u64; 4],
}

impl Rng {
    /// A generator from a seed; equal seeds give equal streams on every platform.
    pub fn new(seed: u64) -> Self {
        let mut z = seed;
        let mut s = [0u64; 4];
        for word in &mut s {
            *word = mix64(z);
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        }
        Self { s }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// A uniform double in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A uniform integer in `[0, n)` (Lemire's multiply-shift with rejection); `n` must be positive.
    pub fn below(&mut self, n: u64) -> u64 {
        debug_assert!(n > 0);
        let threshold = n.wrapping_neg() % n.max(1);
        loop {
            let m = (self.next_u64() as u128) * (n as u128);
            if (m as u64) >= threshold {
                return (m >> 64) as u64;
            }
        }
    }
}

/// A batch of `k` positions drawn uniformly *with replacement* from `0..n` with `seed` (the
/// reference's batching, Sellán et al. 2024 §4.4: about `n (1 - exp(-k / n))` distinct ones), or
/// `None` for all of them: `k` of 0, or of at least `n`.
pub fn batch_with_replacement(n: usize, k: usize, seed: u64) -> Option<Vec<u32>> {
    if k == 0 || k >= n {
        return None;
    }
    let mut rng = Rng::new(seed);
    Some((0..k).map(|_| rng.below(n as u64) as u32).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_batch_holds_positions_below_n_and_all_is_none() {
        let b = batch_with_replacement(50, 20, 3).expect("a batch");
        assert_eq!(b.len(), 20);
        assert!(b.iter().all(|&i| i < 50));
        assert_eq!(b, batch_with_replacement(50, 20, 3).expect("the same"));
        assert!(b.windows(2).any(|w| w[0] != w[1]));
        assert!(batch_with_replacement(50, 0, 3).is_none());
        assert!(batch_with_replacement(50, 50, 3).is_none());
    }

    #[test]
    fn uniform_doubles_have_the_right_mean_and_range() {
        let mut rng = Rng::new(7);
        let n = 100_000;
        let xs: Vec<f64> = (0..n).map(|_| rng.next_f64()).collect();
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is 1/sqrt(12 n) ~ 0.0009: allow 5 sigma.
        assert!((mean - 0.5).abs() < 0.0046, "mean {mean}");
    }

    #[test]
    fn below_is_unbiased_over_a_small_range() {
        let mut rng = Rng::new(1);
        let mut counts = [0u32; 6];
        for _ in 0..60_000 {
            counts[rng.below(6) as usize] += 1;
        }
        // Expected 10,000 each, sd ~ 91: allow 5 sigma.
        assert!(
            counts.iter().all(|&c| (c as i64 - 10_000).abs() < 460),
            "{counts:?}"
        );
    }

    #[test]
    fn streams_depend_only_on_the_seed() {
        let a: Vec<u64> = (0..4).map(|i| Rng::new(hash(42, i)).next_u64()).collect();
        let b: Vec<u64> = (0..4).map(|i| Rng::new(hash(42, i)).next_u64()).collect();
        assert_eq!(a, b);
        assert_ne!(a[0], a[1]);
    }
}
