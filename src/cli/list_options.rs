//! A list option names each item once.
//!
//! A comma-separated option that names an item twice does the work twice and reports it twice:
//! `report --grids 4x4x4,4x4x4` timed every row twice and wrote each one twice into its table,
//! JSON and plot, where `bench --methods exact,exact` was already refused (audit g2). Items are
//! compared once parsed, so two spellings of one item (`4x4x4` and `04x4x4`) are one item.

use anyhow::{Result, ensure};

/// Refuses `items` (the parsed values of `flag`) when one appears twice, naming it by `name`.
pub fn refuse_repeats<T: PartialEq>(
    flag: &str,
    items: &[T],
    name: impl Fn(&T) -> String,
) -> Result<()> {
    for (i, item) in items.iter().enumerate() {
        ensure!(
            !items[..i].contains(item),
            "{flag} lists {} twice",
            name(item)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repeat_is_named_and_distinct_items_pass() {
        refuse_repeats("--x", &[1, 2, 3], |n| n.to_string()).unwrap();
        let e = refuse_repeats("--x", &[1, 2, 1], |n| n.to_string()).unwrap_err();
        assert_eq!(e.to_string(), "--x lists 1 twice");
    }
}
