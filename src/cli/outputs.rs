//! An output must never be one of the run's inputs.
//!
//! Outputs replace their file whole (`myriad::scene::replace_file`), which is exactly what
//! destroys an input named again as the output: `assign --scene s.json --out s.json` replaced the
//! scene with its dump, and `scene --gltf m.glb --out m.glb` the model with a scene file (audit
//! g2). Each command checks its outputs against its inputs before any work, through links and
//! other names of the same file (`same_file` compares the files themselves).
//!
//! The check must never wait. `same_file` opens both paths, and opening a FIFO waits for the
//! other end, which is this very run: an input naming a FIFO hung the check forever whenever the
//! output already existed (audit: `assign --scene fifo --out existing.json`). So both kinds are
//! looked at first, without opening anything, and only two regular files are compared; anything
//! else cannot be the same file as a regular output, and the readers refuse a non-regular input
//! with their own message.

use anyhow::{Context, Result, bail};
use std::path::Path;

/// Refuses when `output` is the same file as one of `inputs` (an output that does not exist yet,
/// or is no regular file, is never an input). Never opens a path that is not a regular file.
pub fn refuse_overwriting_inputs(output: &Path, inputs: &[&Path]) -> Result<()> {
    if let Some(input) = the_input(output, inputs) {
        bail!(
            "the output {} is the input {}: refusing to overwrite it (name another output)",
            output.display(),
            input.display()
        );
    }
    Ok(())
}

/// Refuses when `output` is one of the files a glTF model `model` is made of (`Model::files`:
/// its external buffers and images), as [`refuse_overwriting_inputs`] does for named inputs.
pub fn refuse_overwriting_model_files(output: &Path, model: &Path, files: &[&Path]) -> Result<()> {
    if let Some(file) = the_input(output, files) {
        bail!(
            "the output {} is {}, a file of the model {}: refusing to overwrite it (name another \
             output)",
            output.display(),
            file.display(),
            model.display()
        );
    }
    Ok(())
}

/// The first of `inputs` that is the same file as `output`, if any (an output that does not
/// exist yet, or is no regular file, is never an input).
fn the_input<'a>(output: &Path, inputs: &[&'a Path]) -> Option<&'a Path> {
    if !is_regular_file(output) {
        return None;
    }
    inputs.iter().copied().find(|input| {
        is_regular_file(input) && same_file::is_same_file(input, output).unwrap_or(false)
    })
}

/// Whether `path`, links followed, is a regular file: `metadata` is a `stat`, which never opens
/// (and so never waits on) a FIFO or a device.
fn is_regular_file(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

/// Creates the `--out` folder `out` (and its parents). A file in its place is named as such,
/// where `create_dir_all` said only "cannot create afile: File exists (os error 17)"
/// (hostile-input hunt, session 38).
pub fn create_out_folder(out: &Path) -> Result<()> {
    check_out_folder(out)?;
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create the folder {}", out.display()))
}

/// Makes sure, before any work, that the `--out` folder `out` can be made and written into, and
/// leaves no trace: the folders it had to make are removed again, so a run refused later leaves
/// no empty output folder. `render` and `paper` found a folder they could not make or write
/// into only after minutes of rendering (audit).
pub fn check_out_folder_writable(out: &Path) -> Result<()> {
    check_out_folder(out)?;
    // The folders that do not exist yet, innermost first.
    let missing: Vec<&Path> = out
        .ancestors()
        .take_while(|p| !p.as_os_str().is_empty() && !p.exists())
        .collect();
    let written = create_out_folder(out).and_then(|()| {
        // A probe of this process's own name, removed at once: the run's files are written to
        // temporary names and renamed the same way (`replace_files`).
        let probe = out.join(format!(".myriad-write-probe-{}", std::process::id()));
        std::fs::write(&probe, b"")
            .with_context(|| format!("cannot write into the folder {}", out.display()))?;
        let _ = std::fs::remove_file(&probe);
        Ok(())
    });
    for folder in missing {
        let _ = std::fs::remove_dir(folder);
    }
    written
}

/// Refuses an `--out` folder `out` that is something else (a file), before any work.
fn check_out_folder(out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        bail!(
            "--out {}: is not a folder (the run writes its files into it)",
            out.display()
        );
    }
    Ok(())
}

/// Says what a command wrote to `output`: on stdout, unless the output is not a regular file
/// (`--out /dev/stdout`, a pipe), where stdout may be the output itself and the line would
/// corrupt it (`assign --out /dev/stdout | jq` read the dump with the summary glued to its end):
/// then on stderr.
pub fn say_written(output: &Path, line: &str) {
    if is_regular_file(output) {
        println!("{line}");
    } else {
        eprintln!("{line}");
    }
}
