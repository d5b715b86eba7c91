//! The error type of every fallible public operation.

use std::path::PathBuf;

/// What went wrong, with the file and (where known) the entity and field.
#[derive(Debug, thiserror::Error)]
pub enum GlintError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The scene file is not valid RON for the scene format.
    #[error("{path}:{line}:{col}: {message}")]
    Syntax {
        /// The scene file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What the parser expected.
        message: String,
    },
    /// A value parsed but is not acceptable.
    #[error("{path}: {entity}: {field}: {message}")]
    Invalid {
        /// The scene (or asset) file.
        path: PathBuf,
        /// The entity (or section) that holds the value.
        entity: String,
        /// The field name.
        field: String,
        /// Why it is rejected.
        message: String,
    },
    /// An image could not be decoded or encoded.
    #[error("{path}: {source}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The underlying error.
        source: image::ImageError,
    },
    /// An imported asset (glTF, OBJ) could not be loaded.
    #[error("{path}: {message}")]
    Asset {
        /// The asset file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A command-line value is not acceptable.
    #[error("{0}")]
    Usage(String),
}

/// Shorthand for results with [`GlintError`].
pub type Result<T, E = GlintError> = std::result::Result<T, E>;
