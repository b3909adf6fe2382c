//! Errors of the physics domain.

use crate::scene::file::SceneError;

/// A scene that cannot be simulated.
#[derive(Debug, thiserror::Error)]
pub enum PhysicsError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A mesh that cannot become a collider (e.g. all points coplanar).
    #[error("{file}: {field}: {message}")]
    Collider { file: String, field: String, message: String },
    /// An option given to the simulation that makes no sense.
    #[error("{option}: {message}")]
    Option { option: &'static str, message: String },
}
