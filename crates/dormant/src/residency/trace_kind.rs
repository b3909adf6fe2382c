//! What a frame's measured trace time stands for ([`TraceKind`]): the input by which the render
//! loop tells the cost model whether a frame's trace is typical of the frames after it.

/// What a frame's trace time says of the frames after it, whose trace the model prices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceKind {
    /// They trace about as much: it joins the running mean.
    Typical,
    /// Traced in full in a run that reuses samples (`--reuse exact`), where the frames after
    /// it trace only what changed: it stands for them only until one is measured (averaged
    /// in, its seconds kept `auto` from integrating for many frames: docs/lab/reuse.md).
    FullBeforeReuse,
}
