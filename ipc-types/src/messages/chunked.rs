//! The shape shared by the messages that carry a long list in pieces (a path, a particle
//! cloud, a grid's cells): a header, what describes the whole, where this piece starts in
//! it and how long the whole is, then the piece's items in a [`super::BoundedArray`].

/// Defines a message of this shape and its record (the message without its unused
/// capacity, what gets serialised): `$name` carries up to `$capacity` items of `$item` in
/// its field `$items` (refused as `$what` when there are more) after the fields `$extra`,
/// under the wire type name `$type_name`.
///
/// A macro, not a generic struct, for the reason `corner_list_message!` gives: the derived
/// `ZeroCopySend` names one concrete type with its own versioned type name.
macro_rules! chunked_message {
    (
        $(#[$attr:meta])*
        $name:ident, $record:ident, $item:ty, $capacity:expr, $type_name:tt, $what:tt,
        $items:ident { $($(#[$extra_attr:meta])* $extra:ident: $extra_ty:ty,)* }
    ) => {
        #[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
        #[type_name($type_name)]
        #[repr(C)]
        $(#[$attr])*
        pub struct $name {
            pub header: Header,
            $($(#[$extra_attr])* pub $extra: $extra_ty,)*
            /// Index in the whole of this piece's first item.
            pub first: u64,
            /// Items in the whole.
            pub total: u64,
            pub $items: BoundedArray<$item, $capacity>,
        }

        impl $name {
            /// This piece's items.
            pub fn $items(&self) -> &[$item] {
                self.$items.as_slice()
            }

            /// Replaces the items, or says that they do not fit and leaves them as they were.
            pub fn set(&mut self, items: &[$item]) -> Result<(), CapacityError> {
                self.$items.set($what, items)
            }

            /// Whether this piece ends the whole.
            pub fn is_last_piece(&self) -> bool {
                self.first + self.$items.len() as u64 >= self.total
            }

            pub fn to_record(&self) -> $record<'_> {
                $record {
                    header: self.header,
                    $($extra: self.$extra,)*
                    first: self.first,
                    total: self.total,
                    $items: std::borrow::Cow::Borrowed(self.$items()),
                }
            }

            /// Rebuilds the message from its record, on the heap.
            pub fn from_record(record: &$record<'_>) -> Result<Box<Self>, CapacityError> {
                let mut message = <Self as crate::Zeroable>::boxed_zeroed();
                message.header = record.header;
                $(message.$extra = record.$extra;)*
                message.first = record.first;
                message.total = record.total;
                message.set(&record.$items)?;
                Ok(message)
            }
        }

        #[doc = concat!("[`", stringify!($name), "`] without the unused capacity.")]
        #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
        pub struct $record<'a> {
            pub header: Header,
            $(pub $extra: $extra_ty,)*
            pub first: u64,
            pub total: u64,
            pub $items: std::borrow::Cow<'a, [$item]>,
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                self.to_record().serialize(serializer)
            }
        }
    };
}

pub(crate) use chunked_message;
