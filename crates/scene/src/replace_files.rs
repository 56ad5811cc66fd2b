//! Writing a set of output files that belong together: all of them, or none.
//!
//! `render` writes frame.png, heatmap.png and stats.json, which describe one run. Written one by
//! one with `replace_file`, a failure at the last (a folder in its place, a full disk) left the
//! first two new beside an old third: a set that no run produced (audit). Here every target is
//! looked at first (a folder or a read-only file refuses the whole set before anything is
//! written), then every file's content is staged whole in a temporary file beside its target,
//! and only when all are staged are they renamed in. On an error before the renames, no target
//! has changed and no temporary file is left.
//!
//! Targets written in place (devices, FIFOs: see `replace_file`) have no old content to keep;
//! they are written after everything is staged, before the renames.

use crate::replace_file::{Target, write_in_place};
use std::path::{Path, PathBuf};

/// Which file of a set failed, and why.
#[derive(Debug)]
pub struct ReplaceFilesError {
    /// The file, as the caller named it.
    pub path: PathBuf,
    /// What went wrong with it.
    pub error: std::io::Error,
}

impl std::fmt::Display for ReplaceFilesError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write {}: {}", self.path.display(), self.error)
    }
}

impl std::error::Error for ReplaceFilesError {}

/// Refuses, before any work, a set whose targets `replace_files` would refuse (a folder, a
/// read-only file): a run that cannot write its outputs should say so before it runs.
pub fn check_replaceable(paths: &[&Path]) -> Result<(), ReplaceFilesError> {
    for &path in paths {
        Target::of(path).map_err(|error| ReplaceFilesError {
            path: path.to_path_buf(),
            error,
        })?;
    }
    Ok(())
}

/// Writes every `(path, bytes)` of `files` as `replace_file` does, but as one set: on an error
/// before the final renames no target has changed (see the module docs).
pub fn replace_files(files: &[(&Path, &[u8])]) -> Result<(), ReplaceFilesError> {
    let failed = |path: &Path| {
        let path = path.to_path_buf();
        move |error| ReplaceFilesError { path, error }
    };
    let targets = files
        .iter()
        .map(|&(path, _)| Target::of(path).map_err(failed(path)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut in_place = Vec::new();
    let mut staged = Vec::new();
    for (target, &(path, bytes)) in targets.into_iter().zip(files) {
        match target {
            Target::InPlace(device) => in_place.push((device, bytes)),
            Target::Replace(replacement) => {
                staged.push((path, replacement.stage(bytes).map_err(failed(path))?));
            }
        }
    }
    for (device, bytes) in in_place {
        write_in_place(device, bytes).map_err(failed(device))?;
    }
    for (path, file) in staged {
        file.persist().map_err(failed(path))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let [a, b, c] = ["a.png", "b.png", "c.json"].map(|n| dir.path().join(n));
        std::fs::write(&a, b"old a").unwrap();
        replace_files(&[(&a, b"new a"), (&b, b"new b")]).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(std::fs::read(&b).unwrap(), b"new b");
        // The last target is a folder: refused, and the others keep their old content.
        std::fs::create_dir(&c).unwrap();
        let e = replace_files(&[(&a, b"newer a"), (&b, b"newer b"), (&c, b"c")]).unwrap_err();
        assert_eq!(e.path, c);
        assert_eq!(e.error.kind(), std::io::ErrorKind::IsADirectory);
        assert_eq!(
            e.to_string(),
            format!("cannot write {}: {} is a folder", c.display(), c.display())
        );
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        assert_eq!(std::fs::read(&b).unwrap(), b"new b");
        assert_eq!(check_replaceable(&[&a, &c]).unwrap_err().path, c);
        check_replaceable(&[&a, &b, &dir.path().join("new.json")]).unwrap();
        // A target whose folder is missing fails at staging, after the others were staged:
        // still nothing changed, and no temporary file is left.
        let missing = dir.path().join("no/such.json");
        let e = replace_files(&[(&a, b"newer a"), (&missing, b"x")]).unwrap_err();
        assert_eq!(e.path, missing);
        assert_eq!(std::fs::read(&a).unwrap(), b"new a");
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, ["a.png", "b.png", "c.json"]);
    }
}
