//! [`TraversalStack`]: the fixed-capacity stack of subtrees still to visit that every BVH ray
//! traversal uses (the 8-wide trees of meshes, blocks, the persistent tree's overlay and the
//! instance levels, and the binary reference walk of the tests). It owns the traversal's only
//! `unsafe`.
//!
//! The storage is left uninitialised: a ray runs one traversal per block subtree and per
//! instance it enters, most of them short, and zeroing 1-3 KiB for each slowed a whole AO
//! render. The length lives in the stack object, so the compiler reloads it
//! around pushes; keeping it in a register (the entries in a separate local) and dropping the
//! pop's bounds check were tried and did not pay:
//! docs/lab/accelerators.md#2026-12-01-one-traversal-stack-type-its-storage-left-uninitialised

use std::mem::MaybeUninit;

/// Subtrees to visit later, last in first out: for one ray `(node, entry distance)`, for a
/// packet ([`super::packet`]) also the lanes that entered it. Holds at most `N` entries;
/// pushing more panics (the builders bound tree depth so that the traversals never do).
pub(crate) struct TraversalStack<E: Copy, const N: usize> {
    /// `entries[..len]` are initialised; the rest may not be.
    entries: [MaybeUninit<E>; N],
    len: usize,
}

impl<E: Copy, const N: usize> TraversalStack<E, N> {
    #[inline(always)]
    pub(crate) fn new() -> Self {
        Self { entries: [const { MaybeUninit::uninit() }; N], len: 0 }
    }

    /// Saves an entry.
    #[inline(always)]
    pub(crate) fn push(&mut self, entry: E) {
        debug_assert!(self.len < N, "traversal stack overflow: deeper than {N}");
        // Indexing is bounds-checked: an overflow panics instead of writing past the array.
        self.entries[self.len].write(entry);
        self.len += 1;
    }

    /// The last entry pushed and not popped yet; `None` once the stack is empty.
    #[inline(always)]
    pub(crate) fn pop(&mut self) -> Option<E> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: `entries[..len]` are initialised: `push` writes `entries[len]` before it
        // increments `len`, and only this pop decrements it, so the entry at the new `len` was
        // written by a push and not popped since.
        Some(unsafe { self.entries[self.len].assume_init() })
    }
}

impl<const N: usize> TraversalStack<(u32, f32), N> {
    /// Pops entries until one was entered at `t <= t_max` (a subtree still in front of the
    /// closest hit found so far) and returns its node; `None` once the stack is empty.
    #[inline(always)]
    pub(crate) fn pop_within(&mut self, t_max: f32) -> Option<u32> {
        while let Some((node, t)) = self.pop() {
            if t <= t_max {
                return Some(node);
            }
        }
        None
    }
}
