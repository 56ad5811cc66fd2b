//! The README's assignment snippet (and the engine guide's copy of it) is
//! `myriad-assignment`'s crate-level example word for word, so the doctest that `cargo test`
//! runs is the text an engine developer copies. (The README said so while the two had drifted
//! apart: `println!` against `assert_eq!`, an inline argument, a comment.)

use std::path::Path;

/// The rest of the fenced block whose line holds `marker`, from that line on, in the file at
/// `path` (relative to the workspace).
fn fenced_block(path: &str, fence: &str, marker: &str) -> String {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
        .unwrap_or_else(|e| panic!("{path}: {e}"));
    let start = text
        .find(marker)
        .unwrap_or_else(|| panic!("{path}: no {marker:?}"));
    // From the start of the marker's line, so that a doc comment's `//!` comes with it.
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let body = &text[line_start..];
    let end = body
        .find(fence)
        .unwrap_or_else(|| panic!("{path}: the block after {marker:?} never closes"));
    body[..end].to_string()
}

#[test]
fn the_readmes_assignment_snippet_is_the_crate_example_that_runs() {
    let marker = "use myriad_assignment::{Assigner, LightInput, LightLists, Method};";
    let example: String = fenced_block("crates/assignment/src/lib.rs", "//! ```", marker)
        .lines()
        .map(|line| {
            let text = line.strip_prefix("//!").expect("a crate doc line");
            format!("{}\n", text.strip_prefix(' ').unwrap_or(text))
        })
        .collect();
    assert!(
        example.contains("assert_eq!(stats.pairs, 57);"),
        "{example}"
    );
    for doc in ["README.md", "docs/engine-guide.md"] {
        let snippet = fenced_block(doc, "```", marker);
        assert_eq!(
            snippet, example,
            "{doc}'s snippet is not the crate's example"
        );
    }
}
