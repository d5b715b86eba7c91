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
    /// An output path glint cannot write as asked (unknown format, wrong extension).
    #[error("{path}: {message}")]
    Output {
        /// The output file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A setting override (`key=value`) names no setting or its value does not parse.
    #[error("{0}")]
    Setting(String),
    /// The scene has no camera to render from.
    #[error("the scene has no camera")]
    NoCamera,
    /// A pixel to debug lies outside the image.
    #[error("pixel {},{} is outside the {}x{} image", .pixel[0], .pixel[1], .size[0], .size[1])]
    PixelOutside {
        /// The pixel `[x, y]`.
        pixel: [u32; 2],
        /// The image `[width, height]`.
        size: [u32; 2],
    },
    /// The reference image of a converge run cannot be used.
    #[error("{0}")]
    Reference(String),
    /// Options of a run are out of range or missing.
    #[error("{0}")]
    Options(String),
    /// The debug dump could not be encoded as RON.
    #[error("debug dump: {0}")]
    Dump(String),
}

/// Shorthand for results with [`GlintError`].
pub type Result<T, E = GlintError> = std::result::Result<T, E>;
