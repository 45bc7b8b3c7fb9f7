//! The one colour of each body, shared by every picture of a run: the plots and animation
//! frames of `report::plot` (feature `plot`) and the `viewer` example, so a body keeps its
//! colour from one picture to the next.

/// The colours of moving bodies, by spawn index: matplotlib's `tab10` without its grey, which
/// is kept for static bodies. Ten and more moving bodies reuse them in turn.
pub const BODY_PALETTE: [(u8, u8, u8); 9] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (188, 189, 34),
    (23, 190, 207),
];

/// The colour of every static body: a mid grey that none of [`BODY_PALETTE`] is close to.
pub const STATIC_GREY: (u8, u8, u8) = (120, 120, 120);

/// The colour (sRGB, 0–255) of the body spawned `spawn_index`-th: [`STATIC_GREY`] if it is
/// static, else [`BODY_PALETTE`] at `spawn_index` modulo its length. Indices count static
/// bodies too, so a body's colour does not change when another body becomes static.
///
/// ```
/// use rugosa::report::{BODY_PALETTE, STATIC_GREY, body_colour};
/// assert_eq!(body_colour(0, false), BODY_PALETTE[0]);
/// assert_eq!(body_colour(0, true), STATIC_GREY);
/// assert_eq!(body_colour(9, false), body_colour(0, false));
/// ```
#[must_use]
pub fn body_colour(spawn_index: usize, is_static: bool) -> (u8, u8, u8) {
    if is_static { STATIC_GREY } else { BODY_PALETTE[spawn_index % BODY_PALETTE.len()] }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_bodies_get_distinct_colours_none_of_them_grey() {
        let colours: Vec<_> = (0..BODY_PALETTE.len()).map(|i| body_colour(i, false)).collect();
        for (i, a) in colours.iter().enumerate() {
            assert!(colours[i + 1..].iter().all(|b| b != a), "colour {i} repeats");
            let distance = [a.0.abs_diff(STATIC_GREY.0), a.1.abs_diff(STATIC_GREY.1), a.2.abs_diff(STATIC_GREY.2)];
            assert!(distance.iter().any(|&d| d > 40), "colour {i} is close to the static grey");
        }
    }
}
