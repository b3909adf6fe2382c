//! [`StaticSceneSnapshot`]: a saved static scene, opaque outside its backend.

use std::any::Any;
use std::sync::Arc;

use super::Backend;

/// What a backend keeps in a snapshot.
pub(crate) trait SnapshotPayload: Any + Send + Sync {
    /// Bytes only this snapshot keeps alive (what dropping it would free).
    fn unique_bytes(&self) -> usize;
    fn as_any(&self) -> &dyn Any;
}

/// A static scene saved by [`super::Accelerator::snapshot_static_scene`]. Cloning is O(1).
#[derive(Clone)]
pub struct StaticSceneSnapshot {
    backend: Backend,
    payload: Arc<dyn SnapshotPayload>,
}

impl StaticSceneSnapshot {
    pub(crate) fn new(backend: Backend, payload: impl SnapshotPayload) -> Self {
        Self { backend, payload: Arc::new(payload) }
    }

    pub(crate) fn backend(&self) -> Backend {
        self.backend
    }

    /// Memory only this snapshot keeps alive: shared structure is not counted, so the value
    /// grows as the live scene moves away from the snapshot.
    pub(crate) fn unique_bytes(&self) -> usize {
        self.payload.unique_bytes()
    }

    pub(crate) fn payload<T: 'static>(&self) -> Option<&T> {
        self.payload.as_any().downcast_ref()
    }
}

impl std::fmt::Debug for StaticSceneSnapshot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StaticSceneSnapshot").field("backend", &self.backend).finish_non_exhaustive()
    }
}
