//! From a grey image to dark closed outlines: the adaptive threshold (a pixel is dark when it
//! is darker than the mean of the window around it by an offset, OpenCV's
//! `ADAPTIVE_THRESH_MEAN_C`), the dark regions as 8-connected components, and each region's
//! outer boundary traced as a closed chain of pixels, simplified to a polygon
//! (Douglas–Peucker).

use crate::gray::Gray;
use bevy_math::Vec2;

/// Sums of the image over every rectangle from the top-left corner, for window means in
/// constant time.
pub struct Integral {
    width: usize,
    height: usize,
    /// `(width + 1) * (height + 1)` sums; the first row and column are zero.
    sums: Vec<u32>,
}

impl Integral {
    /// The sums of `gray`.
    pub fn new(gray: &Gray) -> Self {
        let (width, height) = (gray.width as usize, gray.height as usize);
        let stride = width + 1;
        let mut sums = vec![0u32; stride * (height + 1)];
        for y in 0..height {
            let mut row = 0u32;
            let source = &gray.pixels[y * width..(y + 1) * width];
            let (above, below) = sums.split_at_mut((y + 1) * stride);
            let above = &above[y * stride..];
            for x in 0..width {
                row += u32::from(source[x]);
                below[x + 1] = above[x + 1] + row;
            }
        }
        Self { width, height, sums }
    }

    /// The dark mask: 1 where a pixel is at most the mean of the `window x window` square
    /// around it (clipped to the image) minus `offset`, else 0.
    pub fn threshold(&self, gray: &Gray, window: u32, offset: f32, mask: &mut Vec<u8>) {
        let (width, height, stride) = (self.width, self.height, self.width + 1);
        let half = (window / 2) as usize;
        mask.clear();
        mask.resize(width * height, 0);
        for y in 0..height {
            let (y0, y1) = (y.saturating_sub(half), (y + half + 1).min(height));
            let (top, bottom) =
                (&self.sums[y0 * stride..(y0 + 1) * stride], &self.sums[y1 * stride..(y1 + 1) * stride]);
            let row = &gray.pixels[y * width..(y + 1) * width];
            let out = &mut mask[y * width..(y + 1) * width];
            let rows = (y1 - y0) as f32;
            // `pixel <= sum / area - offset`, as `(pixel + offset) * area <= sum`.
            let dark = |x: usize, x0: usize, x1: usize| {
                let sum = bottom[x1] + top[x0] - bottom[x0] - top[x1];
                u8::from((f32::from(row[x]) + offset) * ((x1 - x0) as f32 * rows) <= sum as f32)
            };
            if width <= 2 * half + 1 {
                for (x, out) in out.iter_mut().enumerate() {
                    *out = dark(x, x.saturating_sub(half), (x + half + 1).min(width));
                }
                continue;
            }
            for x in (0..half).chain(width - half - 1..width) {
                out[x] = dark(x, x.saturating_sub(half), (x + half + 1).min(width));
            }
            // The interior, where the window is whole: one pass of slices the compiler can
            // vectorize.
            let area = (2 * half + 1) as f32 * rows;
            let span = width - 2 * half - 1;
            let corners = bottom[2 * half + 1..].iter().zip(top).zip(bottom).zip(&top[2 * half + 1..]);
            for ((((&br, &tl), &bl), &tr), (&pixel, out)) in
                corners.zip(row[half..].iter().zip(&mut out[half..])).take(span)
            {
                let sum = br + tl - bl - tr;
                *out = u8::from((f32::from(pixel) + offset) * area <= sum as f32);
            }
        }
    }
}

/// A dark region's outer boundary: pixel centres in order, clockwise as seen on the image
/// (y down).
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// Boundary pixels, each once per pass.
    pub points: Vec<[i32; 2]>,
}

/// The eight neighbours clockwise on the image from east (x right, y down).
const NEIGHBOURS: [[i32; 2]; 8] = [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1]];

