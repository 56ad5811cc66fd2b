//! Text from files, made safe to print.
//!
//! Why: a name in a model (a camera's, a light's, a material's) or an unknown key in a scene
//! file is the file's own text, and the tools print it in summaries, warnings and errors. A
//! control character in it — an escape sequence, a carriage return, a newline — reached the
//! terminal raw: a hostile model could clear the screen or print a fake `error:` line inside a
//! warning (hostile-input hunt, session 38). Bidirectional overrides are escaped too: they
//! reorder what the terminal shows.

use std::borrow::Cow;

/// Whether `c` is escaped by [`printable`]: a control character, or a bidirectional embedding,
/// override or isolate (U+202A–U+202E, U+2066–U+2069).
fn needs_escape(c: char) -> bool {
    c.is_control() || matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// `text` with each control character and bidirectional override escaped as Rust writes it
/// (`\u{1b}`, `\n`, `\r`, `\t`, `\u{202e}`); everything else, quotes and backslashes included,
/// as it is. Borrowed unchanged when nothing needs escaping.
pub fn printable(text: &str) -> Cow<'_, str> {
    if !text.chars().any(needs_escape) {
        return Cow::Borrowed(text);
    }
    let mut shown = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if needs_escape(c) {
            shown.extend(c.escape_debug());
        } else {
            shown.push(c);
        }
    }
    Cow::Owned(shown)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_text_is_borrowed_unchanged() {
        for text in ["Main", "Säulen \"links\" \\ 3", ""] {
            assert!(matches!(printable(text), Cow::Borrowed(t) if t == text));
        }
    }

    #[test]
    fn control_characters_and_overrides_are_escaped() {
        let hostile = "Ma\u{1b}[2J\u{1b}[31mIN\r\nerror: fake\t\u{202e}gnp.exe\u{7f}";
        let shown = printable(hostile);
        assert_eq!(
            shown,
            "Ma\\u{1b}[2J\\u{1b}[31mIN\\r\\nerror: fake\\t\\u{202e}gnp.exe\\u{7f}"
        );
        assert!(!shown.chars().any(needs_escape), "{shown}");
    }
}
