//! The SCIP line checksum: the lower 6 bits of the sum of a line's data bytes, plus `0x30`,
//! sent as the line's last character.

use super::ScipError;
use super::encoding::OFFSET;

/// The checksum character of `data`.
pub fn checksum(data: &[u8]) -> u8 {
    let sum = data.iter().fold(0u8, |sum, &b| sum.wrapping_add(b));
    (sum & 0x3f) + OFFSET
}

/// Splits a line (without its LF) into its data and checks the data against the last
/// character. `line` is the line's number in the reply, for the error.
pub fn verify(text: &[u8], line: usize) -> Result<&[u8], ScipError> {
    let Some((&found, data)) = text.split_last() else {
        return Err(ScipError::Truncated("checksum"));
    };
    let expected = checksum(data);
    if found == expected {
        Ok(data)
    } else {
        Err(ScipError::Checksum {
            line,
            expected: char::from(expected),
            found: char::from(found),
        })
    }
}

/// Checks an information line of `VV`, `PP` or `II` (`NAME:VALUE;S`) and returns
/// `NAME:VALUE`.
///
/// The specification sums the text before the `;`. Hokuyo's own library also accepts a sum
/// that includes the `;`, and UTM-class firmware leaves a trailing `<-comment` out of the
/// sum, so all three are accepted.
pub fn verify_information(text: &[u8], line: usize) -> Result<&[u8], ScipError> {
    let [data @ .., b';', found] = text else {
        return Err(ScipError::malformed(
            "information line (NAME:VALUE;sum)",
            text,
        ));
    };
    let with_separator = &text[..text.len() - 1];
    let without_comment = find(data, b"<-").map(|at| &data[..at]);
    let candidates = [Some(data), Some(with_separator), without_comment];
    if candidates.iter().flatten().any(|c| checksum(c) == *found) {
        Ok(data)
    } else {
        Err(ScipError::Checksum {
            line,
            expected: char::from(checksum(data)),
            found: char::from(*found),
        })
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_lines_of_the_specification() {
        // "00P": '0' + '0' = 0x60, lower 6 bits 0x20, + 0x30 = 'P'.
        assert_eq!(checksum(b"00"), b'P');
        // "99b": 0x39 + 0x39 = 0x72, lower 6 bits 0x32, + 0x30 = 'b'.
        assert_eq!(checksum(b"99"), b'b');
        assert_eq!(verify(b"00P", 1), Ok(&b"00"[..]));
        assert_eq!(verify(b"99b", 1), Ok(&b"99"[..]));
    }

    #[test]
    fn information_lines_of_the_examples() {
        // The PP, VV and II replies of a URG-04LX as Hokuyo's SCIP documentation prints
        // them: each line checks out, and its data is the line without `;` and the sum.
        for line in [
            &b"MODL:URG-04LX(Hokuyo Automatic Co.,Ltd.);N"[..],
            b"DMIN:20;4",
            b"DMAX:5600;_",
            b"ARES:1024;\\",
            b"AMIN:44;7",
            b"AMAX:725;o",
            b"AFRT:384;6",
            b"SCAN:600;e",
            b"VEND:Hokuyo Automatic Co.,Ltd.;[",
            b"PROD:SOKUIKI Sensor URG-04LX;[",
            b"FIRM:3.1.00(18/Jan./2007);`",
            b"PROT:SCIP 2.0;N",
            b"SERI:H0614967;V",
            b"LASR:OFF;7",
            b"SCSP:Initial(600[rpm])<-Default setting by user;A",
            b"MESM:IDLE;:",
            b"STAT:Sensor works well.;8",
        ] {
            let data = verify_information(line, 2);
            assert_eq!(data, Ok(&line[..line.len() - 2]), "{line:?}");
        }
    }

    #[test]
    fn a_trailing_comment_may_be_left_out_of_the_sum() {
        // UTM-class firmware: the sum covers "SCSP:Initial(600[rpm])" only.
        let data = b"SCSP:Initial(600[rpm])";
        let mut line = b"SCSP:Initial(600[rpm])<-Default setting by user;".to_vec();
        line.push(checksum(data));
        assert!(verify_information(&line, 3).is_ok());
    }

    #[test]
    fn wrong_checksums_are_reported_with_their_line() {
        assert_eq!(
            verify(b"00Q", 1),
            Err(ScipError::Checksum {
                line: 1,
                expected: 'P',
                found: 'Q'
            })
        );
        assert!(matches!(
            verify_information(b"DMIN:20;5", 4),
            Err(ScipError::Checksum { line: 4, .. })
        ));
        assert_eq!(verify(b"", 2), Err(ScipError::Truncated("checksum")));
        assert!(matches!(
            verify_information(b"DMIN:204", 2),
            Err(ScipError::Malformed { .. })
        ));
        assert!(verify_information(b";", 2).is_err());
        assert!(verify_information(b"", 2).is_err());
    }
}
