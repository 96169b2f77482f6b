//! SCIP 2.0 replies, both ways: parsing what a sensor sends and building it (for the
//! emulator and for tests).
//!
//! Every reply is a run of LF-terminated lines ended by an empty line:
//!
//! ```text
//! echo of the command        MD0000108001000
//! status + checksum          00P       (99b on each scan of a ranging command)
//! body lines + checksum      a 4-character time stamp, then data in lines of up to 64
//! (empty line)               characters; or NAME:VALUE;sum lines for VV, PP, II
//! ```

use super::ScipError;
use super::checksum::{checksum, verify, verify_information};
use super::command::DataKind;
use super::encoding::{decode, decode_values, encode_into};

/// Data characters per line of a scan, before the checksum.
pub const DATA_LINE: usize = 64;
/// Characters of a time stamp.
const TIMESTAMP_WIDTH: usize = 4;

/// The two-character status of a reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Status(pub [u8; 2]);

impl Status {
    /// `00`: command accepted.
    pub const OK: Self = Self(*b"00");
    /// `99`: a scan of a running ranging command follows.
    pub const SCAN: Self = Self(*b"99");

    /// The status as text.
    pub fn as_str(&self) -> String {
        String::from_utf8_lossy(&self.0).into_owned()
    }
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.as_str())
    }
}

/// A reply as received: the echo, the status, and the body lines still with their
/// checksums (information and data lines are checked differently).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    pub echo: Vec<u8>,
    pub status: Status,
    pub body: Vec<Vec<u8>>,
}

/// The decoded data of one scan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanData {
    /// The sensor's millisecond clock when the scan passed step 0 (24 bits, wraps).
    pub timestamp_ms: u32,
    /// One value per requested beam, in millimetres (small values are error codes).
    pub ranges: Vec<u32>,
    /// One intensity per beam for `ME`; empty otherwise.
    pub intensities: Vec<u32>,
}

/// `NAME:VALUE` pairs of a `VV`, `PP` or `II` reply, in order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Information(pub Vec<(String, String)>);

impl Information {
    /// The value of `name`, if the sensor reported it.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

impl std::fmt::Display for Information {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, (name, value)) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{name}={value}")?;
        }
        Ok(())
    }
}

impl Reply {
    /// Parses the lines of one reply (without their LFs and without the final empty line).
    /// Checks the status's checksum; the body is checked by the accessor that reads it.
    pub fn parse(mut lines: Vec<Vec<u8>>) -> Result<Self, ScipError> {
        if lines.len() < 2 {
            return Err(ScipError::Truncated("status line"));
        }
        let body = lines.split_off(2);
        let status_line = lines.pop().unwrap_or_default();
        let echo = lines.pop().unwrap_or_default();
        let status = match verify(&status_line, 1)? {
            &[a, b] => Status([a, b]),
            _ => return Err(ScipError::malformed("status line", &status_line)),
        };
        Ok(Self { echo, status, body })
    }

    /// The `NAME:VALUE` lines of the body.
    pub fn information(&self) -> Result<Information, ScipError> {
        self.body
            .iter()
            .enumerate()
            .map(|(i, line)| {
                let data = verify_information(line, i + 2)?;
                let text = String::from_utf8_lossy(data);
                match text.split_once(':') {
                    Some((name, value)) if !name.is_empty() => {
                        Ok((name.to_owned(), value.to_owned()))
                    }
                    _ => Err(ScipError::malformed("information line", line)),
                }
            })
            .collect::<Result<_, _>>()
            .map(Information)
    }

    /// The sensor time of a `TM1` reply.
    pub fn time(&self) -> Result<u32, ScipError> {
        let line = self.body.first().ok_or(ScipError::Truncated("time"))?;
        timestamp(line)
    }

    /// The scan of a ranging reply: a time stamp line, then `beams` values of `kind`
    /// spread over data lines, every line with its checksum.
    pub fn scan(&self, kind: DataKind, beams: usize) -> Result<ScanData, ScipError> {
        let (stamp, lines) = self
            .body
            .split_first()
            .ok_or(ScipError::Truncated("time stamp"))?;
        let timestamp_ms = timestamp(stamp)?;
        let mut data = Vec::with_capacity(beams * kind.step_width());
        for (i, line) in lines.iter().enumerate() {
            // Line numbers: echo 0, status 1, time stamp 2, data from 3.
            data.extend_from_slice(verify(line, i + 3)?);
        }
        // A value may straddle two lines, so decode the joined data.
        let values = decode_values(&data, kind.width())?;
        let (ranges, intensities) = if kind.has_intensities() {
            if values.len() % 2 != 0 {
                return Err(ScipError::PartialValue {
                    len: data.len(),
                    width: kind.step_width(),
                });
            }
            values
                .chunks_exact(2)
                .map(|pair| (pair[0], pair[1]))
                .unzip()
        } else {
            (values, Vec::new())
        };
        if ranges.len() != beams {
            return Err(ScipError::ScanLength {
                expected: beams,
                got: ranges.len(),
            });
        }
        Ok(ScanData {
            timestamp_ms,
            ranges,
            intensities,
        })
    }

