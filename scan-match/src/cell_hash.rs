//! A hash for integer grid cells. The standard library's SipHash resists adversarial keys,
//! which cell coordinates never are, at several times the cost in the matcher's inner loop.
//! The table places entries by the hash's low bits, and a product's low bits depend only
//! on the key's low bits (here: the cell's y), so the result is mixed once more at the
//! end (splitmix64's finaliser): without it every cell of a row would share a bucket.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// Multiply-rotate hashing of the one `u64` a cell key writes (Fx-style), mixed at the end.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, value: u64) {
        const K: u64 = 0x517c_c1b7_2722_0a95;
        self.0 = (self.0.rotate_left(5) ^ value).wrapping_mul(K);
    }
}

pub(crate) type CellMap<V> = HashMap<u64, V, BuildHasherDefault<CellHasher>>;
pub(crate) type CellSet = HashSet<u64, BuildHasherDefault<CellHasher>>;

/// The key of the cell of edge `size` holding `(x, y)`; two `i32` packed into a `u64`.
#[inline]
pub(crate) fn cell_key(x: f64, y: f64, size: f64) -> u64 {
    pack(floor_i32(x / size), floor_i32(y / size))
}

/// `floor(v)` as an integer (saturating, as `as` does) without the library call the
/// baseline x86-64 target makes of `f64::floor`.
#[inline]
pub(crate) fn floor_i32(v: f64) -> i32 {
    let t = v as i32;
    if f64::from(t) > v { t - 1 } else { t }
}

#[inline]
pub(crate) fn pack(ix: i32, iy: i32) -> u64 {
    (u64::from(ix as u32) << 32) | u64::from(iy as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_cells_differ_and_negative_coordinates_work() {
        assert_ne!(cell_key(0.01, 0.0, 0.1), cell_key(-0.01, 0.0, 0.1));
        assert_ne!(cell_key(0.0, 0.01, 0.1), cell_key(0.0, -0.01, 0.1));
        assert_eq!(cell_key(0.01, 0.02, 0.1), cell_key(0.09, 0.05, 0.1));
        assert_eq!(pack(-1, 2), cell_key(-0.05, 0.25, 0.1));
        for v in [-2.5, -1.0, -0.5, 0.0, 0.3, 1.0, 2.7] {
            assert_eq!(floor_i32(v), v.floor() as i32);
        }
    }
}
