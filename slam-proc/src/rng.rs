//! Random streams that do not depend on the thread count: each particle draws from its own
//! position `(seed, scan, particle)` of a ChaCha8 keystream, so whichever thread updates a
//! particle, it sees the same numbers.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Words reserved for one particle in one scan: far more than a step ever draws.
const WORDS_PER_PARTICLE: u128 = 1 << 32;

/// What a stream is used for; each purpose has its own ChaCha stream per scan.
#[derive(Debug, Clone, Copy)]
enum Purpose {
    Particle = 0,
    Resample = 1,
    Proposal = 2,
}

/// Purposes per scan.
const PURPOSES: u64 = 3;

/// The keyed generator, built once from the seed and repositioned for each use.
#[derive(Debug, Clone)]
pub(crate) struct Streams {
    base: ChaCha8Rng,
}

impl Streams {
    pub fn new(seed: u64) -> Self {
        Self {
            base: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    fn at(&self, scan: u64, purpose: Purpose, offset: u128) -> ChaCha8Rng {
        let mut rng = self.base.clone();
        // One stream id per scan and purpose.
        rng.set_stream(scan.wrapping_mul(PURPOSES).wrapping_add(purpose as u64));
        rng.set_word_pos(offset);
        rng
    }

    /// The generator of particle `particle` in scan `scan`.
    pub fn particle(&self, scan: u64, particle: usize) -> ChaCha8Rng {
        self.at(
            scan,
            Purpose::Particle,
            particle as u128 * WORDS_PER_PARTICLE,
        )
    }

    /// The generator of particle `particle`'s pose correction in scan `scan`.
    pub fn proposal(&self, scan: u64, particle: usize) -> ChaCha8Rng {
        self.at(
            scan,
            Purpose::Proposal,
            particle as u128 * WORDS_PER_PARTICLE,
        )
    }

    /// The generator of the resampling step of scan `scan`.
    pub fn resample(&self, scan: u64) -> ChaCha8Rng {
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
}