/// The outer boundaries of the 8-connected regions of `mask` whose bounding box is at least
/// `min_side` and at most `max_side` pixels on its longer side; `labels` is scratch space.
pub fn outer_contours(
    mask: &[u8],
    width: u32,
    height: u32,
    min_side: u32,
    max_side: u32,
    labels: &mut Vec<u32>,
) -> Vec<Contour> {
    let (w, h) = (width as usize, height as usize);
    let regions = label_regions(mask, w, h, labels);
    let mut contours = Vec::new();
    for region in regions {
        let side = (region.max[0] - region.min[0] + 1).max(region.max[1] - region.min[1] + 1) as u32;
        if side < min_side || side > max_side {
            continue;
        }
        contours.push(trace(mask, w, h, region.start));
    }
    contours
}

/// A region's first pixel in raster order (on its outer boundary, its west neighbour outside)
/// and its bounding box.
struct Region {
    start: [i32; 2],
    min: [i32; 2],
    max: [i32; 2],
}

/// Labels the 8-connected regions of `mask` (one pass with union–find, each provisional
/// label keeping its first pixel and bounding box) and returns them in the raster order of
/// their first pixels.
fn label_regions(mask: &[u8], w: usize, h: usize, labels: &mut Vec<u32>) -> Vec<Region> {
    labels.clear();
    labels.resize(w * h, 0);
    // parent[0] is the background; provisional labels start at 1, each with a region.
    let mut parent: Vec<u32> = vec![0];
    let mut boxes: Vec<Region> = vec![Region { start: [0, 0], min: [0, 0], max: [0, 0] }];
    for y in 0..h {
        let row = &mask[y * w..(y + 1) * w];
        for (x, &dark) in row.iter().enumerate() {
            if dark == 0 {
                continue;
            }
            let i = y * w + x;
            // Already-labelled neighbours: west, north-west, north, north-east.
            let mut label = 0;
            let mut join = |other: u32, parent: &mut Vec<u32>| {
                if other == 0 {
                    return;
                }
                if label == 0 {
                    label = find(parent, other);
                } else {
                    let (a, b) = (find(parent, label), find(parent, other));
                    if a != b {
                        let (low, high) = (a.min(b), a.max(b));
                        parent[high as usize] = low;
                        label = low;
                    }
                }
            };
            if x > 0 {
                join(labels[i - 1], &mut parent);
            }
            if y > 0 {
                let above = i - w;
                if x > 0 {
                    join(labels[above - 1], &mut parent);
                }
                join(labels[above], &mut parent);
                if x + 1 < w {
                    join(labels[above + 1], &mut parent);
                }
            }
            let (xi, yi) = (x as i32, y as i32);
            if label == 0 {
                label = parent.len() as u32;
                parent.push(label);
                boxes.push(Region { start: [xi, yi], min: [xi, yi], max: [xi, yi] });
            } else {
                let region = &mut boxes[label as usize];
                region.min = [region.min[0].min(xi), region.min[1].min(yi)];
                region.max = [region.max[0].max(xi), region.max[1].max(yi)];
            }
            labels[i] = label;
        }
    }
    // Each set's root is its smallest label, created at the set's first pixel in raster
    // order; the other labels' boxes are merged into it.
    for label in (1..parent.len()).rev() {
        let root = find(&mut parent, label as u32) as usize;
        if root != label {
            let (min, max) = (boxes[label].min, boxes[label].max);
            let region = &mut boxes[root];
            region.min = [region.min[0].min(min[0]), region.min[1].min(min[1])];
            region.max = [region.max[0].max(max[0]), region.max[1].max(max[1])];
        }
    }
    (1..parent.len())
        .filter(|&label| parent[label] == label as u32)
        .map(|label| std::mem::replace(&mut boxes[label], Region { start: [0, 0], min: [0, 0], max: [0, 0] }))
        .collect()
}

fn find(parent: &mut [u32], mut label: u32) -> u32 {
    while parent[label as usize] != label {
        let grand = parent[parent[label as usize] as usize];
        parent[label as usize] = grand;
        label = grand;
    }
    label
}

