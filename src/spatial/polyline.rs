//! Polylines with a radius at each point (supports, tubes): simplified within a tolerance.

use bevy::math::Vec3;

/// Distinct points along a polyline (consecutive ones closer than a tenth of a millimetre
/// merged), less those within `tolerance` metres of the line between the points kept on
/// either side (Douglas-Peucker), each with its radius.
pub fn simplified(points: &[Vec3], radii: &[f32], tolerance: f32) -> (Vec<Vec3>, Vec<f32>) {
    let mut distinct: Vec<usize> = vec![0];
    for i in 1..points.len() {
        if points[i].distance(points[*distinct.last().expect("starts with the first")]) > 1e-4 {
            distinct.push(i);
        }
    }
    if distinct.len() < 2 {
        // A support shorter than the merging distance keeps its two ends.
        distinct = vec![0, points.len() - 1];
    }
    if tolerance <= 0.0 {
        return distinct.iter().map(|&i| (points[i], radii[i])).unzip();
    }
    let mut keep = vec![false; distinct.len()];
    keep[0] = true;
    keep[distinct.len() - 1] = true;
    let mut spans = vec![(0, distinct.len() - 1)];
    while let Some((a, b)) = spans.pop() {
        let (pa, pb) = (points[distinct[a]], points[distinct[b]]);
        let farthest = (a + 1..b)
            .map(|k| {
                let p = points[distinct[k]];
                let ab = pb - pa;
                let t = ((p - pa).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
                (k, p.distance(pa + ab * t))
            })
            .max_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((k, distance)) = farthest
            && distance > tolerance
        {
            keep[k] = true;
            spans.push((a, k));
            spans.push((k, b));
        }
    }
    distinct.iter().zip(&keep).filter(|(_, kept)| **kept).map(|(&i, _)| (points[i], radii[i])).unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearly_straight_runs_simplify_within_the_tolerance() {
        let points: Vec<Vec3> = (0..=10).map(|i| Vec3::new(i as f32 * 0.1, 0.001 * (i % 2) as f32, 0.0)).collect();
        let radii: Vec<f32> = (0..=10).map(|i| 0.1 - i as f32 * 0.005).collect();
        let (kept, kept_radii) = simplified(&points, &radii, 0.002);
        assert_eq!(kept, [points[0], points[10]]);
        assert_eq!(kept_radii, [radii[0], radii[10]]);
        let (all, _) = simplified(&points, &radii, 0.0005);
        assert_eq!(all.len(), 11);
        // Without a tolerance even collinear joints stay.
        let straight: Vec<Vec3> = (0..=4).map(|i| Vec3::X * i as f32).collect();
        assert_eq!(simplified(&straight, &radii[..5], 0.0).0, straight);
    }
}
