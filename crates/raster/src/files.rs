//! Reading an input file within bounds: what every file fragsim is handed goes through (a mesh,
//! a dump's header and arrays), so that no input can make it read without end or wait for ever.
//!
//! **Guarantee**: only a regular file is read. The path's type is looked up before the file is
//! opened (links followed, so a link is judged by what it points at): a directory, a FIFO, a
//! character or block device (`/dev/zero`) or a socket is refused by its kind, and never opened,
//! so a FIFO cannot block the reader. On Unix the file is then opened without blocking
//! (`O_NONBLOCK`, which changes nothing for a regular file) and its type checked again on the
//! open handle, so a file swapped for a FIFO between the two looks is refused too. Its size
//! comes from that handle's metadata, is checked against the caller's bound before a byte is
//! read, and the read itself stops one byte past the size, so a file that grows while being
//! read cannot exceed it either.

use std::fs::{File, Metadata, OpenOptions};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Why a file was not read.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The path is not a regular file (a directory, FIFO, device or socket), after links.
    #[error("{}: not a regular file but {kind}; only regular files are read", path.display())]
    NotRegular {
        /// The path given.
        path: PathBuf,
        /// What it is: `a directory`, `a FIFO`, `a character device`, ….
        kind: &'static str,
    },
    /// The file is larger than the reader accepts.
    #[error("{}: {bytes} bytes, more than the {limit} bytes {what}", path.display())]
    TooLarge {
        /// The path given.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// The most accepted.
        limit: u64,
        /// Why that is the most (`a dump header may have`, `the memory cap allows`).
        what: String,
    },
    /// The system refused to look it up, open or read it.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The path given.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
}

impl FileError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What a file of `metadata` is, in words, when it is no regular file.
fn irregular_kind(metadata: &Metadata) -> Option<&'static str> {
    let kind = metadata.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO");
        }
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("neither a file nor a directory")
}

/// Refuses `metadata` of `path` unless it is a regular file's.
fn regular(path: &Path, metadata: &Metadata) -> Result<(), FileError> {
    match irregular_kind(metadata) {
        Some(kind) => Err(FileError::NotRegular {
            path: path.to_path_buf(),
            kind,
        }),
        None => Ok(()),
    }
}

/// `path` opened for reading once it is known to be a regular file, with its size.
///
/// # Errors
/// A path that cannot be looked up or opened, or is no regular file.
pub fn open_regular(path: &Path) -> Result<(File, u64), FileError> {
    // The type first, links followed: a FIFO is never opened (opening one blocks until a writer
    // comes), a device never read.
    regular(
        path,
        &std::fs::metadata(path).map_err(|e| FileError::io(path, e))?,
    )?;
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| FileError::io(path, e))?;
    let metadata = file.metadata().map_err(|e| FileError::io(path, e))?;
    regular(path, &metadata)?;
    Ok((file, metadata.len()))
}

/// The bytes of the regular file `path`, which may hold at most `limit` bytes (`what` says
/// whose limit it is, for the error).
///
/// # Errors
/// As [`open_regular`]; a file of more than `limit` bytes, refused before it is read.
pub fn read_regular(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, FileError> {
    let (file, bytes) = open_regular(path)?;
    let too_large = |size| FileError::TooLarge {
        path: path.to_path_buf(),
        bytes: size,
        limit,
        what: what.to_string(),
    };
    if bytes > limit {
        return Err(too_large(bytes));
    }
    let mut contents = Vec::with_capacity(usize::try_from(bytes).unwrap_or(0));
    // One byte past the size: a file that grew since is seen to, and never read whole.
    file.take(bytes.saturating_add(1))
        .read_to_end(&mut contents)
        .map_err(|e| FileError::io(path, e))?;
    let read = contents.len() as u64;
    if read > limit {
        return Err(too_large(read));
    }
    Ok(contents)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("fragsim-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_regular_file_is_read_and_one_past_the_limit_refused_unread() {
        let dir = scratch("regular");
        let path = dir.join("a");
        std::fs::write(&path, b"12345").unwrap();
        assert_eq!(read_regular(&path, 5, "at most").unwrap(), b"12345");
        let error = read_regular(&path, 4, "the test allows").unwrap_err();
        assert!(
            matches!(error, FileError::TooLarge { bytes: 5, .. }),
            "{error}"
        );
        assert!(error
            .to_string()
            .contains("more than the 4 bytes the test allows"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_directory_is_refused_by_its_kind() {
        let dir = scratch("directory");
        let error = read_regular(&dir, u64::MAX, "").unwrap_err();
        assert!(
            error
                .to_string()
                .contains("not a regular file but a directory"),
            "{error}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_to_a_device_is_refused_unread() {
        let dir = scratch("device");
        let link = dir.join("zeros");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let error = read_regular(&link, u64::MAX, "").unwrap_err();
        assert!(error.to_string().contains("a character device"), "{error}");
        // The control: a link to a regular file is read through.
        std::fs::write(dir.join("data"), b"x").unwrap();
        std::os::unix::fs::symlink(dir.join("data"), dir.join("to-data")).unwrap();
        assert_eq!(read_regular(&dir.join("to-data"), 1, "").unwrap(), b"x");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
