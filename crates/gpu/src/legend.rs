//! The heat map's legend: a strip under the image with the colour ramp and its scale
//! (0, half, max lights per pixel), drawn on the CPU after read-back with a built-in 3×5 digit
//! font, so the PNG explains itself.

/// The ramp's colour stops as sRGB bytes (the same stops as `heat_ramp` in
/// `shaders/common/lighting.wgsl`).
const STOPS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.5],
    [0.0, 0.6, 1.0],
    [0.0, 0.9, 0.2],
    [1.0, 0.9, 0.0],
    [0.9, 0.0, 0.0],
];

/// The ramp colour for `t` in [0, 1], as sRGB bytes.
pub fn heat_color(t: f32) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| ((a[c] + (b[c] - a[c]) * f) * 255.0).round() as u8)
}

/// 3×5 glyphs for 0–9, one row per `u8` (bits 2..0 = left..right).
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

/// Pixels per font pixel.
const SCALE: u32 = 2;
/// Height of the legend strip.
pub const LEGEND_HEIGHT: u32 = 28;

/// The labels under the bar and the x of each one's left edge: the largest count's
/// (right-aligned on the bar's end), 0's (left-aligned) and then the middle's (centred), each only
/// where its box — its digits and a font pixel of space after them — overlaps none placed before.
/// On a narrow image the middle label would run into the last one (on a 64-pixel image "125" and
/// "250" overlapped and read as "8"s); it is left out there, and the ramp's ends keep theirs.
fn placed_labels(margin: u32, bar_width: u32, heat_max: u32) -> Vec<(String, u32)> {
    let mut placed: Vec<(String, u32)> = Vec::with_capacity(3);
    let text_width = |text: &str| text.len() as u32 * 4 * SCALE;
    for (value, at) in [(heat_max, 1.0), (0, 0.0), (heat_max / 2, 0.5)] {
        let text = value.to_string();
        let width = text_width(&text);
        let anchor = margin + (at * (bar_width - 1) as f32) as u32;
        let x0 = anchor.saturating_sub((width as f32 * at) as u32);
        let clear = placed
            .iter()
            .all(|(other, x)| x0 + width <= *x || x + text_width(other) <= x0);
        if clear {
            placed.push((text, x0));
        }
    }
    placed
}

