//! Random streams that do not depend on the thread count: each particle draws from its own
//! generator keyed by `(seed, scan, purpose, particle)`, so whichever thread updates a
//! particle, it sees the same numbers.
//!
//! The generator is xoshiro256++ seeded through SplitMix64 from a mixed 64-bit key: a
//! particle draws a handful of numbers per scan, and starting a generator must cost little
//! next to them (positioning a ChaCha8 keystream computed four blocks every time, 3 % of
//! the filter).

use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// What a stream is used for; each has its own generators per scan.
#[derive(Debug, Clone, Copy)]
enum Purpose {
    Particle = 0,
    Resample = 1,
    Proposal = 2,
}

/// SplitMix64's finaliser: a bijection of `u64` whose outputs for nearby inputs look
/// unrelated.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The keyed generators of one run.
#[derive(Debug, Clone)]
pub(crate) struct Streams {
    key: u64,
}

impl Streams {
    pub fn new(seed: u64) -> Self {
        Self { key: mix(seed) }
    }

    fn at(&self, scan: u64, purpose: Purpose, index: u64) -> Xoshiro256PlusPlus {
        // Chained mixing, one field at a time: distinct fields give unrelated keys.
        let key = mix(mix(mix(self.key ^ scan) ^ purpose as u64) ^ index);
        Xoshiro256PlusPlus::seed_from_u64(key)
    }

    /// The generator of particle `particle` in scan `scan`.
    pub fn particle(&self, scan: u64, particle: usize) -> Xoshiro256PlusPlus {
        self.at(scan, Purpose::Particle, particle as u64)
    }

    /// The generator of particle `particle`'s pose correction in scan `scan`.
    pub fn proposal(&self, scan: u64, particle: usize) -> Xoshiro256PlusPlus {
        self.at(scan, Purpose::Proposal, particle as u64)
    }

    /// The generator of the resampling step of scan `scan`.
    pub fn resample(&self, scan: u64) -> Xoshiro256PlusPlus {
        self.at(scan, Purpose::Resample, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn streams_are_repeatable_and_distinct() {
        let streams = Streams::new(7);
        let a: u64 = streams.particle(3, 5).random();
        assert_eq!(a, streams.particle(3, 5).random::<u64>());
        assert_ne!(a, streams.particle(3, 6).random::<u64>());
        assert_ne!(a, streams.particle(4, 5).random::<u64>());
        assert_ne!(a, streams.resample(3).random::<u64>());
        assert_ne!(a, streams.proposal(3, 5).random::<u64>());
        assert_ne!(a, Streams::new(8).particle(3, 5).random::<u64>());
    }

    #[test]
    fn neighbouring_streams_are_unrelated() {
        // The first uniform of 4000 consecutive particles: uniform, and no correlation
        // between neighbours (the keys differ in one low bit).
        let streams = Streams::new(1);
        let u: Vec<f64> = (0..4000).map(|i| streams.particle(9, i).random()).collect();
        let n = u.len() as f64;
        let mean = u.iter().sum::<f64>() / n;
        let variance = u.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        let lag1 = u
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / ((n - 1.0) * variance);
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert!((variance - 1.0 / 12.0).abs() < 0.005, "{variance}");
        assert!(lag1.abs() < 0.05, "{lag1}");
    }
}
