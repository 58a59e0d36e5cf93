//! Per-sample deterministic random numbers.
//!
//! Every camera sample owns a stream seeded from (seed, pixel, sample index), so an image
//! depends only on the scene, the seed and the sample count: never on which thread ran which
//! pixel. Two renders with the same seed share their random numbers (common random numbers),
//! which is what makes the two members of an antithetic pair comparable.

/// SplitMix64's avalanche: a bijective 64-bit mixer with good diffusion. The library's
/// [`plateau_free::seeding::mix`] is SplitMix64's whole step (it adds the golden-ratio increment
/// first), so `mix64(z)` is `mix(z - increment)`. Written out here rather than called: `mix`
/// goes through rand_xoshiro's `seed_from_u64`, which is not inlined across crates, and a
/// camera sample draws several times (tested equal to `mix` bit for bit).
#[inline(always)]
fn mix64(z: u64) -> u64 {
    let z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    let z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64's increment, the golden ratio in 64 bits.
const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// A SplitMix64 stream; cheap (two multiplies per 64 bits), no allocation, `Copy`.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    state: u64,
}

impl Sampler {
    /// The stream of one camera sample. Distinct (pixel, sample) pairs give unrelated streams
    /// because the key is mixed twice before use.
    #[inline(always)]
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        let key = ((pixel as u64) << 32) | sample as u64;
        Self {
            state: mix64(seed ^ mix64(key.wrapping_add(0x632B_E59B_D9B4_E019))),
        }
    }

    /// The next 64 random bits.
    #[inline(always)]
    pub fn next_u64(&mut self) -> u64 {
        let z = self.state;
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(z.wrapping_add(GOLDEN))
    }

    /// A uniform number in [0, 1) with 24 bits of resolution (exactly representable in f32).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform numbers in [0, 1) from one 64-bit draw (24 bits each).
    #[inline(always)]
    pub fn next_2d(&mut self) -> (f32, f32) {
        let bits = self.next_u64();
        let a = (bits >> 40) as f32 * (1.0 / 16_777_216.0);
        let b = ((bits >> 8) & 0x00FF_FFFF) as f32 * (1.0 / 16_777_216.0);
        (a, b)
    }
}

/// A stateless hash to a uniform number in [0, 1), for deterministic scene set-up
/// (e.g. SORT's scrambled start, TEXTURE's procedural pattern).
pub fn hash_unit(seed: u64, index: u64) -> f64 {
    (mix64(seed ^ mix64(index.wrapping_add(0xD1B5_4A32_D192_ED03))) >> 11) as f64
        * (1.0 / 9_007_199_254_740_992.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let mut s = Sampler::new(7, 3, 1);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let (a, b) = s.next_2d();
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
            sum += (a + b) as f64;
        }
        let mean = sum / (2 * n) as f64;
        assert!((mean - 0.5).abs() < 3e-3, "mean {mean}");
    }

    #[test]
    fn mix64_is_the_library_mix_without_its_increment() {
        let mut z = 0x0123_4567_89AB_CDEFu64;
        for k in 0..10_000u64 {
            z = z.rotate_left(17) ^ k.wrapping_mul(GOLDEN);
            for v in [z, 0, u64::MAX, k] {
                assert_eq!(
                    mix64(v),
                    plateau_free::seeding::mix(v.wrapping_sub(GOLDEN)),
                    "{v}"
                );
            }
        }
        let mut s = Sampler::new(3, 5, 7);
        let start = s.state;
        assert_eq!(s.next_u64(), plateau_free::seeding::mix(start));
    }

    #[test]
    fn streams_differ() {
        let a = Sampler::new(1, 0, 0).next_u64();
        let b = Sampler::new(1, 0, 1).next_u64();
        let c = Sampler::new(1, 1, 0).next_u64();
        let d = Sampler::new(2, 0, 0).next_u64();
        assert!(a != b && a != c && a != d && b != c);
    }
}
