//! The CDR (OMG XCDR1) encoding ROS 2 serializes its messages in, read by hand for the
//! few types a bag's lidar replay needs.
//!
//! A serialized message opens with a 4-byte encapsulation header: `00 01` for little-endian
//! plain CDR (what every ROS 2 middleware writes), `00 00` for big-endian, then two option
//! bytes. Each primitive is aligned to its own size, counted from the end of that header;
//! a string is a `u32` length (its NUL included), the bytes and the NUL; a sequence is a
//! `u32` count and its elements. Nothing here trusts a length: every read is checked
//! against the bytes there are.

/// Why a message's bytes are not the CDR of the type they were read as.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    #[error("{0} bytes: too short for a CDR encapsulation header")]
    NoHeader(usize),
    #[error("encapsulation {0:#06x} is not plain CDR (0x0000 or 0x0001)")]
    Representation(u16),
    #[error("ends at byte {len} while reading {what} (needs {need} bytes at {at})")]
    Truncated {
        what: &'static str,
        at: usize,
        need: usize,
        len: usize,
    },
    #[error("{what}: {reason}")]
    Invalid { what: &'static str, reason: String },
}

/// A reader over one serialized message.
#[derive(Debug)]
pub struct Cdr<'a> {
    data: &'a [u8],
    /// Next byte to read, from the start of `data` (the header included).
    at: usize,
    little_endian: bool,
}

/// Bytes of the encapsulation header; alignment counts from its end.
const HEADER: usize = 4;

impl<'a> Cdr<'a> {
    /// A reader positioned after the encapsulation header of `data`.
    pub fn new(data: &'a [u8]) -> Result<Self, CdrError> {
        if data.len() < HEADER {
            return Err(CdrError::NoHeader(data.len()));
        }
        let representation = u16::from_be_bytes([data[0], data[1]]);
        let little_endian = match representation {
            0x0000 => false,
            0x0001 => true,
            other => return Err(CdrError::Representation(other)),
        };
        Ok(Self {
            data,
            at: HEADER,
            little_endian,
        })
    }

    /// Takes `N` bytes (2, 4 or 8) aligned to `N`.
    fn bytes<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], CdrError> {
        let offset = self.at - HEADER;
        let padding = (N - offset % N) % N;
        let start = self.at + padding;
        let end = start.checked_add(N).filter(|&end| end <= self.data.len());
        let Some(end) = end else {
            return Err(self.truncated(what, start, N));
        };
        let mut out = [0; N];
        out.copy_from_slice(&self.data[start..end]);
        self.at = end;
        Ok(out)
    }

    fn truncated(&self, what: &'static str, at: usize, need: usize) -> CdrError {
        CdrError::Truncated {
            what,
            at,
            need,
            len: self.data.len(),
        }
    }

    pub fn u32(&mut self, what: &'static str) -> Result<u32, CdrError> {
        let bytes = self.bytes::<4>(what)?;
        Ok(if self.little_endian {
            u32::from_le_bytes(bytes)
        } else {
            u32::from_be_bytes(bytes)
        })
    }

    pub fn i32(&mut self, what: &'static str) -> Result<i32, CdrError> {
        Ok(self.u32(what)? as i32)
    }

    pub fn f32(&mut self, what: &'static str) -> Result<f32, CdrError> {
        Ok(f32::from_bits(self.u32(what)?))
    }

    pub fn f64(&mut self, what: &'static str) -> Result<f64, CdrError> {
        let bytes = self.bytes::<8>(what)?;
        Ok(f64::from_bits(if self.little_endian {
            u64::from_le_bytes(bytes)
        } else {
            u64::from_be_bytes(bytes)
        }))
    }

    /// A sequence's or string's length, checked to fit in what is left at `size` bytes an
    /// element, so that a damaged count cannot ask for memory the message does not have.
    pub fn count(&mut self, what: &'static str, size: usize) -> Result<usize, CdrError> {
        let count = self.u32(what)? as usize;
        let left = self.data.len() - self.at;
        if count.saturating_mul(size.max(1)) > left {
            return Err(self.truncated(what, self.at, count.saturating_mul(size.max(1))));
        }
        Ok(count)
    }

    /// A string (UTF-8, NUL-terminated).
    pub fn string(&mut self, what: &'static str) -> Result<String, CdrError> {
        let length = self.count(what, 1)?;
        let bytes = &self.data[self.at..self.at + length];
        self.at += length;
        // The length counts the NUL; an empty string may be written with length 0.
        let text = match bytes.split_last() {
            Some((0, text)) => text,
            Some(_) => {
                return Err(CdrError::Invalid {
                    what,
                    reason: "the string does not end with NUL".into(),
                });
            }
            None => bytes,
        };
        String::from_utf8(text.to_vec()).map_err(|_| CdrError::Invalid {
            what,
            reason: "the string is not UTF-8".into(),
        })
    }

    /// A sequence of `f32`.
    pub fn f32_sequence(&mut self, what: &'static str) -> Result<Vec<f32>, CdrError> {
        let count = self.count(what, 4)?;
        (0..count).map(|_| self.f32(what)).collect()
    }

    /// `N` `f64` (a fixed-size array: no count).
    pub fn f64_array<const N: usize>(&mut self, what: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        for value in &mut out {
            *value = self.f64(what)?;
        }
        Ok(out)
    }
}

