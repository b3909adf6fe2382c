//! [`TraversalStack`]: the fixed-capacity stack of subtrees still to visit that every BVH ray
//! traversal uses (the 8-wide trees of meshes, blocks, the persistent tree's overlay and the
//! instance levels, and the binary reference walk of the tests). It owns the traversal's only
//! `unsafe`.
//!
//! Performance notes (measured, so nobody retries them blind). Setup: CPU time (`perf stat -e
//! task-clock`) of `dormant --threads 1 render --backend bvh --mode ao --env monastery.glb
//! --object duck.glb --count 1000 --size 640x360 --spp 16`, 8 runs of each binary alternating,
//! 2 shared cores:
//! - This type against the two hand-written stacks it replaced: 1.00x (median of runs and
//!   best run); images byte-identical.
//! - Zeroed storage (a plain `[(0, 0.0); N]`, no `unsafe` at all): 1.21x the CPU time, every
//!   run. The memset is 1 KiB per binary traversal and 3 KiB per 4-wide one, and a ray runs
//!   one traversal per block subtree and per instance it enters, most of them short.
//! - The entries in a separate local borrowed by the stack, so that the length stays in a
//!   register (with the length in the same object, the compiler reloads it around every push:
//!   the wide traversal's assembly shows it): tried together with the child-order changes of
//!   2026-12-02 (docs/performance.md, "Node step and leaves"), no gain measured. Counted
//!   (session 29, cachegrind, 320x180 path-traced frames): 0.4% fewer trace instructions on
//!   the default scene, but 1.1% more and 10% more simulated mispredictions on the monastery
//!   with 8,000 ducks.
//! - `get_unchecked` in [`TraversalStack::pop_within`] (dropping the bounds check on the
//!   pop): 0.99x median, 1.00x best run, within noise; not worth a second `unsafe`.

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
    pub fn new() -> Self {
        Self { entries: [const { MaybeUninit::uninit() }; N], len: 0 }
    }

    /// Saves an entry.
    #[inline(always)]
    pub fn push(&mut self, entry: E) {
        debug_assert!(self.len < N, "traversal stack overflow: deeper than {N}");
        // Indexing is bounds-checked: an overflow panics instead of writing past the array.
        self.entries[self.len].write(entry);
        self.len += 1;
    }

    /// The last entry pushed and not popped yet; `None` once the stack is empty.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<E> {
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
    pub fn pop_within(&mut self, t_max: f32) -> Option<u32> {
        while let Some((node, t)) = self.pop() {
            if t <= t_max {
                return Some(node);
            }
        }
        None
    }
}
