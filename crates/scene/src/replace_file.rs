//! Writing an output file without ever leaving a broken one behind.
//!
//! `std::fs::write` truncates the old file first, so a write that fails halfway (disk full, a
//! file-size limit, a signal) destroys a good file and leaves a truncated one. Here the bytes go
//! to a temporary file in the same folder, which is renamed over the target only once it is
//! complete: afterwards the target is either the old file or the new one, never a mix.

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path`, replacing it only once the whole content is written. On error the
/// old file (if any) is untouched and no temporary file is left.
pub fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".myriad-");
    // A temporary file is private (0600); the output should be what a plain write makes: the old
    // file's mode, or for a new file 0666 less the umask.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(path).map_or(0o666, |m| m.permissions().mode() & 0o7777);
        builder.permissions(std::fs::Permissions::from_mode(mode));
    }
    let mut temp = builder.tempfile_in(dir)?;
    temp.write_all(bytes)?;
    temp.as_file().sync_all()?;
    temp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_whole_files_and_keeps_the_old_one_on_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        replace_file(&path, b"first").unwrap();
        replace_file(&path, b"second, longer").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second, longer");
        // A target that cannot be replaced (a folder) is an error, and nothing is left behind.
        let folder = dir.path().join("folder");
        std::fs::create_dir(&folder).unwrap();
        assert!(replace_file(&folder, b"x").is_err());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 2, "{left:?}");
        // The output's mode is a plain file's, not the temporary file's private 0600; an
        // existing file keeps its own.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            let fresh = dir.path().join("fresh.json");
            replace_file(&fresh, b"x").unwrap();
            std::fs::write(dir.path().join("plain"), b"x").unwrap();
            assert_eq!(mode(&fresh), mode(&dir.path().join("plain")));
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
            replace_file(&path, b"third").unwrap();
            assert_eq!(mode(&path), 0o640);
        }
        // A missing folder is an error too.
        assert!(replace_file(&dir.path().join("no/such/out.json"), b"x").is_err());
    }
}
