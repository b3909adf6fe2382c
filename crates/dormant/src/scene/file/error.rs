//! Errors of the scene-file domain: every one names the file, and the field (and line)
//! where the problem is.

use std::path::PathBuf;

use crate::scene::gltf::GltfError;

/// A scene file that cannot be read, parsed, validated or resolved into geometry.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: cannot read scene file: {source}", .file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Malformed TOML, a wrong type, a missing or an unknown key.
    #[error("{}:{line}:{column}: {field}: {message}", .file.display())]
    Syntax { file: PathBuf, line: usize, column: usize, field: String, message: String },
    /// Well-formed TOML with a value that makes no sense (NaN, a zero count, a dangling
    /// reference, a missing asset file).
    #[error("{}: {field}: {message}", location(.file, *.line))]
    Invalid { file: PathBuf, line: Option<usize>, field: String, message: String },
    /// An asset referenced by a field failed to load. Where the asset is the file itself (a
    /// glTF file given as the scene, a `--env` file), its error names it once.
    #[error("{}", asset_message(.file, *.line, .field, .source))]
    Asset {
        file: PathBuf,
        line: Option<usize>,
        field: String,
        #[source]
        source: Box<GltfError>,
    },
}

impl SceneError {
    /// The offending field's path, e.g. `spawners[1].count`.
    pub fn field(&self) -> Option<&str> {
        match self {
            SceneError::Io { .. } => None,
            SceneError::Syntax { field, .. }
            | SceneError::Invalid { field, .. }
            | SceneError::Asset { field, .. } => Some(field),
        }
    }

    /// The 1-based line of the offending field, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            SceneError::Io { .. } => None,
            SceneError::Syntax { line, .. } => Some(*line),
            SceneError::Invalid { line, .. } | SceneError::Asset { line, .. } => *line,
        }
    }
}

fn asset_message(file: &std::path::Path, line: Option<usize>, field: &str, source: &GltfError) -> String {
    if line.is_none() && source.file == file {
        format!("{field}: {source}")
    } else {
        format!("{}: {field}: {source}", location(file, line))
    }
}

fn location(file: &std::path::Path, line: Option<usize>) -> String {
    match line {
        Some(line) => format!("{}:{line}", file.display()),
        None => file.display().to_string(),
    }
}