/// Follows the outer boundary of the region holding `start` (Moore-neighbour tracing with
/// Jacob's stopping rule): from each boundary pixel, the neighbours are searched clockwise
/// from the one after the background pixel it was entered beside.
fn trace(mask: &[u8], w: usize, h: usize, start: [i32; 2]) -> Contour {
    let dark = |p: [i32; 2]| {
        p[0] >= 0
            && p[1] >= 0
            && (p[0] as usize) < w
            && (p[1] as usize) < h
            && mask[p[1] as usize * w + p[0] as usize] != 0
    };
    let mut points = vec![start];
    // The start's west neighbour is background: the search begins there.
    let mut backtrack = 4usize;
    let mut current = start;
    let mut entered: Option<usize> = None;
    loop {
        let mut next = None;
        for k in 1..=8 {
            let d = (backtrack + k) % 8;
            let p = [current[0] + NEIGHBOURS[d][0], current[1] + NEIGHBOURS[d][1]];
            if dark(p) {
                next = Some((p, d));
                break;
            }
        }
        let Some((p, d)) = next else {
            // A single pixel.
            return Contour { points };
        };
        // The neighbour searched just before `p` is background; seen from `p` it lies in
        // direction (d + 5) or (d + 6) mod 8, and the next search starts after it.
        let previous = (d + 7) % 8;
        let background = [current[0] + NEIGHBOURS[previous][0], current[1] + NEIGHBOURS[previous][1]];
        backtrack = direction(p, background);
        if current == start {
            match entered {
                // Back at the start, leaving it the way it was first left: the boundary is closed.
                Some(first) if first == d => {
                    points.pop();
                    return Contour { points };
                }
                None => entered = Some(d),
                Some(_) => {}
            }
        }
        points.push(p);
        current = p;
        if points.len() > 4 * (w + h) * 4 {
            // Cannot happen for an outer boundary; a guard against an endless walk.
            return Contour { points };
        }
    }
}

/// The index in [`NEIGHBOURS`] of `to` seen from `from` (adjacent pixels).
fn direction(from: [i32; 2], to: [i32; 2]) -> usize {
    let delta = [to[0] - from[0], to[1] - from[1]];
    NEIGHBOURS.iter().position(|&n| n == delta).unwrap_or(4)
}

/// The closed polygon of `points` simplified so that no point lies further than `epsilon`
/// from it (Douglas–Peucker from the two points furthest apart).
pub fn simplify_closed(points: &[[i32; 2]], epsilon: f32) -> Vec<Vec2> {
    let p: Vec<Vec2> = points.iter().map(|&[x, y]| Vec2::new(x as f32, y as f32)).collect();
    if p.len() < 3 {
        return p;
    }
    // The point furthest from the first, then the one furthest from that: a diameter.
    let far = |from: Vec2| {
        (0..p.len()).max_by(|&a, &b| p[a].distance_squared(from).total_cmp(&p[b].distance_squared(from))).unwrap_or(0)
    };
    let a = far(p[0]);
    let b = far(p[a]);
    let (a, b) = (a.min(b), a.max(b));
    if a == b {
        return vec![p[a]];
    }
    let mut keep = vec![false; p.len()];
    keep[a] = true;
    keep[b] = true;
    let forward: Vec<usize> = (a..=b).collect();
    let around: Vec<usize> = (b..p.len()).chain(0..=a).collect();
    for chain in [forward, around] {
        simplify_chain(&p, &chain, epsilon, &mut keep);
    }
    (0..p.len()).filter(|&i| keep[i]).map(|i| p[i]).collect()
}

