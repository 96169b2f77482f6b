//! SCIP's character encodings: a value is cut into 6-bit groups, most significant first, and
//! each group is sent as the printable character `0x30 + group`.
//!
//! Ranges use 3 characters (`MD`, `ME`: 18 bits, up to 262 143 mm) or 2 (`MS`: 12 bits, up
//! to 4 095 mm); time stamps use 4 (24 bits of milliseconds).

use super::ScipError;

/// Added to every 6-bit group to make it a printable character.
pub const OFFSET: u8 = 0x30;
/// The widest value SCIP sends: 4 characters, 24 bits.
pub const MAX_WIDTH: usize = 4;
/// Bits carried by one character.
const BITS: u32 = 6;

/// Decodes one value of `chars.len()` (1 to 4) characters.
pub fn decode(chars: &[u8]) -> Result<u32, ScipError> {
    check_width(chars.len())?;
    chars
        .iter()
        .enumerate()
        .try_fold(0u32, |value, (position, &byte)| {
            let group = group_of(byte).ok_or(ScipError::BadCharacter { byte, position })?;
            Ok((value << BITS) | u32::from(group))
        })
}

/// Decodes consecutive values of `width` characters each.
pub fn decode_values(data: &[u8], width: usize) -> Result<Vec<u32>, ScipError> {
    check_width(width)?;
    if !data.len().is_multiple_of(width) {
        return Err(ScipError::PartialValue {
            len: data.len(),
            width,
        });
    }
    data.chunks_exact(width)
        .enumerate()
        .map(|(i, chunk)| {
            decode(chunk).map_err(|e| match e {
                // Report the position in the whole data, not in the value.
                ScipError::BadCharacter { byte, position } => ScipError::BadCharacter {
                    byte,
                    position: i * width + position,
                },
                other => other,
            })
        })
        .collect()
}

/// Appends `value` encoded in `width` characters to `out`.
pub fn encode_into(value: u32, width: usize, out: &mut Vec<u8>) -> Result<(), ScipError> {
    check_width(width)?;
    // `width` is at most 4, so the shift stays below 32.
    let bits = BITS * width as u32;
    if u64::from(value) >= 1u64 << bits {
        return Err(ScipError::ValueTooLarge { value, width });
    }
    for i in (0..width as u32).rev() {
        // Masked to 6 bits, so the cast and the addition cannot overflow.
        out.push(OFFSET + ((value >> (BITS * i)) & 0x3f) as u8);
    }
    Ok(())
}

/// `value` encoded in `width` characters.
pub fn encode(value: u32, width: usize) -> Result<Vec<u8>, ScipError> {
    let mut out = Vec::with_capacity(width);
    encode_into(value, width, &mut out)?;
    Ok(out)
}

/// The largest value `width` characters carry.
pub fn max_value(width: usize) -> Result<u32, ScipError> {
    check_width(width)?;
    Ok(((1u64 << (BITS * width as u32)) - 1) as u32)
}

fn check_width(width: usize) -> Result<(), ScipError> {
    if (1..=MAX_WIDTH).contains(&width) {
        Ok(())
    } else {
        Err(ScipError::BadWidth { width })
    }
}

fn group_of(byte: u8) -> Option<u8> {
    byte.checked_sub(OFFSET).filter(|&group| group <= 0x3f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worked_examples_of_the_specification() {
        // The SCIP 2.0 specification's examples (section 6, figures 2 to 7): two, three and
        // four characters.
        for (value, text) in [
            // 1234 mm = 010011 010010 = 0x13 0x12 -> 0x43 0x42 = "CB"
            (1234, &b"CB"[..]),
            // 5432 mm = 000001 010100 111000 = 0x01 0x14 0x38 -> "1Dh"
            (5432, b"1Dh"),
            // 16 000 000 ms = 111101 000010 010000 000000 = 0x3d 0x02 0x10 0x00 -> "m2@0"
            (16_000_000, b"m2@0"),
        ] {
            assert_eq!(decode(text), Ok(value));
            assert_eq!(encode(value, text.len()).unwrap(), text);
        }
    }

    #[test]
    fn extremes_of_the_alphabet() {
        assert_eq!(decode(b"000"), Ok(0));
        assert_eq!(decode(b"ooo"), Ok((1 << 18) - 1));
        assert_eq!(decode(b"oo"), Ok(4095));
        assert_eq!(max_value(3), Ok(262_143));
        assert_eq!(max_value(4), Ok(16_777_215));
    }

    #[test]
    fn values_round_trip() {
        for width in 1..=4 {
            let max = max_value(width).unwrap();
            let step = (max / 997).max(1);
            for value in (0..=max).step_by(step as usize).chain([max]) {
                assert_eq!(decode(&encode(value, width).unwrap()), Ok(value));
            }
        }
    }

    #[test]
    fn characters_outside_the_alphabet_are_refused() {
        assert_eq!(
            decode(b"1/h"),
            Err(ScipError::BadCharacter {
                byte: b'/',
                position: 1
            })
        );
        assert_eq!(
            decode(b"p00"),
            Err(ScipError::BadCharacter {
                byte: b'p',
                position: 0
            })
        );
        assert_eq!(
            decode(&[0x31, 0xff, 0x31]),
            Err(ScipError::BadCharacter {
                byte: 0xff,
                position: 1
            })
        );
        assert_eq!(
            decode(b"\n00"),
            Err(ScipError::BadCharacter {
                byte: b'\n',
                position: 0
            })
        );
    }

    #[test]
    fn widths_outside_one_to_four_are_refused() {
        assert_eq!(decode(b""), Err(ScipError::BadWidth { width: 0 }));
        assert_eq!(decode(b"00000"), Err(ScipError::BadWidth { width: 5 }));
        assert!(encode(1, 0).is_err());
        assert!(decode_values(b"000", 0).is_err());
    }

    #[test]
    fn values_too_large_for_their_width_are_refused() {
        assert_eq!(
            encode(4096, 2),
            Err(ScipError::ValueTooLarge {
                value: 4096,
                width: 2
            })
        );
        assert!(encode(u32::MAX, 4).is_err());
    }

    #[test]
    fn a_run_of_values_decodes_and_reports_positions() {
        assert_eq!(
            decode_values(b"1DhCB0", 3),
            Ok(vec![5432, 19 << 12 | 18 << 6])
        );
        assert_eq!(decode_values(b"CB0000", 2), Ok(vec![1234, 0, 0]));
        assert_eq!(
            decode_values(b"1Dh1D", 3),
            Err(ScipError::PartialValue { len: 5, width: 3 })
        );
        assert_eq!(
            decode_values(b"1Dh1 h", 3),
            Err(ScipError::BadCharacter {
                byte: b' ',
                position: 4
            })
        );
    }
}
