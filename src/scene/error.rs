//! Errors of scene loading. Every one names the file, and where the text is at fault, the line
//! and column and what was expected there.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read the scene: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}:{line}:{column}: expected {expected}, found {found}")]
    Syntax {
        file: PathBuf,
        line: u32,
        column: u32,
        expected: String,
        found: String,
    },
    #[error("{file}:{line}:{column}: {message}")]
    Invalid {
        file: PathBuf,
        line: u32,
        column: u32,
        message: String,
    },
    #[error("{file}: {message}")]
    Obj { file: PathBuf, message: String },
}

impl SceneError {
    /// The line the error points at, when it points at one.
    pub fn line(&self) -> Option<u32> {
        match self {
            SceneError::Syntax { line, .. } | SceneError::Invalid { line, .. } => Some(*line),
            _ => None,
        }
    }
}
