//! Error type shared by all loaders, generators and scene edits.

use std::path::PathBuf;

/// Everything that can go wrong while loading, generating, validating or editing a scene.
///
/// Messages always say *what* went wrong and *where* (file path, mesh/primitive/node/instance
/// index, generator parameter).
#[derive(thiserror::Error, Debug)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The model file is not something a model can be read from (a device, FIFO, directory, socket).
    #[error("cannot read {path}: {message}")]
    Unreadable { path: PathBuf, message: String },
    /// A file the model references (glTF buffer URI, OBJ `mtllib`) cannot be used: outside the model's
    /// folder, not a regular file, missing, or of another size than declared.
    #[error("{model}: cannot use `{uri}`: {message}")]
    Reference {
        model: PathBuf,
        uri: String,
        message: String,
    },
    /// The load was cancelled through [`crate::LoadOptions::cancel`].
    #[error("loading {0} was cancelled")]
    Cancelled(String),
    /// The glTF file is malformed or uses something unsupported.
    #[error("glTF {path}: {message}")]
    Gltf { path: PathBuf, message: String },
    /// The OBJ file is malformed.
    #[error("OBJ {path}: {message}")]
    Obj { path: PathBuf, message: String },
    /// The STL file is malformed.
    #[error("STL {path}: {message}")]
    Stl { path: PathBuf, message: String },
    /// The PLY file is malformed.
    #[error("PLY {path}: {message}")]
    Ply { path: PathBuf, message: String },
    /// A STEP or IGES file cannot be read, or its kernel (OpenCASCADE, in a worker process) failed.
    #[error("{format} {path}: {message}")]
    Cad {
        format: &'static str,
        path: PathBuf,
        message: String,
    },
    /// The scene data is inconsistent (bad index, NaN position, singular transform, ...).
    #[error("invalid scene: {0}")]
    Invalid(String),
    /// The scene contains no triangles at all.
    #[error("{0}")]
    Empty(String),
    /// `gen:NAME` with an unknown NAME.
    #[error("unknown generator: {0}")]
    UnknownGenerator(String),
    /// A generator parameter is unknown, malformed or out of range.
    #[error("bad generator parameter: {0}")]
    BadGeneratorParam(String),
    /// The input would exceed a size limit (triangles per mesh, instances, node visits).
    #[error("too large: {0}")]
    TooLarge(String),
    /// The file extension is not one we can load.
    #[error("unsupported scene format: {0}")]
    UnsupportedFormat(String),
    /// An edit referenced an instance or mesh id that does not exist.
    #[error("{what} id {index} out of range (have {len})")]
    OutOfRange {
        what: &'static str,
        index: u64,
        len: u64,
    },
}
