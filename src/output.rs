//! Files written atomically: to a temporary file beside the target, then renamed over it, so
//! an interrupted render never leaves a broken image, CSV, OBJ or photon file. Every file
//! trilux writes goes through `write_atomically`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: unknown image format (use .png, .jpg, .exr or .pfm)")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: the folder {folder} does not exist")]
    NoFolder { path: PathBuf, folder: PathBuf },
    #[error("{path}: cannot write the image: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: cannot encode the image: {message}")]
    Encode { path: PathBuf, message: String },
}

impl OutputError {
    /// The error of an I/O failure on `path`: `map_err(OutputError::io(path))`.
    pub fn io(path: &Path) -> impl Fn(std::io::Error) -> OutputError + '_ {
        move |source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// The error of an encoder's failure on `path`: `map_err(OutputError::encode(path))`.
    pub fn encode<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> OutputError + '_ {
        move |e| OutputError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}

/// Writes `text` to `path` atomically (temporary file, then rename).
pub fn write_text_atomically(path: &Path, text: &str) -> Result<(), OutputError> {
    write_atomically(path, |w| {
        w.write_all(text.as_bytes())
            .map_err(|source| OutputError::Io {
                path: path.to_path_buf(),
                source,
            })
    })
}

/// Runs `fill` on a temporary file beside `path`, then renames it to `path`.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let io_err = |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let file = File::create(&tmp).map_err(io_err)?;
        let mut w = BufWriter::new(file);
        fill(&mut w)?;
        let file = w.into_inner().map_err(|e| io_err(e.into_error()))?;
        file.sync_all().map_err(io_err)?;
        std::fs::rename(&tmp, path).map_err(io_err)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// That the folder a file is to be written into exists (checked before the work that writes
/// it, so that a typo does not cost a render).
pub fn check_folder(path: &Path) -> Result<(), OutputError> {
    match path.parent() {
        Some(folder) if !folder.as_os_str().is_empty() && !folder.is_dir() => {
            Err(OutputError::NoFolder {
                path: path.to_path_buf(),
                folder: folder.to_path_buf(),
            })
        }
        _ => Ok(()),
    }
}
