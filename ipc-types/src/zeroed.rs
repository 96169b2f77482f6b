//! Messages are plain old data: all-zero bytes are a valid, empty message.
//!
//! That lets a publisher loan uninitialised shared memory and zero it in place instead of
//! building a multi-kilobyte message on the stack and copying it in, and lets tests and
//! recorders make a message on the heap with [`Zeroable::boxed_zeroed`].
//!
//! Every message derives [`zerocopy::FromZeros`], so the compiler checks that claim field by
//! field (no references, `bool`, enums or `NonZero`); [`Zeroable`] only adds the two ways of
//! getting a zeroed message the transport and the recorders need.

use std::mem::MaybeUninit;

use zerocopy::FromZeros;

/// A type for which all-zero bytes are a valid value, as its derived [`FromZeros`] proves.
pub trait Zeroable: FromZeros + Sized {
    /// A zeroed value on the heap, without passing a large value through the stack.
    fn boxed_zeroed() -> Box<Self> {
        Self::new_box_zeroed()
            .unwrap_or_else(|_| std::alloc::handle_alloc_error(std::alloc::Layout::new::<Self>()))
    }

    /// Zeroes `slot` in place and returns it as initialised.
    fn zero_in_place(slot: &mut MaybeUninit<Self>) -> &mut Self {
        // SAFETY: `Self: FromZeros` (derived, so checked by the compiler) means all-zero
        // bytes are a valid `Self`, and writing them over the whole slot initialises it.
        // zerocopy can zero only a value that is already initialised (`FromZeros::zero`), and
        // a loaned shared-memory slot is not: building a zeroed value and moving it in would
        // put a multi-kilobyte message on the stack, which is what zeroing in place avoids.
        unsafe {
            std::ptr::write_bytes(slot.as_mut_ptr(), 0, 1);
            slot.assume_init_mut()
        }
    }
}

impl<T: FromZeros> Zeroable for T {}