fn simplify_chain(p: &[Vec2], chain: &[usize], epsilon: f32, keep: &mut [bool]) {
    let mut stack = vec![(0usize, chain.len() - 1)];
    while let Some((first, last)) = stack.pop() {
        if last <= first + 1 {
            continue;
        }
        let (a, b) = (p[chain[first]], p[chain[last]]);
        let along = b - a;
        let length = along.length();
        let distance = |q: Vec2| if length > 0.0 { along.perp_dot(q - a).abs() / length } else { q.distance(a) };
        let (index, worst) = (first + 1..last)
            .map(|k| (k, distance(p[chain[k]])))
            .max_by(|x, y| x.1.total_cmp(&y.1))
            .unwrap_or((first, 0.0));
        if worst > epsilon {
            keep[chain[index]] = true;
            stack.push((first, index));
            stack.push((index, last));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask_of(rows: &[&str]) -> (Vec<u8>, u32, u32) {
        let mask = rows.iter().flat_map(|r| r.bytes().map(|b| u8::from(b == b'#'))).collect();
        (mask, rows[0].len() as u32, rows.len() as u32)
    }

    #[test]
    fn the_outer_boundary_of_a_ring_goes_round_once_clockwise() {
        let (mask, w, h) = mask_of(&["......", ".####.", ".#..#.", ".####.", "......"]);
        let contours = outer_contours(&mask, w, h, 1, 100, &mut Vec::new());
        assert_eq!(contours.len(), 1);
        let points = &contours[0].points;
        assert_eq!(points.len(), 10, "{points:?}");
        assert_eq!(points[0], [1, 1]);
        assert_eq!(points[1], [2, 1], "clockwise on the image: east first");
        // Every step goes to a neighbour and no pixel repeats.
        for (a, b) in points.iter().zip(points.iter().cycle().skip(1)) {
            assert!((a[0] - b[0]).abs() <= 1 && (a[1] - b[1]).abs() <= 1);
        }
        let mut unique = points.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), points.len());
    }

    #[test]
    fn regions_touching_diagonally_are_one_and_sizes_are_filtered() {
        let (mask, w, h) = mask_of(&["#.....", ".#....", "....##", "....##"]);
        let all = outer_contours(&mask, w, h, 1, 100, &mut Vec::new());
        assert_eq!(all.len(), 2);
        assert_eq!(all[0].points, vec![[0, 0], [1, 1]]);
        assert_eq!(outer_contours(&mask, w, h, 3, 100, &mut Vec::new()).len(), 0);
    }

    #[test]
    fn a_thin_spur_is_walked_out_and_back() {
        let (mask, w, h) = mask_of(&["####", "#...", "#...", "#..."]);
        let points = &outer_contours(&mask, w, h, 1, 100, &mut Vec::new())[0].points;
        // Out along the top and back, down the side and back: the spur's pixels twice.
        assert_eq!(points.len(), 11, "{points:?}");
    }

    #[test]
    fn the_threshold_equals_the_window_mean_rule_everywhere() {
        let mut gray = Gray::filled(23, 17, 0);
        for (i, p) in gray.pixels.iter_mut().enumerate() {
            *p = ((i * 7919) % 251) as u8;
        }
        let integral = Integral::new(&gray);
        let mut mask = Vec::new();
        for window in [3, 5, 13, 31] {
            integral.threshold(&gray, window, 7.0, &mut mask);
            let half = (window / 2) as i32;
            for y in 0..17i32 {
                for x in 0..23i32 {
                    let (mut sum, mut area) = (0.0, 0.0);
                    for v in (y - half).max(0)..=(y + half).min(16) {
                        for u in (x - half).max(0)..=(x + half).min(22) {
                            sum += f32::from(gray.at(u as u32, v as u32));
                            area += 1.0;
                        }
                    }
                    let expected = u8::from(f32::from(gray.at(x as u32, y as u32)) <= sum / area - 7.0);
                    assert_eq!(mask[(y * 23 + x) as usize], expected, "window {window} at ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn threshold_marks_what_is_darker_than_its_surroundings() {
        let mut gray = Gray::filled(9, 9, 200);
        gray.pixels[4 * 9 + 4] = 20;
        let mut mask = Vec::new();
        Integral::new(&gray).threshold(&gray, 3, 7.0, &mut mask);
        assert_eq!(mask.iter().map(|&m| u32::from(m)).sum::<u32>(), 1);
        assert_eq!(mask[4 * 9 + 4], 1);
    }

    #[test]
    fn a_square_outline_simplifies_to_its_corners() {
        let mut points = Vec::new();
        for x in 0..20 {
            points.push([x, 0]);
        }
        for y in 0..20 {
            points.push([20, y]);
        }
        for x in (1..=20).rev() {
            points.push([x, 20]);
        }
        for y in (1..=20).rev() {
            points.push([0, y]);
        }
        let polygon = simplify_closed(&points, 1.0);
        assert_eq!(polygon.len(), 4, "{polygon:?}");
        for corner in [[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [0.0, 20.0]] {
            assert!(polygon.contains(&Vec2::from(corner)), "{polygon:?}");
        }
    }
}
