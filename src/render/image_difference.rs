//! How far apart two images are: the largest difference of any channel of any pixel (of 255).
//! Every "changes nothing" claim — each skip, the tuned prepass, the frame loop's cull — is this
//! number for the image with the saving against the one without, so it is one function.

/// The largest channel difference between two images of the same size (RGBA8 bytes, or any
/// bytes); 0 for two empty images. Panics when their sizes differ: comparing images of two sizes
/// is a bug in the caller, not a difference.
pub fn max_channel_difference(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(
        a.len(),
        b.len(),
        "images of different sizes: {} and {} bytes",
        a.len(),
        b.len()
    );
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::max_channel_difference;

    #[test]
    fn the_largest_channel_difference_either_way() {
        assert_eq!(max_channel_difference(&[], &[]), 0);
        assert_eq!(max_channel_difference(&[1, 2, 3, 255], &[1, 2, 3, 255]), 0);
        assert_eq!(max_channel_difference(&[0, 200, 7, 9], &[3, 190, 7, 9]), 10);
        assert_eq!(max_channel_difference(&[255, 0], &[0, 0]), 255);
        assert_eq!(max_channel_difference(&[0, 0], &[0, 255]), 255);
    }

    #[test]
    #[should_panic(expected = "different sizes")]
    fn images_of_different_sizes_are_refused() {
        max_channel_difference(&[0; 8], &[0; 4]);
    }
}
