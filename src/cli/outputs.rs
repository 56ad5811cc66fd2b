//! An output must never be one of the run's inputs.
//!
//! Outputs replace their file whole (`myriad::scene::replace_file`), which is exactly what
//! destroys an input named again as the output: `assign --scene s.json --out s.json` replaced the
//! scene with its dump, and `scene --gltf m.glb --out m.glb` the model with a scene file (audit
//! g2). Each command checks its outputs against its inputs before any work, through links and
//! other names of the same file (`same_file` compares the files themselves).

use anyhow::{Result, bail};
use std::path::Path;

/// Refuses when `output` is the same file as one of `inputs` (an output that does not exist yet,
/// or is no regular file, is never an input).
pub fn refuse_overwriting_inputs(output: &Path, inputs: &[&Path]) -> Result<()> {
    // Inputs are regular files (the readers refuse anything else), and `same_file` opens both
    // files: opening a FIFO to compare would wait for its writer, which is this run.
    if !std::fs::metadata(output).is_ok_and(|m| m.is_file()) {
        return Ok(());
    }
    for input in inputs {
        if same_file::is_same_file(input, output).unwrap_or(false) {
            bail!(
                "the output {} is the input {}: refusing to overwrite it (name another output)",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}
