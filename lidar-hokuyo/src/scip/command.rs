//! SCIP 2.0 commands: what the host sends, and what the sensor echoes back.
//!
//! A command is two letters, fixed-width decimal parameters, an optional `;tag` the sensor
//! echoes, and a line feed. The reply's first line repeats the command as sent (for the
//! ranging commands' scans, with the remaining scan count in place of the requested one).

use super::ScipError;

/// Largest step number a 4-digit ranging parameter holds.
pub const MAX_STEP: u16 = 9999;
/// Largest cluster count (2 digits).
pub const MAX_CLUSTER: u8 = 99;

/// What a ranging command asks the sensor to send for each step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataKind {
    /// `MS`: ranges in 2 characters (12 bits, up to 4 095 mm).
    Ranges2,
    /// `MD`: ranges in 3 characters (18 bits).
    Ranges3,
    /// `ME`: a 3-character range and a 3-character intensity per step.
    RangesIntensities,
}

impl DataKind {
    /// The command's two letters.
    pub fn code(self) -> &'static [u8; 2] {
        match self {
            Self::Ranges2 => b"MS",
            Self::Ranges3 => b"MD",
            Self::RangesIntensities => b"ME",
        }
    }

    /// Characters of one value (range or intensity).
    pub fn width(self) -> usize {
        match self {
            Self::Ranges2 => 2,
            Self::Ranges3 | Self::RangesIntensities => 3,
        }
    }

    /// True when every step carries an intensity after its range.
    pub fn has_intensities(self) -> bool {
        self == Self::RangesIntensities
    }

    /// Characters of one step's data.
    pub fn step_width(self) -> usize {
        if self.has_intensities() {
            2 * self.width()
        } else {
            self.width()
        }
    }

    fn from_code(code: &[u8]) -> Option<Self> {
        [Self::Ranges2, Self::Ranges3, Self::RangesIntensities]
            .into_iter()
            .find(|kind| kind.code() == code)
    }
}

/// A continuous ranging command (`MD`, `MS`, `ME`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ranging {
    pub kind: DataKind,
    /// First step measured.
    pub start: u16,
    /// Last step measured (inclusive).
    pub end: u16,
    /// Adjacent steps merged into one value (0 and 1: none); the sensor sends the
    /// shortest valid range of each group.
    pub cluster: u8,
    /// Scans skipped between two sent scans.
    pub interval: u8,
    /// Scans to send; 0 = until `QT`.
    pub scans: u8,
}

impl Ranging {
    /// A ranging command, checked against the widths of its fields.
    pub fn new(
        kind: DataKind,
        start: u16,
        end: u16,
        cluster: u8,
        interval: u8,
        scans: u8,
    ) -> Result<Self, ScipError> {
        let bad = |name: &'static str, value: u16| ScipError::BadParameter {
            name,
            value: value.to_string(),
        };
        if end > MAX_STEP {
            return Err(bad("end step", end));
        }
        if start > end {
            return Err(bad("start step (after the end step)", start));
        }
        if cluster > MAX_CLUSTER {
            return Err(bad("cluster count", cluster.into()));
        }
        if interval > 9 {
            return Err(bad("scan interval", interval.into()));
        }
        if scans > 99 {
            return Err(bad("number of scans", scans.into()));
        }
        Ok(Self {
            kind,
            start,
            end,
            cluster,
            interval,
            scans,
        })
    }

    /// Steps merged into one value (at least 1).
    pub fn cluster_size(&self) -> usize {
        usize::from(self.cluster.max(1))
    }

    /// Values the sensor sends per scan: the steps in groups of `cluster`, the last group
    /// possibly short.
    pub fn beams(&self) -> usize {
        let steps = usize::from(self.end - self.start) + 1;
        steps.div_ceil(self.cluster_size())
    }

    /// The echo of one scan of this command, `remaining` scans still to come.
    pub fn echo(&self, remaining: u8) -> Vec<u8> {
        let mut line = self.echo_prefix();
        line.extend_from_slice(format!("{:02}", remaining.min(99)).as_bytes());
        line
    }

    /// The part of the echo every scan of this command repeats (all but the scan count).
    pub fn echo_prefix(&self) -> Vec<u8> {
        let mut line = self.kind.code().to_vec();
        line.extend_from_slice(
            format!(
                "{:04}{:04}{:02}{:01}",
                self.start, self.end, self.cluster, self.interval
            )
            .as_bytes(),
        );
        line
    }

    fn parse(kind: DataKind, fields: &[u8], text: &[u8]) -> Result<Self, ScipError> {
        let unknown = || ScipError::UnknownCommand(String::from_utf8_lossy(text).into_owned());
        if fields.len() != 13 {
            return Err(unknown());
        }
        let number = |range: std::ops::Range<usize>| decimal(&fields[range]).ok_or_else(unknown);
        let start = number(0..4)?;
        let end = number(4..8)?;
        // Two and one digits: always below 256.
        let cluster = number(8..10)? as u8;
        let interval = number(10..11)? as u8;
        let scans = number(11..13)? as u8;
        Self::new(kind, start, end, cluster, interval, scans)
    }
}

