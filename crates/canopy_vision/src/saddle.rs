//! A chessboard corner (where two dark squares meet at a point) placed to a fraction of a
//! pixel, as OpenCV's `cornerSubPix` places it (Förstner's operator): at the corner every
//! intensity gradient nearby is perpendicular to the line from the corner to where the gradient
//! is, so the corner is the point `q` minimising `sum (g_p . (p - q))^2` over a window, weighted
//! by a Gaussian of the distance from its middle; solved again about each new estimate.

use crate::gray::Gray;
use bevy_math::DVec2;

/// The most iterations.
const MAX_ITERATIONS: usize = 40;
/// Moves shorter than this end the iteration, pixels.
const SETTLED_PX: f64 = 0.001;

/// The corner near `guess` within a window of `half` pixels either side, or `None` where the
/// window holds no corner (no two gradient directions) or the estimate leaves the window.
///
/// Gradients are taken at the pixels themselves, after a 3 x 3 binomial smoothing, never
/// between them: reading an edge between pixels pulls its place towards the pixel grid by up
/// to a tenth of a pixel, which is the precision sought.
pub fn refine(image: &Gray, guess: DVec2, half: u32) -> Option<DVec2> {
    let half = half.max(1) as i64;
    // Every pixel a window within `half` of the guess can reach, smoothed, with a ring of one
    // more for the differences.
    let reach = 2 * half + 1;
    let (gx, gy) = (guess.x.round() as i64, guess.y.round() as i64);
    let (w, h) = (i64::from(image.width), i64::from(image.height));
    if gx - reach - 2 < 0 || gy - reach - 2 < 0 || gx + reach + 2 >= w || gy + reach + 2 >= h {
        return None;
    }
    let side = (2 * reach + 3) as usize;
    let pixel = |x: i64, y: i64| f64::from(image.pixels[(y * w + x) as usize]);
    let mut smooth = vec![0.0f64; side * side];
    for (k, value) in smooth.iter_mut().enumerate() {
        let (x, y) = (gx - reach - 1 + (k % side) as i64, gy - reach - 1 + (k / side) as i64);
        let row = |y: i64| pixel(x - 1, y) + 2.0 * pixel(x, y) + pixel(x + 1, y);
        *value = (row(y - 1) + 2.0 * row(y) + row(y + 1)) / 16.0;
    }
    let at = |x: i64, y: i64| smooth[((y - gy + reach + 1) as usize) * side + (x - gx + reach + 1) as usize];
    let mut corner = guess;
    for _ in 0..MAX_ITERATIONS {
        let (cx, cy) = (corner.x.round() as i64, corner.y.round() as i64);
        let (mut a, mut b, mut c, mut bx, mut by) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for y in cy - half..=cy + half {
            let wy = (-((y as f64 - corner.y) / half as f64).powi(2)).exp();
            for x in cx - half..=cx + half {
                let weight = wy * (-((x as f64 - corner.x) / half as f64).powi(2)).exp();
                let gradient = DVec2::new(at(x + 1, y) - at(x - 1, y), at(x, y + 1) - at(x, y - 1));
                let (gxx, gxy, gyy) = (
                    gradient.x * gradient.x * weight,
                    gradient.x * gradient.y * weight,
                    gradient.y * gradient.y * weight,
                );
                let (px, py) = (x as f64 - corner.x, y as f64 - corner.y);
                a += gxx;
                b += gxy;
                c += gyy;
                bx += gxx * px + gxy * py;
                by += gxy * px + gyy * py;
            }
        }
        let det = a * c - b * b;
        if det.abs() <= 1e-9 * (a * c).max(1e-300) {
            return None;
        }
        let step = DVec2::new(c * bx - b * by, a * by - b * bx) / det;
        corner += step;
        if corner.distance(guess) > half as f64 {
            return None;
        }
        if step.length() < SETTLED_PX {
            break;
        }
    }
    Some(corner)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chessboard of 16-pixel squares, each pixel the exact share of it that is white, its
    /// corners offset by `shift`.
    fn chessboard(shift: DVec2) -> Gray {
        let (width, height) = (64u32, 64u32);
        // The pieces of a pixel's span `[centre - 0.5, centre + 0.5]` in each square: their
        // lengths and the squares' parities.
        let pieces = |centre: f64, offset: f64| -> Vec<(f64, i64)> {
            let (from, to) = (centre - 0.5 - offset, centre + 0.5 - offset);
            let edge = (to / 16.0).floor() * 16.0;
            let square = |v: f64| (v / 16.0).floor() as i64;
            if edge > from {
                vec![(edge - from, square(from)), (to - edge, square(to))]
            } else {
                vec![(1.0, square(from))]
            }
        };
        let mut image = Gray::filled(width, height, 0);
        for y in 0..height {
            for x in 0..width {
                let mut white = 0.0;
                for (lx, px) in pieces(f64::from(x), shift.x) {
                    for (ly, py) in pieces(f64::from(y), shift.y) {
                        if (px + py).rem_euclid(2) == 0 {
                            white += lx * ly;
                        }
                    }
                }
                image.pixels[(y * width + x) as usize] = (30.0 + white * 190.0).round() as u8;
            }
        }
        image
    }

    #[test]
    fn a_corner_is_found_to_a_twentieth_of_a_pixel_from_a_guess_pixels_off() {
        let shift = DVec2::new(0.37, -0.21);
        let image = chessboard(shift);
        let truth = DVec2::new(32.0, 32.0) + shift;
        let found = refine(&image, truth + DVec2::new(2.0, -1.5), 5).unwrap();
        assert!(found.distance(truth) < 0.05, "{found} against {truth}");
    }

    #[test]
    fn a_window_without_a_corner_gives_none() {
        let image = chessboard(DVec2::ZERO);
        // Inside one square: no gradient at all.
        assert_eq!(refine(&image, DVec2::new(8.0, 8.0), 3), None);
        // At the image's edge.
        assert_eq!(refine(&image, DVec2::new(1.0, 32.0), 5), None);
    }
}
