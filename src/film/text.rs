//! Text for images without a system font: the public-domain 8x8 bitmap font of the
//! `font8x8` crate, laid out left to right. The debug overlay and the convergence plot
//! both draw their labels through [`for_each_dot`].

/// Width and height of a glyph in font pixels.
pub const GLYPH: i32 = 8;

/// The glyph of `ch`: bit `col` of byte `row` is set where the glyph is drawn. A
/// character outside ASCII shows as `?`.
pub fn glyph(ch: char) -> [u8; 8] {
    let code = ch as usize;
    let table = &font8x8::legacy::BASIC_LEGACY;
    if code < table.len() {
        table[code]
    } else {
        table[b'?' as usize]
    }
}

/// Calls `dot(x, y)` for every set font pixel of `text`, in font pixels from its top-left
/// corner (character `i` spans `x` in `8 i .. 8 i + 8`), character by character, row by row.
pub fn for_each_dot(text: &str, mut dot: impl FnMut(i32, i32)) {
    for (i, ch) in text.chars().enumerate() {
        for (row, bits) in glyph(ch).iter().enumerate() {
            for col in 0..GLYPH {
                if bits & (1 << col) != 0 {
                    dot(i as i32 * GLYPH + col, row as i32);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dots_follow_the_glyphs_left_to_right() {
        let mut dots = Vec::new();
        for_each_dot("| ", |x, y| dots.push((x, y)));
        assert!(!dots.is_empty());
        // The bar is one column of the first cell; the space draws nothing.
        assert!(dots.iter().all(|&(x, _)| x < GLYPH));
        assert!(dots.iter().all(|&(_, y)| (0..GLYPH).contains(&y)));
        assert_eq!(glyph('\u{e9}'), glyph('?'));
    }
}
