//! A fixed-capacity list inside a fixed-layout message.

use iceoryx2::prelude::ZeroCopySend;
use zerocopy::FromZeros;

use crate::capacity::{CapacityError, fill, used};

/// Up to `N` items of `T`, of which the first `len` are meaningful: how a message carries a
/// list of varying length in a fixed layout. Unused slots stay as they were (zero in a fresh
/// message) and are never read.
///
/// The layout is the count, four bytes that keep it free of implicit padding, then the
/// slots, so a message with a count and an array of 8-byte aligned items just after it
/// keeps its wire layout when it carries them as a `BoundedArray`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
pub struct BoundedArray<T: ZeroCopySend + Copy, const N: usize> {
    len: u32,
    /// Always 0.
    reserved: u32,
    items: [T; N],
}

impl<T: ZeroCopySend + Copy, const N: usize> BoundedArray<T, N> {
    /// The most items it holds.
    pub const CAPACITY: usize = N;

    /// The items in use.
    pub fn as_slice(&self) -> &[T] {
        used(&self.items, self.len)
    }

    /// How many items are in use.
    pub fn len(&self) -> usize {
        self.as_slice().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The items in use, in order.
    pub fn iter(&self) -> std::slice::Iter<'_, T> {
        self.as_slice().iter()
    }

    /// Replaces the items with `items`, or says that they do not fit (naming the list as
    /// `what`) and leaves the list as it was.
    pub fn set(&mut self, what: &'static str, items: &[T]) -> Result<(), CapacityError> {
        self.len = fill(what, &mut self.items, items)?;
        Ok(())
    }

    /// Appends `item`, or says that the list is full (naming it as `what`).
    pub fn push(&mut self, what: &'static str, item: T) -> Result<(), CapacityError> {
        let len = self.len();
        let slot = self.items.get_mut(len).ok_or(CapacityError {
            what,
            len: len + 1,
            capacity: N,
        })?;
        *slot = item;
        // Every capacity is far below u32::MAX: `slot` exists.
        self.len = (len + 1) as u32;
        Ok(())
    }
}

impl<'a, T: ZeroCopySend + Copy, const N: usize> IntoIterator for &'a BoundedArray<T, N> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Zeroable;

    #[test]
    fn pushes_until_full_then_names_the_list() {
        let mut list = BoundedArray::<u64, 2>::boxed_zeroed();
        assert!(list.is_empty());
        list.push("numbers", 7).unwrap();
        list.push("numbers", 8).unwrap();
        let full = list.push("numbers", 9).unwrap_err();
        assert_eq!(
            full,
            CapacityError {
                what: "numbers",
                len: 3,
                capacity: 2
            }
        );
        assert_eq!(list.as_slice(), &[7, 8]);
        assert_eq!(list.iter().sum::<u64>(), 15);
    }

    #[test]
    fn set_replaces_the_items_and_refuses_too_many() {
        let mut list = BoundedArray::<u64, 3>::boxed_zeroed();
        list.set("numbers", &[1, 2, 3]).unwrap();
        list.set("numbers", &[4]).unwrap();
        assert_eq!(list.as_slice(), &[4]);
        assert!(list.set("numbers", &[1, 2, 3, 4]).is_err());
        assert_eq!(
            list.as_slice(),
            &[4],
            "a refused set leaves the list as it was"
        );
        assert_eq!((&*list).into_iter().count(), 1);
    }
}
