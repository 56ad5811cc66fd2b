//! Reading an input file that is really a file.
//!
//! `std::fs::read` reads until end of file, and a device or a pipe has none: a scene, dump or
//! glTF path naming `/dev/zero` grows the process until memory runs out, and a FIFO blocks
//! forever. Every input of the tool is a regular file, so that is checked on the opened handle
//! (the thing actually read, whatever links led to it) before reading.

use std::io::{self, Read};
use std::path::Path;

/// Reads all of `path`, which must be a regular file (not a device, pipe or folder).
pub fn read_regular_file(path: &Path) -> io::Result<Vec<u8>> {
    let mut file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file (a device, pipe or folder)",
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.read_to_end(&mut bytes)?;
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
        let file = dir.path().join("a.txt");
        std::fs::write(&file, b"bytes").unwrap();
        assert_eq!(read_regular_file(&file).unwrap(), b"bytes");
    }
}