/// Returns the image with a legend strip appended below it, and the new height. `heat_max` is
/// the light count at the top of the ramp.
pub fn with_heat_legend(rgba: &[u8], width: u32, height: u32, heat_max: u32) -> (Vec<u8>, u32) {
    let new_height = height + LEGEND_HEIGHT;
    // In usize: a wide image's bytes pass u32.
    let bytes = width as usize * new_height as usize * 4;
    let mut out = Vec::with_capacity(bytes);
    out.extend_from_slice(rgba);
    out.resize(bytes, 0);
    let mut put = |x: u32, y: u32, c: [u8; 3]| {
        if x < width && y < new_height {
            let i = (y as usize * width as usize + x as usize) * 4;
            out[i..i + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
        }
    };
    // Background, then the ramp bar across the width (with a margin).
    for y in height..new_height {
        for x in 0..width {
            put(x, y, [16, 16, 16]);
        }
    }
    let margin = 4.min(width / 4);
    let bar_width = width.saturating_sub(2 * margin).max(1);
    for y in height + 3..height + 13 {
        for x in 0..bar_width {
            put(
                margin + x,
                y,
                heat_color(x as f32 / (bar_width - 1).max(1) as f32),
            );
        }
    }
    // Labels at 0, the middle and the end of the bar.
    let text_y = height + 16;
    for (text, x0) in placed_labels(margin, bar_width, heat_max) {
        for (n, ch) in text.bytes().enumerate() {
            let glyph = DIGITS[(ch - b'0') as usize];
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for dy in 0..SCALE {
                            for dx in 0..SCALE {
                                put(
                                    x0 + (n as u32 * 4 + col) * SCALE + dx,
                                    text_y + row as u32 * SCALE + dy,
                                    [230, 230, 230],
                                );
                            }
                        }
                    }
                }
            }
        }
    }
    (out, new_height)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_and_stops() {
        assert_eq!(heat_color(0.0), [0, 0, 128]);
        assert_eq!(heat_color(1.0), [230, 0, 0]);
        assert_eq!(heat_color(0.5), [0, 230, 51]);
        assert_eq!(heat_color(-1.0), heat_color(0.0));
        assert_eq!(heat_color(2.0), heat_color(1.0));
    }

    #[test]
    fn legend_keeps_image_and_draws_bar_and_labels() {
        let (w, h) = (64, 8);
        let image = vec![7u8; (w * h * 4) as usize];
        let (out, new_h) = with_heat_legend(&image, w, h, 250);
        assert_eq!(new_h, h + LEGEND_HEIGHT);
        assert_eq!(&out[..image.len()], &image[..]);
        let px = |x: u32, y: u32| {
            let i = ((y * w + x) * 4) as usize;
            [out[i], out[i + 1], out[i + 2]]
        };
        assert_eq!(px(4, h + 5), heat_color(0.0));
        assert_eq!(px(4 + 55, h + 5), heat_color(1.0));
        // Some label pixels are lit in the text row.
        let lit = (0..w)
            .flat_map(|x| (h + 16..h + 26).map(move |y| (x, y)))
            .filter(|&(x, y)| px(x, y) == [230, 230, 230])
            .count();
        assert!(lit > 20, "only {lit} label pixels");
    }

    /// The whole strip of a legend for 250 lights on a 96-pixel-wide image, pixel by pixel:
    /// background, the ramp across the bar (rows 3..13, 4-pixel margins) from its first to its
    /// last colour, and the labels "0", "125" and "250" in the 3×5 font at twice its size, left-,
    /// centre- and right-aligned on the bar. Where the labels go and which digits they show is
    /// what a reader of the PNG relies on; a shifted, mirrored or wrong digit is caught here.
    #[test]
    fn legend_strip_is_background_ramp_and_the_three_labels_pixel_for_pixel() {
        const TEXT: [&str; 10] = [
            "....######...........................##....######..######..........######..######..######.......",
            "....######...........................##....######..######..........######..######..######.......",
            "....##..##.........................####........##..##..................##..##......##..##.......",
            "....##..##.........................####........##..##..................##..##......##..##.......",
            "....##..##...........................##....######..######..........######..######..##..##.......",
            "....##..##...........................##....######..######..........######..######..##..##.......",
            "....##..##...........................##....##..........##..........##..........##..##..##.......",
            "....##..##...........................##....##..........##..........##..........##..##..##.......",
            "....######.........................######..######..######..........######..######..######.......",
            "....######.........................######..######..######..........######..######..######.......",
        ];
        let (w, h) = (96, 2);
        let image: Vec<u8> = (0..w * h * 4).map(|v| v as u8).collect();
        let (out, new_h) = with_heat_legend(&image, w, h, 250);
        assert_eq!(new_h, h + LEGEND_HEIGHT);
        assert_eq!(out.len(), (w * new_h * 4) as usize);
        assert_eq!(&out[..image.len()], &image[..], "the image above is kept");
        for y in 0..LEGEND_HEIGHT {
            for x in 0..w {
                let want = match y {
                    3..13 if (4..92).contains(&x) => heat_color((x - 4) as f32 / 87.0),
                    16..26 if TEXT[(y - 16) as usize].as_bytes()[x as usize] == b'#' => [230; 3],
                    _ => [16; 3],
                };
                let i = (((h + y) * w + x) * 4) as usize;
                assert_eq!(
                    out[i..i + 4],
                    [want[0], want[1], want[2], 255],
                    "legend pixel ({x}, {y})"
                );
            }
        }
    }

    /// On an image too narrow for its labels (12 pixels, labels "10000" and "20000") the margin
    /// shrinks to a quarter of the width and the labels are cut at the right edge: nothing they
    /// would draw past it wraps into the next row, so the strip's last two rows stay background.
    #[test]
    fn labels_wider_than_a_narrow_image_are_clipped_at_its_edge_not_wrapped() {
        let (w, h) = (12, 2);
        let image = vec![7u8; (w * h * 4) as usize];
        let (out, new_h) = with_heat_legend(&image, w, h, 20_000);
        assert_eq!(out.len(), (w * new_h * 4) as usize);
        let px = |x: u32, y: u32| {
            let i = ((y * w + x) * 4) as usize;
            [out[i], out[i + 1], out[i + 2], out[i + 3]]
        };
        // A 3-pixel margin (12 / 4), then the ramp's first colour.
        let first = heat_color(0.0);
        assert_eq!(px(2, h + 5), [16, 16, 16, 255]);
        assert_eq!(px(3, h + 5), [first[0], first[1], first[2], 255]);
        // The digits' last row is h + 25: nothing lit below it.
        for y in h + 26..new_h {
            for x in 0..w {
                assert_eq!(px(x, y), [16, 16, 16, 255], "pixel ({x}, {y})");
            }
        }
        // The labels were drawn (cut, not dropped): their bottom row is lit up to the edge.
        assert_eq!(px(w - 1, h + 25), [230, 230, 230, 255]);
    }
    /// Placed labels never overlap (their boxes keep a font pixel apart), the largest count is
    /// always labelled, 0 wherever it fits beside it, and the middle label only where it fits
    /// between them — from the 64-pixel image whose "125" ran into "250" to a 1920-pixel one.
    #[test]
    fn placed_labels_never_overlap_and_keep_the_ramps_ends() {
        for heat_max in [0, 1, 9, 250, 20_000, 4_000_000_000] {
            for width in 1..=1920u32 {
                let margin = 4.min(width / 4);
                let bar_width = width.saturating_sub(2 * margin).max(1);
                let labels = placed_labels(margin, bar_width, heat_max);
                let context = format!("width {width}, max {heat_max}");
                assert_eq!(labels[0].0, heat_max.to_string(), "{context}");
                let boxes: Vec<(u32, u32)> = labels
                    .iter()
                    .map(|(text, x)| (*x, x + text.len() as u32 * 4 * SCALE))
                    .collect();
                for (a, &(a0, a1)) in boxes.iter().enumerate() {
                    for &(b0, b1) in &boxes[a + 1..] {
                        assert!(a1 <= b0 || b1 <= a0, "{context}: {labels:?} overlap");
                    }
                }
                if width >= 400 && heat_max > 1 {
                    assert_eq!(labels.len(), 3, "{context}: {labels:?}");
                }
            }
        }
        let texts = |width: u32| -> Vec<String> {
            let margin = 4.min(width / 4);
            let labels = placed_labels(margin, width - 2 * margin, 250);
            labels.into_iter().map(|(text, _)| text).collect()
        };
        assert_eq!(texts(64), ["250", "0"], "the middle label does not fit");
        assert_eq!(texts(96), ["250", "0", "125"]);
    }
}