/// `TM`'s control code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeMode {
    /// `TM0`: enter the time adjustment mode (laser off, nothing else accepted).
    AdjustOn,
    /// `TM1`: read the sensor's millisecond clock.
    Request,
    /// `TM2`: leave the adjustment mode.
    AdjustOff,
}

/// A SCIP 2.0 command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `VV`: vendor, product, firmware, protocol, serial number.
    Version,
    /// `PP`: model, range limits, angular resolution, step range, front step, speed.
    Parameters,
    /// `II`: laser, motor and measurement state.
    Status,
    /// `TM0`, `TM1`, `TM2`: time adjustment.
    Time(TimeMode),
    /// `BM`: laser on.
    LaserOn,
    /// `QT`: stop measuring, laser off.
    Quit,
    /// `RS`: stop measuring and reset the settings.
    Reset,
    /// `MD`, `MS`, `ME`: continuous ranging.
    Ranging(Ranging),
}

impl Command {
    /// The command as sent, without its line feed; also the echo of its reply.
    pub fn line(&self) -> Vec<u8> {
        match self {
            Self::Version => b"VV".to_vec(),
            Self::Parameters => b"PP".to_vec(),
            Self::Status => b"II".to_vec(),
            Self::Time(TimeMode::AdjustOn) => b"TM0".to_vec(),
            Self::Time(TimeMode::Request) => b"TM1".to_vec(),
            Self::Time(TimeMode::AdjustOff) => b"TM2".to_vec(),
            Self::LaserOn => b"BM".to_vec(),
            Self::Quit => b"QT".to_vec(),
            Self::Reset => b"RS".to_vec(),
            Self::Ranging(ranging) => ranging.echo(ranging.scans),
        }
    }

    /// The bytes to send.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = self.line();
        bytes.push(b'\n');
        bytes
    }

    /// Parses a command line (without its terminator); a `;tag` is ignored.
    pub fn parse(text: &[u8]) -> Result<Self, ScipError> {
        let body = text.split(|&b| b == b';').next().unwrap_or_default();
        let unknown = || ScipError::UnknownCommand(String::from_utf8_lossy(text).into_owned());
        let (code, fields) = body.split_at_checked(2).ok_or_else(unknown)?;
        if let Some(kind) = DataKind::from_code(code) {
            return Ranging::parse(kind, fields, text).map(Self::Ranging);
        }
        let command = match (code, fields) {
            (b"VV", b"") => Self::Version,
            (b"PP", b"") => Self::Parameters,
            (b"II", b"") => Self::Status,
            (b"TM", b"0") => Self::Time(TimeMode::AdjustOn),
            (b"TM", b"1") => Self::Time(TimeMode::Request),
            (b"TM", b"2") => Self::Time(TimeMode::AdjustOff),
            (b"BM", b"") => Self::LaserOn,
            (b"QT", b"") => Self::Quit,
            (b"RS", b"") => Self::Reset,
            _ => return Err(unknown()),
        };
        Ok(command)
    }
}