    /// The reply on the wire: lines, LFs and the final empty line.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(
            self.echo.len() + 5 + self.body.iter().map(|l| l.len() + 1).sum::<usize>(),
        );
        bytes.extend_from_slice(&self.echo);
        bytes.push(b'\n');
        bytes.extend_from_slice(&self.status.0);
        bytes.push(checksum(&self.status.0));
        bytes.push(b'\n');
        for line in &self.body {
            bytes.extend_from_slice(line);
            bytes.push(b'\n');
        }
        bytes.push(b'\n');
        bytes
    }
}

/// An information line `NAME:VALUE;sum` as the sensor sends it.
pub fn information_line(name: &str, value: &str) -> Vec<u8> {
    let mut line = format!("{name}:{value}").into_bytes();
    let sum = checksum(&line);
    line.push(b';');
    line.push(sum);
    line
}

/// A data line: `data` and its checksum.
pub fn data_line(data: &[u8]) -> Vec<u8> {
    let mut line = data.to_vec();
    line.push(checksum(data));
    line
}

/// The body of one scan as the sensor sends it: the time stamp line, then the encoded
/// values in lines of [`DATA_LINE`] characters. `intensities` is used for `ME` only and
/// must then have one value per range.
pub fn scan_body(
    kind: DataKind,
    timestamp_ms: u32,
    ranges: &[u32],
    intensities: &[u32],
) -> Result<Vec<Vec<u8>>, ScipError> {
    let mut stamp = Vec::with_capacity(TIMESTAMP_WIDTH);
    encode_into(timestamp_ms, TIMESTAMP_WIDTH, &mut stamp)?;
    let mut data = Vec::with_capacity(ranges.len() * kind.step_width());
    for (i, &range) in ranges.iter().enumerate() {
        encode_into(range, kind.width(), &mut data)?;
        if kind.has_intensities() {
            let intensity = intensities.get(i).copied().ok_or(ScipError::ScanLength {
                expected: ranges.len(),
                got: intensities.len(),
            })?;
            encode_into(intensity, kind.width(), &mut data)?;
        }
    }
    let mut body = vec![data_line(&stamp)];
    body.extend(data.chunks(DATA_LINE).map(data_line));
    Ok(body)
}

