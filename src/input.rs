//! Input files a scene names (image textures, OBJ meshes): opened only when
//! they are regular files, read within a bound, and told apart by what they
//! are, not by the names that lead to them.
//!
//! A path that is something else is refused before it is opened (a FIFO
//! would wait for a writer; a device may never end), and again after (what
//! was opened, not what was looked at a moment before). The callers word
//! the refusals: each names its own kind of file and field.

use crate::output::{clip_to, printable};
use std::fs::{File, Metadata};
use std::io::Read;
use std::path::{Path, PathBuf};

/// What identifies a file however it is named: its device and inode.
#[cfg(unix)]
pub type FileId = (u64, u64);
#[cfg(unix)]
fn file_id(meta: &Metadata, _path: &Path) -> FileId {
    use std::os::unix::fs::MetadataExt;
    (meta.dev(), meta.ino())
}
/// What identifies a file however it is named: its canonical path.
#[cfg(not(unix))]
pub type FileId = PathBuf;
#[cfg(not(unix))]
fn file_id(_meta: &Metadata, path: &Path) -> FileId {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// A regular file, open.
#[derive(Debug)]
pub struct Regular {
    pub path: PathBuf,
    pub file: File,
    pub meta: Metadata,
    pub id: FileId,
}

/// Why a path cannot be read as an input file.
#[derive(Debug)]
pub enum Unusable {
    /// Something other than a regular file is there: "a folder", "a FIFO
    /// (named pipe)", "a socket", "a device", "not a regular file".
    NotAFile(&'static str),
    /// A symbolic link to nothing.
    DanglingLink,
    /// The path could not be looked at or opened.
    Io(std::io::Error),
}

impl Unusable {
    /// The refusal as the rest of a sentence about the file ("is a folder,
    /// {not_what}"; `not_what` says what the file should have been).
    pub fn describe(&self, not_what: &str) -> String {
        match self {
            Unusable::NotAFile(what) => format!("is {what}, {not_what}"),
            Unusable::DanglingLink => "is a symbolic link to a file that does not exist".into(),
            Unusable::Io(e) => format!("cannot be read: {e}"),
        }
    }
}

/// The regular file at `path`, open; `None` when nothing is there.
pub fn open_regular(path: &Path) -> Result<Option<Regular>, Unusable> {
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if matches!(e.kind(), std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory) => {
            if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(Unusable::DanglingLink);
            }
            return Ok(None);
        }
        Err(e) => return Err(Unusable::Io(e)),
    };
    if let Some(what) = not_a_file(&meta) {
        return Err(Unusable::NotAFile(what));
    }
    let file = File::open(path).map_err(Unusable::Io)?;
    let meta = file.metadata().map_err(Unusable::Io)?;
    if let Some(what) = not_a_file(&meta) {
        return Err(Unusable::NotAFile(what));
    }
    Ok(Some(Regular { id: file_id(&meta, path), path: path.to_path_buf(), file, meta }))
}

/// What a path that is not a regular file is; `None` for a regular file.
fn not_a_file(meta: &Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        } else if t.is_socket() {
            return Some("a socket");
        } else if t.is_block_device() || t.is_char_device() {
            return Some("a device");
        }
    }
    Some("not a regular file")
}

/// Why [`read_bounded`] read nothing.
#[derive(Debug)]
pub enum ReadError {
    /// More than the bound: the size the file has (`None`: it grew while read).
    TooLarge(Option<u64>),
    Io(std::io::Error),
}

/// An open file's bytes (from where it stands), refused beyond `max` bytes:
/// by its size before reading, and while reading a file that grows.
pub fn read_bounded(file: &File, meta: &Metadata, max: u64) -> Result<Vec<u8>, ReadError> {
    if meta.len() > max {
        return Err(ReadError::TooLarge(Some(meta.len())));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(max + 1).read_to_end(&mut bytes).map_err(ReadError::Io)?;
    if bytes.len() as u64 > max {
        return Err(ReadError::TooLarge(None));
    }
    Ok(bytes)
}

/// A path for a message: its control characters escaped, at most 300
/// characters (a name may have 4,096 bytes; the message is one line).
pub fn shown(path: &Path) -> String {
    clip_to(&printable(&path.display().to_string()), 300)
}

/// `"at <path> "` when the file read is not the name a scene gives (`name`),
/// else `""`.
pub fn at(path: &Path, name: &str) -> String {
    if path == Path::new(name) {
        String::new()
    } else {
        format!("at {} ", shown(path))
    }
}