/// A fixed-width decimal field: ASCII digits only.
fn decimal(field: &[u8]) -> Option<u16> {
    if field.is_empty() || field.len() > 4 || !field.iter().all(u8::is_ascii_digit) {
        return None;
    }
    Some(
        field
            .iter()
            .fold(0u16, |n, &d| n * 10 + u16::from(d - b'0')),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranging_commands_have_the_documented_layout() {
        // MD, start 0000, end 1080, cluster 01, interval 0, scans 00 (until QT).
        let md = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
        assert_eq!(Command::Ranging(md).to_bytes(), b"MD0000108001000\n");
        // The specification's example range: steps 10 to 750.
        let ms = Ranging::new(DataKind::Ranges2, 10, 750, 3, 1, 5).unwrap();
        assert_eq!(Command::Ranging(ms).line(), b"MS0010075003105");
        assert_eq!(ms.echo(4), b"MS0010075003104");
        assert_eq!(ms.echo_prefix(), b"MS00100750031");
        let me = Ranging::new(DataKind::RangesIntensities, 0, 1080, 0, 0, 0).unwrap();
        assert_eq!(Command::Ranging(me).line(), b"ME0000108000000");
    }

    #[test]
    fn beams_count_clusters_with_a_short_last_one() {
        let full = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
        assert_eq!(full.beams(), 1081);
        let none = Ranging::new(DataKind::Ranges3, 0, 1080, 0, 0, 0).unwrap();
        assert_eq!(none.beams(), 1081);
        let threes = Ranging::new(DataKind::Ranges3, 0, 1080, 3, 0, 0).unwrap();
        assert_eq!(threes.beams(), 361);
        let one_step = Ranging::new(DataKind::Ranges3, 540, 540, 1, 0, 0).unwrap();
        assert_eq!(one_step.beams(), 1);
    }

    #[test]
    fn other_commands() {
        assert_eq!(Command::Version.to_bytes(), b"VV\n");
        assert_eq!(Command::Parameters.to_bytes(), b"PP\n");
        assert_eq!(Command::Status.to_bytes(), b"II\n");
        assert_eq!(Command::Time(TimeMode::AdjustOn).to_bytes(), b"TM0\n");
        assert_eq!(Command::Time(TimeMode::Request).to_bytes(), b"TM1\n");
        assert_eq!(Command::Time(TimeMode::AdjustOff).to_bytes(), b"TM2\n");
        assert_eq!(Command::Quit.to_bytes(), b"QT\n");
        assert_eq!(Command::LaserOn.to_bytes(), b"BM\n");
        assert_eq!(Command::Reset.to_bytes(), b"RS\n");
    }

    #[test]
    fn commands_parse_back() {
        let commands = [
            Command::Version,
            Command::Parameters,
            Command::Status,
            Command::Time(TimeMode::AdjustOn),
            Command::Time(TimeMode::Request),
            Command::Time(TimeMode::AdjustOff),
            Command::LaserOn,
            Command::Quit,
            Command::Reset,
            Command::Ranging(Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap()),
            Command::Ranging(Ranging::new(DataKind::Ranges2, 44, 725, 2, 3, 10).unwrap()),
            Command::Ranging(
                Ranging::new(DataKind::RangesIntensities, 100, 980, 99, 9, 99).unwrap(),
            ),
        ];
        for command in commands {
            assert_eq!(Command::parse(&command.line()), Ok(command));
        }
        assert_eq!(Command::parse(b"QT;stop-1"), Ok(Command::Quit));
    }

    #[test]
    fn malformed_commands_are_refused() {
        for text in [
            &b""[..],
            b"Q",
            b"XX",
            b"TM3",
            b"VVV",
            b"MD000010800100",
            b"MD00001080010000",
            b"MD00a0108001000",
            b"MD1080000001000",
            b"MD0000108001-00",
            b"\xff\xfe",
        ] {
            assert!(Command::parse(text).is_err(), "{text:?}");
        }
    }

    #[test]
    fn out_of_range_fields_are_refused() {
        assert!(Ranging::new(DataKind::Ranges3, 0, 10_000, 1, 0, 0).is_err());
        assert!(Ranging::new(DataKind::Ranges3, 11, 10, 1, 0, 0).is_err());
        assert!(Ranging::new(DataKind::Ranges3, 0, 10, 100, 0, 0).is_err());
        assert!(Ranging::new(DataKind::Ranges3, 0, 10, 1, 10, 0).is_err());
        assert!(Ranging::new(DataKind::Ranges3, 0, 10, 1, 0, 100).is_err());
    }
}