fn timestamp(line: &[u8]) -> Result<u32, ScipError> {
    let data = verify(line, 2)?;
    if data.len() != TIMESTAMP_WIDTH {
        return Err(ScipError::malformed("time stamp line", line));
    }
    decode(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(text: &[u8]) -> Vec<Vec<u8>> {
        let text = text
            .strip_suffix(b"\n\n")
            .expect("a reply ends with an empty line");
        text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
    }

    #[test]
    fn a_parameter_reply_worked_out_by_hand() {
        // PP of a URG-04LX as in Hokuyo's documentation.
        let text = b"PP\n00P\nMODL:URG-04LX(Hokuyo Automatic Co.,Ltd.);N\nDMIN:20;4\n\
                     DMAX:5600;_\nARES:1024;\\\nAMIN:44;7\nAMAX:725;o\nAFRT:384;6\nSCAN:600;e\n\n";
        let reply = Reply::parse(lines(text)).unwrap();
        assert_eq!(reply.echo, b"PP");
        assert_eq!(reply.status, Status::OK);
        let info = reply.information().unwrap();
        assert_eq!(info.get("DMAX"), Some("5600"));
        assert_eq!(info.get("AFRT"), Some("384"));
        assert_eq!(
            info.get("MODL"),
            Some("URG-04LX(Hokuyo Automatic Co.,Ltd.)")
        );
        assert_eq!(info.get("XXXX"), None);
        assert_eq!(reply.to_bytes(), text);
    }

    #[test]
    fn a_scan_worked_out_by_hand() {
        // MD of steps 44..=46: time stamp 16 000 000 ms ("m2@0", its bytes sum to
        // 0x6d+0x32+0x40+0x30 = 0x10f, lower 6 bits 0x0f, + 0x30 = '?'), ranges 5432
        // ("1Dh"), 1234 (0 19 18 = "0CB") and the error code 1 ("001"). The data line
        // "1Dh0CB001" sums to 0x31+0x44+0x68+0x30+0x43+0x42+0x30+0x30+0x31 = 0x223, lower
        // 6 bits 0x23, + 0x30 = 'S'.
        let text = b"MD0044004601000\n99b\nm2@0?\n1Dh0CB001S\n\n";
        let reply = Reply::parse(lines(text)).unwrap();
        assert_eq!(reply.status, Status::SCAN);
        let scan = reply.scan(DataKind::Ranges3, 3).unwrap();
        assert_eq!(scan.timestamp_ms, 16_000_000);
        assert_eq!(scan.ranges, vec![5432, 1234, 1]);
        assert!(scan.intensities.is_empty());
        let built = scan_body(DataKind::Ranges3, 16_000_000, &[5432, 1234, 1], &[]).unwrap();
        assert_eq!(built, reply.body);
    }

    #[test]
    fn two_character_scans_decode() {
        // MS of two steps: "CB" = 1234 and "00" = 0; "CB00" sums to 0xe5, lower 6 bits
        // 0x25, + 0x30 = 'U'.
        let text = b"MS0000000101000\n99b\nm2@0?\nCB00U\n\n";
        let scan = Reply::parse(lines(text))
            .unwrap()
            .scan(DataKind::Ranges2, 2)
            .unwrap();
        assert_eq!(scan.ranges, vec![1234, 0]);
    }

    #[test]
    fn intensities_interleave_with_ranges() {
        let body = scan_body(DataKind::RangesIntensities, 7, &[5432, 1234], &[100, 4000]).unwrap();
        let reply = Reply {
            echo: b"ME0000000101000".to_vec(),
            status: Status::SCAN,
            body,
        };
        let scan = reply.scan(DataKind::RangesIntensities, 2).unwrap();
        assert_eq!(scan.ranges, vec![5432, 1234]);
        assert_eq!(scan.intensities, vec![100, 4000]);
    }

    #[test]
    fn values_may_straddle_lines() {
        // 1081 three-character values make 3243 characters: 50 full lines and one of 43, so
        // values are cut across line ends.
        let ranges: Vec<u32> = (0..1081).map(|i| i * 37 % 60_000).collect();
        let body = scan_body(DataKind::Ranges3, 123, &ranges, &[]).unwrap();
        assert_eq!(body.len(), 1 + 51);
        assert_eq!(body[1].len(), DATA_LINE + 1);
        assert_eq!(body[51].len(), 3243 - 50 * 64 + 1);
        let reply = Reply {
            echo: b"MD0000108001000".to_vec(),
            status: Status::SCAN,
            body,
        };
        assert_eq!(reply.scan(DataKind::Ranges3, 1081).unwrap().ranges, ranges);
    }

    #[test]
    fn a_wrong_checksum_names_its_line() {
        let text = b"MD0044004601000\n99b\nm2@0?\n1Dh0CB001T\n\n";
        let reply = Reply::parse(lines(text)).unwrap();
        assert_eq!(
            reply.scan(DataKind::Ranges3, 3),
            Err(ScipError::Checksum {
                line: 3,
                expected: 'S',
                found: 'T'
            })
        );
        assert!(matches!(
            Reply::parse(lines(b"PP\n00Q\n\n")),
            Err(ScipError::Checksum { line: 1, .. })
        ));
    }

    #[test]
    fn malformed_replies_are_typed_errors() {
        assert_eq!(
            Reply::parse(vec![b"PP".to_vec()]),
            Err(ScipError::Truncated("status line"))
        );
        assert!(matches!(
            Reply::parse(vec![b"PP".to_vec(), b"0P".to_vec()]),
            Err(ScipError::Checksum { .. })
        ));
        assert!(matches!(
            Reply::parse(vec![b"PP".to_vec(), data_line(b"000")]),
            Err(ScipError::Malformed { .. })
        ));
        let reply = |body: Vec<Vec<u8>>| Reply {
            echo: b"MD0044004601000".to_vec(),
            status: Status::SCAN,
            body,
        };
        assert_eq!(
            reply(vec![]).scan(DataKind::Ranges3, 3),
            Err(ScipError::Truncated("time stamp"))
        );
        assert!(matches!(
            reply(vec![data_line(b"m2@")]).scan(DataKind::Ranges3, 0),
            Err(ScipError::Malformed { .. })
        ));
        assert_eq!(
            reply(vec![data_line(b"m2@0"), data_line(b"1Dh0CB")]).scan(DataKind::Ranges3, 3),
            Err(ScipError::ScanLength {
                expected: 3,
                got: 2
            })
        );
        assert!(matches!(
            reply(vec![data_line(b"m2@0"), data_line(b"1Dh0C")]).scan(DataKind::Ranges3, 2),
            Err(ScipError::PartialValue { .. })
        ));
        assert!(matches!(
            reply(vec![data_line(b"m2@0"), data_line(b"1Dh0C~")]).scan(DataKind::Ranges3, 2),
            Err(ScipError::BadCharacter { byte: b'~', .. })
        ));
        assert!(matches!(
            reply(vec![data_line(b"m2@0"), data_line(b"1Dh")]).scan(DataKind::RangesIntensities, 1),
            Err(ScipError::PartialValue { .. })
        ));
        let info = Reply {
            echo: b"VV".to_vec(),
            status: Status::OK,
            body: vec![data_line(b"no colon")],
        };
        assert!(info.information().is_err());
        assert!(matches!(
            scan_body(DataKind::RangesIntensities, 0, &[1, 2], &[1]),
            Err(ScipError::ScanLength { .. })
        ));
        assert!(scan_body(DataKind::Ranges2, 0, &[4096], &[]).is_err());
    }

    // Arbitrary and near-valid replies: tests/scip_properties.rs (proptest).
}
