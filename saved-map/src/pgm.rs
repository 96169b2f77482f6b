//! Binary greyscale PGM (`P5`, Netpbm), the image format of a map_server map.

/// Why bytes are not a PGM this crate can read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PgmError {
    /// Not a binary 8-bit PGM at all (another format, or another Netpbm kind).
    #[error("not a binary 8-bit PGM: {0}")]
    Foreign(String),
    /// The file ends inside the header.
    #[error("truncated: the file ends inside the header")]
    TruncatedHeader,
    /// The header promises more than the file holds.
    #[error("truncated: the header promises {expected} bytes of pixels, the file has {found}")]
    Truncated { expected: usize, found: usize },
}

/// A greyscale image, rows from the top, pixels scaled to 0-255.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pgm {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<u8>,
}

/// `P5` bytes of a `width` x `height` image whose rows, top first, are `pixels`.
pub fn encode_pgm(width: usize, height: usize, pixels: &[u8]) -> Vec<u8> {
    let header = format!("P5\n{width} {height}\n255\n");
    let mut bytes = Vec::with_capacity(header.len() + pixels.len());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(pixels);
    bytes
}

impl Pgm {
    /// Reads a `P5` image with a maximum value up to 255 (one byte a pixel), as Netpbm
    /// defines it: whitespace-separated header fields, `#` comments to the end of a line,
    /// one whitespace character after the maximum value, then the rows.
    pub fn decode(bytes: &[u8]) -> Result<Self, PgmError> {
        if bytes.len() < 2 || &bytes[..2] != b"P5" {
            let what = match bytes.get(..2) {
                Some(b"P2") => "an ASCII PGM (P2)".to_owned(),
                Some([b'P', k]) if k.is_ascii_digit() => format!("a Netpbm P{}", *k as char),
                _ => "no P5 magic number".to_owned(),
            };
            return Err(PgmError::Foreign(what));
        }
        let mut at = 2;
        let mut fields = [0_usize; 3];
        for (n, field) in fields.iter_mut().enumerate() {
            loop {
                match bytes.get(at) {
                    Some(b'#') => {
                        while bytes.get(at).is_some_and(|&b| b != b'\n') {
                            at += 1;
                        }
                    }
                    Some(b) if b.is_ascii_whitespace() => at += 1,
                    _ => break,
                }
            }
            let start = at;
            while bytes.get(at).is_some_and(u8::is_ascii_digit) {
                at += 1;
            }
            if start == at {
                return match bytes.get(at) {
                    None => Err(PgmError::TruncatedHeader),
                    Some(_) => Err(PgmError::Foreign(format!(
                        "header field {} is not a number",
                        n + 1
                    ))),
                };
            }
            *field = std::str::from_utf8(&bytes[start..at])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| PgmError::Foreign(format!("header field {} is too large", n + 1)))?;
        }
        let [width, height, maxval] = fields;
        if !(1..=255).contains(&maxval) {
            return Err(PgmError::Foreign(format!(
                "maximum value {maxval}; only 1-255 (one byte a pixel) is read"
            )));
        }
        if width == 0 || height == 0 {
            return Err(PgmError::Foreign(format!(
                "an empty image ({width} x {height})"
            )));
        }
        match bytes.get(at) {
            Some(b) if b.is_ascii_whitespace() => at += 1,
            Some(_) => {
                return Err(PgmError::Foreign(
                    "no whitespace after the maximum value".into(),
                ));
            }
            None => return Err(PgmError::TruncatedHeader),
        }
        let expected = width
            .checked_mul(height)
            .ok_or_else(|| PgmError::Foreign(format!("{width} x {height} pixels")))?;
        let data = &bytes[at..];
        if data.len() < expected {
            return Err(PgmError::Truncated {
                expected,
                found: data.len(),
            });
        }
        let pixels = data[..expected]
            .iter()
            .map(|&v| ((usize::from(v) * 255 + maxval / 2) / maxval).min(255) as u8)
            .collect();
        Ok(Self {
            width,
            height,
            pixels,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_encoded_image_decodes_to_itself() {
        let pixels = [0, 254, 205, 0, 0, 254];
        let bytes = encode_pgm(3, 2, &pixels);
        assert!(bytes.starts_with(b"P5\n3 2\n255\n"));
        let pgm = Pgm::decode(&bytes).unwrap();
        assert_eq!((pgm.width, pgm.height), (3, 2));
        assert_eq!(pgm.pixels, pixels);
    }

    #[test]
    fn comments_and_smaller_maximum_values_are_read() {
        let pgm = Pgm::decode(b"P5 # made by hand\n2 # width\n1\n15\n\x0f\x00").unwrap();
        assert_eq!(pgm.pixels, [255, 0]);
    }

    #[test]
    fn other_formats_and_short_files_are_refused_by_name() {
        assert!(matches!(
            Pgm::decode(b"\x89PNG\r\n"),
            Err(PgmError::Foreign(_))
        ));
        assert_eq!(
            Pgm::decode(b"P2\n1 1\n255\n0\n"),
            Err(PgmError::Foreign("an ASCII PGM (P2)".into()))
        );
        assert!(matches!(
            Pgm::decode(b"P5\n2 2\n65535\n"),
            Err(PgmError::Foreign(_))
        ));
        assert_eq!(
            Pgm::decode(b"P5\n2 2\n255\n\x00\x00\x00"),
            Err(PgmError::Truncated {
                expected: 4,
                found: 3
            })
        );
        assert_eq!(Pgm::decode(b"P5\n2 "), Err(PgmError::TruncatedHeader));
    }
}
