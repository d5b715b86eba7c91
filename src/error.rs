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
    #[error("{path}: {source}")]
    Asset {
        /// The asset file.
        path: PathBuf,
        /// What went wrong.
        source: AssetError,
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
    /// A part of a render cannot be read, or parts cannot be merged (names the file).
    #[error("{0}")]
    Part(String),
    /// The reference image of a converge run cannot be used.
    #[error("{0}")]
    Reference(String),
    /// Options of a run are out of range or missing.
    #[error("{0}")]
    Options(String),
    /// The debug dump could not be encoded as RON.
    #[error("debug dump: {0}")]
    Dump(String),
    /// The input asks for more memory than the machine has.
    #[error(transparent)]
    Memory(#[from] crate::memory::MemoryError),
}

/// Shorthand for results with [`GlintError`].
pub type Result<T, E = GlintError> = std::result::Result<T, E>;

/// Why an imported asset (glTF, OBJ) could not be loaded; [`GlintError::Asset`] adds the file.
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    /// The glTF file does not parse or validate.
    #[error("not a valid glTF file: {0}")]
    Gltf(#[from] gltf::Error),
    /// A buffer of the glTF file could not be read.
    #[error("cannot read a buffer: {0}")]
    GltfBuffer(#[source] gltf::Error),
    /// The OBJ file could not be read.
    #[error("cannot read the OBJ file: {0}")]
    Obj(#[from] tobj::LoadError),
    /// The file's extension names no model format.
    #[error("not a format glint reads (scenes: .ron; models: .gltf, .glb, .obj)")]
    UnknownFormat,
    /// The glTF file requires an extension glint does not support.
    #[error("requires the glTF extension {0}, which glint does not support")]
    UnsupportedExtension(String),
    /// The requested glTF scene does not exist.
    #[error("scene {index} does not exist (the file has {count})")]
    NoSuchScene {
        /// The requested scene index.
        index: usize,
        /// How many scenes the file has.
        count: usize,
    },
    /// The glTF file has no scene.
    #[error("the file has no scene")]
    NoScene,
    /// A model rendered directly has no triangles.
    #[error("the file has no triangles to render")]
    NoTriangles,
    /// The glTF or OBJ reader gave up on the file (a panic inside the `gltf` or `tobj`
    /// crate, caught).
    #[error("malformed {format} file: {why}")]
    Malformed {
        /// "glTF" or "OBJ".
        format: &'static str,
        /// The reader's message.
        why: String,
    },
    /// A node, mesh or primitive holds data glint cannot use.
    #[error("{item}: {problem}")]
    Invalid {
        /// The node, mesh or primitive.
        item: String,
        /// What is wrong with it.
        problem: String,
    },
}
