//! Reading an input file that is really a file.
//!
//! `std::fs::read` reads until end of file, and a device or a pipe has none: a scene, dump or
//! glTF path naming `/dev/zero` grows the process until memory runs out, and a FIFO blocks
//! forever — even `open` blocks on a FIFO until a writer comes. Every input of the tool is a
//! regular file, so that is checked on the path before opening it and again on the opened handle
//! (the thing actually read, whatever links led to it) before reading. The memory for the whole
//! file is reserved fallibly: a file larger than the machine can hold is an error, not an abort.

use std::io::{self, Read};
use std::path::Path;

/// Reads all of `path`, which must be a regular file (not a device, pipe or folder).
pub fn read_regular_file(path: &Path) -> io::Result<Vec<u8>> {
    read_regular_file_up_to(path, u64::MAX)
}

/// Reads at most `limit` bytes of `path`, which must be a regular file: a glTF buffer needs only
/// its declared `byteLength`, whatever the size of the file its URI names.
pub fn read_regular_file_up_to(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let not_regular = || {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file (a device, pipe or folder)",
        )
    };
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    let wanted = meta.len().min(limit);
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(usize::try_from(wanted).unwrap_or(usize::MAX))
        .map_err(|_| {
            io::Error::new(
                io::ErrorKind::OutOfMemory,
                format!("too large to read into memory ({wanted} bytes)"),
            )
        })?;
    file.take(limit).read_to_end(&mut bytes)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_and_folders_are_refused_files_are_read() {
        for path in ["/dev/zero", "/dev/null", "."] {
            let path = Path::new(path);
            if path.exists() {
                let e = read_regular_file(path).unwrap_err();
                assert!(e.to_string().contains("not a regular file"), "{e}");
            }
        }
        let dir = tempfile::tempdir().unwrap();
        // A FIFO with no writer: refused at once (opening it would block forever).
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo (coreutils) made no FIFO"
        );
        let e = read_regular_file(&fifo).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let file = dir.path().join("a.txt");
        std::fs::write(&file, b"bytes").unwrap();
        assert_eq!(read_regular_file(&file).unwrap(), b"bytes");
        assert_eq!(read_regular_file_up_to(&file, 2).unwrap(), b"by");
        assert_eq!(read_regular_file_up_to(&file, 99).unwrap(), b"bytes");
    }
}
