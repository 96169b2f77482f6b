//! Messages are plain old data: all-zero bytes are a valid, empty message.
//!
//! That lets a publisher loan uninitialised shared memory and zero it in place instead of
//! building a multi-kilobyte message on the stack and copying it in, and lets tests and
//! recorders make a message on the heap with [`Zeroable::boxed_zeroed`].

/// A type for which all-zero bytes are a valid value.
///
/// # Safety
/// Implement only for `#[repr(C)]` types whose fields are integers, floats, arrays of them or
/// other `Zeroable` types: no references, no `bool`, no enums, no `NonZero`.
pub unsafe trait Zeroable: Sized {
    /// A zeroed value on the heap, without passing a large value through the stack.
    fn boxed_zeroed() -> Box<Self> {
        // SAFETY: the trait's contract says all-zero bytes are a valid `Self`.
        unsafe { Box::<Self>::new_zeroed().assume_init() }
    }

    /// Zeroes `slot` in place and returns it as initialised.
    fn zero_in_place(slot: &mut std::mem::MaybeUninit<Self>) -> &mut Self {
        // SAFETY: writing zero bytes over the whole slot makes it a valid `Self` by the
        // trait's contract.
        unsafe {
            std::ptr::write_bytes(slot.as_mut_ptr(), 0, 1);
            slot.assume_init_mut()
        }
    }
}

/// Implements [`Zeroable`] for message types after checking, at compile time, that they
/// contain nothing but numbers.
macro_rules! impl_zeroable {
    ($($t:ty),* $(,)?) => {
        $(
            // SAFETY: every field of these `#[repr(C)]` types is a number, an array of
            // numbers or another `Zeroable` message type (see each type's definition).
            unsafe impl $crate::zeroed::Zeroable for $t {}
        )*
    };
}
pub(crate) use impl_zeroable;
