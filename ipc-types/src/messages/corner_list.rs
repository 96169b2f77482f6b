//! The shape shared by the messages that carry a list of corners: a header, then the
//! corners in a [`BoundedArray`], serialised as a [`CornerListRecord`] of the corners in use.

use std::borrow::Cow;

use serde::{Deserialize, Serialize};

use crate::header::Header;

/// A corner-list message without its unused capacity: what gets written to disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
pub struct CornerListRecord<'a, C: Clone> {
    pub header: Header,
    pub corners: Cow<'a, [C]>,
}

/// Defines a message of this shape: a header and up to `$capacity` corners of type
/// `$corner`, refused as `$what` when there are more, under the wire type name `$type_name`.
///
/// A macro, not a generic struct: the derived `ZeroCopySend` names one concrete type, and
/// each topic's message keeps its own versioned type name (a generic struct would need a
/// hand-written `unsafe impl` per topic instead).
macro_rules! corner_list_message {
    (
        $(#[$attr:meta])*
        $name:ident, $corner:ty, $capacity:expr, $type_name:tt, $what:tt
    ) => {
        $(#[$attr])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
        #[type_name($type_name)]
        pub struct $name {
            pub header: Header,
            pub corners: BoundedArray<$corner, $capacity>,
        }

        impl $name {
            pub fn corners(&self) -> &[$corner] {
                self.corners.as_slice()
            }

            /// Replaces the corners, or says that they do not fit and leaves them as they were.
            pub fn set(&mut self, corners: &[$corner]) -> Result<(), CapacityError> {
                self.corners.set($what, corners)
            }

            pub fn to_record(&self) -> CornerListRecord<'_, $corner> {
                CornerListRecord {
                    header: self.header,
                    corners: std::borrow::Cow::Borrowed(self.corners()),
                }
            }

            /// Rebuilds the message from its record, on the heap.
            pub fn from_record(
                record: &CornerListRecord<'_, $corner>,
            ) -> Result<Box<Self>, CapacityError> {
                let mut message = <Self as crate::Zeroable>::boxed_zeroed();
                message.header = record.header;
                message.set(&record.corners)?;
                Ok(message)
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                self.to_record().serialize(serializer)
            }
        }
    };
}

pub(crate) use corner_list_message;
