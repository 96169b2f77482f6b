//! Whether a result sent again and again as it improves (a path, a grid) is in its last form.

use crate::header::{FLAG_FINAL, Header};

/// A result as it stands, or its last form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Form {
    /// As it stands; a better one may follow.
    Interim,
    /// The last: sent at the end of the stream or as the publisher stops
    /// ([`FLAG_FINAL`] in every piece's header).
    Final,
}

impl Form {
    /// The header of piece `seq` of a result stamped `stamp_ns` (the last scan's), in frame
    /// `map`.
    pub fn header(self, seq: u64, stamp_ns: u64) -> Header {
        let mut header = Header::new(seq, stamp_ns, "map");
        if self == Form::Final {
            header.flags |= FLAG_FINAL;
        }
        header
    }
}
