//! [`Disjoint`]: a slice that the tasks of one parallel call write at disjoint
//! indices. It lives with the state because the state's own tile classification
//! (`tiles.rs`) writes through it on the run's threads, which the numerics layer
//! supplies (`numerics::workers` re-exports it for the stages).

use std::ops::Range;

/// A slice that the tasks of one parallel call write at disjoint indices (each task
/// its own tile's cells, which are not contiguous in a row-major array).
///
/// The caller of [`Disjoint::set`] and [`Disjoint::get`] guarantees that while the
/// parallel call runs, no index written by one task is read or written by another:
/// the tiles of a stepped set are disjoint, and a task touches its own tile's cells and
/// its own entry of per-tile arrays only.
pub struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: the tasks access disjoint indices (the type's contract), so sharing the
// pointer between threads is sharing `&mut` to disjoint parts of the slice.
unsafe impl<T: Send> Send for Disjoint<'_, T> {}
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T: Copy> Disjoint<'a, T> {
    /// The slice `s`, borrowed for the parallel call.
    pub fn new(s: &'a mut [T]) -> Self {
        Disjoint {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _slice: std::marker::PhantomData,
        }
    }

    /// Writes `v` at index `i` (bounds-checked).
    ///
    /// # Safety
    /// No other task reads or writes index `i` during the parallel call.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, v: T) {
        assert!(i < self.len, "index {i} out of {}", self.len);
        // SAFETY: in bounds (checked), and exclusive to this task (the caller's contract).
        unsafe { *self.ptr.add(i) = v }
    }

    /// The elements `range` as one slice (bounds-checked), for copies of whole rows.
    ///
    /// # Safety
    /// No other task reads or writes an index of `range` while the slice lives.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn slice(&self, range: Range<usize>) -> &mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "range {range:?} out of {}",
            self.len
        );
        // SAFETY: in bounds (checked), and exclusive to this task (the caller's contract).
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }

    /// Reads index `i` (bounds-checked).
    ///
    /// # Safety
    /// No other task writes index `i` during the parallel call.
    #[inline(always)]
    pub unsafe fn get(&self, i: usize) -> T {
        assert!(i < self.len, "index {i} out of {}", self.len);
        // SAFETY: in bounds (checked), and not written by another task (the contract).
        unsafe { *self.ptr.add(i) }
    }
}
