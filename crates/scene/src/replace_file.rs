//! Writing an output file without ever leaving a broken one behind.
//!
//! `std::fs::write` truncates the old file first, so a write that fails halfway (disk full, a
//! file-size limit, a signal) destroys a good file and leaves a truncated one. Here the bytes go
//! to a temporary file in the same folder, which is renamed over the target only once it is
//! complete: afterwards the target is either the old file or the new one, never a mix.
//!
//! A rename replaces whatever the name points at, so the target is looked at first (audit g2,
//! where `--out /dev/null` as root turned the device into a regular file):
//! - a **symbolic link** is followed, as a plain write would: the file it names is replaced and
//!   the link stays;
//! - a **device, FIFO or socket** is written in place (there is no file to keep whole), so
//!   `--out /dev/null` discards and `--out /dev/stdout` prints;
//! - a **read-only file** is refused, as a plain write refuses it (a rename would not ask);
//! - a **folder** is refused.
//!
//! (Killed between the temporary file's creation and the rename, a hidden `.myriad-*` file stays
//! beside the target; the target itself is intact.)

use std::io::{Error, ErrorKind, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path`, replacing it only once the whole content is written. On error the
/// old file (if any) is untouched and no temporary file is left. Links are followed, devices
/// and FIFOs written in place, read-only files and folders refused (see the module docs).
pub fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    match Target::of(path)? {
        Target::InPlace(path) => write_in_place(path, bytes),
        Target::Replace(replacement) => replacement.stage(bytes)?.persist(),
    }
}

/// What writing `bytes` to a path will do, decided before a byte is written (so that a set of
/// files, `replace_files`, can refuse any one of them before touching the others).
pub(crate) enum Target<'a> {
    /// A device, FIFO or socket: written in place, through the links as given (`/dev/stdout`'s
    /// last link, `pipe:[…]`, names no path).
    InPlace(&'a Path),
    /// A regular file, existing or new, replaced by a rename.
    Replace(Replacement),
}

/// A regular file to replace: the name links lead to, and the mode the new file gets (the old
/// file's, or for a new file 0666 less the umask).
pub(crate) struct Replacement {
    path: PathBuf,
    #[cfg_attr(not(unix), allow(dead_code))]
    mode: u32,
}

impl<'a> Target<'a> {
    /// Looks at `path`: a folder or a read-only file is an error.
    pub(crate) fn of(path: &'a Path) -> std::io::Result<Self> {
        // `metadata` follows links, as the OS does for a write.
        let existing = match std::fs::metadata(path) {
            Ok(metadata) => Some(metadata),
            Err(e) if e.kind() == ErrorKind::NotFound => None,
            Err(e) => return Err(e),
        };
        Ok(match &existing {
            Some(metadata) if metadata.is_dir() => {
                return Err(Error::new(
                    ErrorKind::IsADirectory,
                    format!("{} is a folder", path.display()),
                ));
            }
            Some(metadata) if !metadata.is_file() => Target::InPlace(path),
            Some(metadata) if metadata.permissions().readonly() => {
                return Err(Error::new(
                    ErrorKind::PermissionDenied,
                    format!("{} is read-only", path.display()),
                ));
            }
            Some(metadata) => Target::Replace(Replacement {
                path: std::fs::canonicalize(path)?,
                mode: mode_of(metadata),
            }),
            None => Target::Replace(Replacement {
                path: follow_links(path)?,
                mode: 0o666,
            }),
        })
    }
}

impl Replacement {
    /// `bytes` written whole, and synced, to a temporary file beside the target.
    pub(crate) fn stage(self, bytes: &[u8]) -> std::io::Result<Staged> {
        let Replacement { path, mode } = self;
        let dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(".myriad-");
        // A temporary file is private (0600); the output should be what a plain write makes.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(mode));
        }
        let mut temp = builder.tempfile_in(dir).map_err(without_temp_name)?;
        temp.write_all(bytes).map_err(without_temp_name)?;
        temp.as_file().sync_all().map_err(without_temp_name)?;
        Ok(Staged { temp, path })
    }
}

/// A replaced target's complete new content, waiting beside it; dropped, it is deleted.
pub(crate) struct Staged {
    temp: tempfile::NamedTempFile,
    path: PathBuf,
}

impl Staged {
    /// Renames the new content over the target.
    pub(crate) fn persist(self) -> std::io::Result<()> {
        self.temp
            .persist(&self.path)
            .map_err(|e| without_temp_name(e.error))?;
        Ok(())
    }
}

/// Writes `bytes` into a device, FIFO or socket (opening a FIFO waits for its reader, as a
/// plain write does).
pub(crate) fn write_in_place(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)?
        .write_all(bytes)
}

/// The permission bits an existing file keeps when it is replaced.
#[cfg(unix)]
fn mode_of(metadata: &std::fs::Metadata) -> u32 {
    use std::os::unix::fs::PermissionsExt;
    metadata.permissions().mode() & 0o7777
}

#[cfg(not(unix))]
fn mode_of(_: &std::fs::Metadata) -> u32 {
    0o666
}

/// The OS error alone: `tempfile` names its hidden temporary file in its errors ("… at path
/// \"dir/.myriad-XXXXXX\"", and hides the OS error behind that text), which the caller, naming
/// the target, would pass on as if the user had asked for that file.
fn without_temp_name(error: Error) -> Error {
    let text = error.to_string();
    match text.split_once(" at path \"") {
        Some((os_error, _)) => Error::new(error.kind(), os_error.to_owned()),
        None => error,
    }
}

/// `path` with symbolic links followed to the name a plain write would create (for a link whose
/// target does not exist yet). More than 40 links is an error, as for the OS.
fn follow_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&path)?;
                path = match path.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(path),
        }
    }
    Err(Error::other(format!(
        "{}: too many levels of symbolic links",
        path.display()
    )))
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
        let e = replace_file(&folder, b"x").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::IsADirectory);
        assert_eq!(e.to_string(), format!("{} is a folder", folder.display()));
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
        // A missing folder is an error too, which does not name the temporary file.
        let e = replace_file(&dir.path().join("no/such/out.json"), b"x").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::NotFound);
        assert!(!e.to_string().contains(".myriad-"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn links_are_followed_and_other_kinds_of_file_are_never_renamed_over() {
        use std::os::unix::fs::{FileTypeExt, PermissionsExt, symlink};
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("real.json");
        std::fs::write(&file, b"old").unwrap();
        // A link (relative, through a second link) is followed: the file is replaced, the
        // links stay links.
        let link = dir.path().join("link.json");
        let link2 = dir.path().join("link2.json");
        symlink("real.json", &link).unwrap();
        symlink(&link, &link2).unwrap();
        replace_file(&link2, b"new").unwrap();
        assert_eq!(std::fs::read(&file).unwrap(), b"new");
        for l in [&link, &link2] {
            assert!(
                std::fs::symlink_metadata(l)
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
        }
        // A dangling link creates its target, as a plain write does.
        let dangling = dir.path().join("dangling.json");
        symlink("created.json", &dangling).unwrap();
        replace_file(&dangling, b"made").unwrap();
        assert_eq!(
            std::fs::read(dir.path().join("created.json")).unwrap(),
            b"made"
        );
        // A socket cannot be written: an error, and it is still a socket (a rename replaced
        // such files, and devices: `--out /dev/null` as root made /dev/null a regular file).
        let socket = dir.path().join("socket");
        let _listener = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        assert!(replace_file(&socket, b"x").is_err());
        assert!(
            std::fs::symlink_metadata(&socket)
                .unwrap()
                .file_type()
                .is_socket()
        );
        // A read-only file is refused and kept.
        let read_only = dir.path().join("read_only.json");
        std::fs::write(&read_only, b"keep").unwrap();
        std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o444)).unwrap();
        let e = replace_file(&read_only, b"x").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::PermissionDenied, "{e}");
        assert_eq!(std::fs::read(&read_only).unwrap(), b"keep");
        // (Devices take the same path: not tested here, where a regression would replace the
        // machine's /dev/null; `tests/cli/render.rs` writes to /dev/null only as a non-root user.)
        // Nothing was left behind.
        let hidden = std::fs::read_dir(dir.path())
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .starts_with('.')
            })
            .count();
        assert_eq!(hidden, 0);
    }
}