/// Builds CDR bytes, little- or big-endian, for the tests of the decoders.
#[cfg(test)]
pub(crate) mod write {
    /// A message being written.
    pub struct CdrWriter {
        pub bytes: Vec<u8>,
        little_endian: bool,
    }

    impl CdrWriter {
        pub fn new(little_endian: bool) -> Self {
            Self {
                bytes: vec![0, u8::from(little_endian), 0, 0],
                little_endian,
            }
        }

        fn align(&mut self, size: usize) {
            while !(self.bytes.len() - 4).is_multiple_of(size) {
                self.bytes.push(0);
            }
        }

        pub fn u32(&mut self, value: u32) -> &mut Self {
            self.align(4);
            let bytes = if self.little_endian {
                value.to_le_bytes()
            } else {
                value.to_be_bytes()
            };
            self.bytes.extend_from_slice(&bytes);
            self
        }

        pub fn f32(&mut self, value: f32) -> &mut Self {
            self.u32(value.to_bits())
        }

        pub fn f64(&mut self, value: f64) -> &mut Self {
            self.align(8);
            let bytes = if self.little_endian {
                value.to_bits().to_le_bytes()
            } else {
                value.to_bits().to_be_bytes()
            };
            self.bytes.extend_from_slice(&bytes);
            self
        }

        pub fn string(&mut self, text: &str) -> &mut Self {
            self.u32(text.len() as u32 + 1);
            self.bytes.extend_from_slice(text.as_bytes());
            self.bytes.push(0);
            self
        }

        /// A `std_msgs/Header`.
        pub fn header(&mut self, sec: i32, nanosec: u32, frame: &str) -> &mut Self {
            self.u32(sec as u32).u32(nanosec).string(frame)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::write::CdrWriter;
    use super::*;

    #[test]
    fn primitives_are_aligned_from_the_end_of_the_header() {
        for little_endian in [true, false] {
            let mut w = CdrWriter::new(little_endian);
            w.string("ab").f64(1.5).f32(-2.0).u32(7);
            // "ab\0" after its length ends at 7; the f64 is padded to 8.
            assert_eq!(w.bytes.len(), 4 + 8 + 8 + 4 + 4);
            let mut r = Cdr::new(&w.bytes).unwrap();
            assert_eq!(r.string("s").unwrap(), "ab");
            assert_eq!(r.f64("d").unwrap(), 1.5);
            assert_eq!(r.f32("f").unwrap(), -2.0);
            assert_eq!(r.u32("u").unwrap(), 7);
        }
    }

    #[test]
    fn damaged_bytes_are_errors_not_panics() {
        assert_eq!(Cdr::new(&[0, 1]).unwrap_err(), CdrError::NoHeader(2));
        assert_eq!(
            Cdr::new(&[0, 7, 0, 0]).unwrap_err(),
            CdrError::Representation(7)
        );
        let mut w = CdrWriter::new(true);
        w.u32(u32::MAX);
        let mut r = Cdr::new(&w.bytes).unwrap();
        assert!(matches!(
            r.f32_sequence("ranges"),
            Err(CdrError::Truncated { what: "ranges", .. })
        ));
        let mut r = Cdr::new(&[0, 1, 0, 0, 1, 0]).unwrap();
        assert!(matches!(r.u32("x"), Err(CdrError::Truncated { .. })));
        let mut w = CdrWriter::new(true);
        w.u32(2);
        w.bytes.extend_from_slice(b"ab");
        let mut r = Cdr::new(&w.bytes).unwrap();
        assert!(matches!(r.string("frame"), Err(CdrError::Invalid { .. })));
    }
}
