//! What can be wrong with SCIP bytes.

/// A SCIP message that cannot be decoded. Every decoder of this crate returns one of these
/// for malformed input; none panics.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScipError {
    /// A character outside the encoding's alphabet `0x30..=0x6f`.
    #[error("byte 0x{byte:02x} at position {position} is not a SCIP data character (0x30..=0x6f)")]
    BadCharacter { byte: u8, position: usize },
    /// SCIP values are 1 to 4 characters wide.
    #[error("{width}-character values do not exist in SCIP (1 to 4)")]
    BadWidth { width: usize },
    /// The value needs more bits than `width` characters carry.
    #[error("{value} does not fit in {width} SCIP characters")]
    ValueTooLarge { value: u32, width: usize },
    /// The data of a line does not add up to its checksum character.
    #[error("line {line} of the reply: checksum '{found}' but its data sums to '{expected}'")]
    Checksum {
        line: usize,
        expected: char,
        found: char,
    },
    /// A line that does not have the shape its place in the reply requires.
    #[error("malformed {what}: {text:?}")]
    Malformed { what: &'static str, text: String },
    /// A reply that ends before a line it must have.
    #[error("reply ends before its {0}")]
    Truncated(&'static str),
    /// A parameter the sensor must report (`PP`) is missing.
    #[error("the sensor did not report {0}")]
    MissingParameter(&'static str),
    /// A parameter with a value that is not a number or makes no sense.
    #[error("the sensor reported {name} = {value:?}, which is not usable")]
    BadParameter { name: &'static str, value: String },
    /// The data of a scan decodes to another number of beams than requested.
    #[error("scan has {got} values where {expected} were requested")]
    ScanLength { expected: usize, got: usize },
    /// Data bytes that do not split into whole values.
    #[error("{len} bytes of scan data are not a whole number of {width}-byte values")]
    PartialValue { len: usize, width: usize },
    /// A command this crate does not know.
    #[error("unknown or malformed command {0:?}")]
    UnknownCommand(String),
}

impl ScipError {
    /// Shows bytes from the wire in an error message, even when they are not UTF-8.
    pub(crate) fn malformed(what: &'static str, bytes: &[u8]) -> Self {
        Self::Malformed {
            what,
            text: String::from_utf8_lossy(bytes).into_owned(),
        }
    }
}
