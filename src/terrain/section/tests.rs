use super::*;
use crate::terrain::bands::BandBlend;
use std::collections::HashMap;

fn geometry() -> Geometry {
    Geometry { cell_m: 0.5, height_m: 4.0, texture_cells: 8.0 }
}

fn bumpy(width: u32, height: u32) -> Heightmap {
    Heightmap::from_fn(width, height, |x, z| ((x as f32 * 0.3).sin() * (z as f32 * 0.2).cos() + 1.0) * 0.5).unwrap()
}

/// Every position of every band mesh, in metres from the section's first vertex, with its
/// normal.
fn vertices(mesh: &SectionMesh) -> Vec<(Vec3, Vec3)> {
    mesh.bands
        .iter()
        .flat_map(|m| m.positions.iter().zip(&m.normals).map(|(p, n)| (*p + mesh.barycentre, *n)))
        .collect()
}

#[test]
fn two_triangles_a_cell_and_the_surface_is_closed() {
    let map = bumpy(20, 16);
    let section = Section { origin: [3, 2], size: [9, 7] };
    let mesh = mesh_section(&map, section, geometry(), &BandRule::default());
    assert_eq!(mesh.counts.iter().sum::<usize>(), 2 * 8 * 6);
    // Every interior edge is shared by exactly two triangles (across bands, by position),
    // every border edge by one: the surface has no holes and no overlaps.
    let mut edges: HashMap<[[u32; 3]; 2], usize> = HashMap::new();
    let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    for band in &mesh.bands {
        for t in &band.triangles {
            for k in 0..3 {
                let (a, b) = (key(band.positions[t[k] as usize]), key(band.positions[t[(k + 1) % 3] as usize]));
                *edges.entry(if a < b { [a, b] } else { [b, a] }).or_default() += 1;
            }
        }
    }
    let border = 2 * (8 + 6);
    assert_eq!(edges.values().filter(|&&n| n == 1).count(), border);
    assert!(edges.values().all(|&n| n == 1 || n == 2));
    // Front faces point up.
    for band in &mesh.bands {
        for t in &band.triangles {
            let [a, b, c] = t.map(|i| band.positions[i as usize]);
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }
}

/// The mix of bands each triangle shows at each of its corners, keyed by the corner's
/// position: one band alone, or a border's two by the corner's blend weight.
fn corner_mixes(mesh: &SectionMesh) -> HashMap<[u32; 3], Vec<[f32; 5]>> {
    let mut mixes: HashMap<[u32; 3], Vec<[f32; 5]>> = HashMap::new();
    let key = |p: Vec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let surfaces = mesh.bands.iter().enumerate().map(|(b, m)| (m, Some(b), None));
    let borders = mesh.borders.iter().zip(BORDERS).map(|(m, pair)| (m, None, Some(pair)));
    for (part, band, border) in surfaces.chain(borders) {
        for &index in part.triangles.iter().flatten() {
            let mut mix = [0.0; 5];
            match (band, border) {
                (Some(band), _) => mix[band] = 1.0,
                (_, Some((lower, upper))) => {
                    let upper_share = part.blend[index as usize];
                    mix[lower.index()] = 1.0 - upper_share;
                    mix[upper.index()] = upper_share;
                }
                _ => unreachable!(),
            }
            mixes.entry(key(part.positions[index as usize])).or_default().push(mix);
        }
    }
    mixes
}

/// The share of vertices where the triangles around show different mixes of bands.
fn seams(mesh: &SectionMesh) -> f64 {
    let mixes = corner_mixes(mesh);
    let differ = |a: &[f32; 5], b: &[f32; 5]| a.iter().zip(b).any(|(x, y)| (x - y).abs() > 1e-4);
    let seams = mixes.values().filter(|m| m.iter().any(|mix| differ(mix, &m[0]))).count();
    seams as f64 / mixes.len() as f64
}

#[test]
fn blended_bands_meet_without_a_seam() {
    // Heights across every threshold, and slopes across the rock slope.
    let map = Heightmap::from_fn(48, 48, |x, z| {
        (x as f32 / 47.0 * 0.9 + 0.05 + 0.03 * (z as f32 * 0.7).sin()).clamp(0.0, 1.0)
    })
    .unwrap();
    let section = Section { origin: [0, 0], size: [48, 48] };
    let hard = BandRule { rock_slope_deg: Some(30.0), ..BandRule::default() };
    let blended = BandRule { blend: Some(BandBlend { height: 0.02, slope_deg: 5.0 }), ..hard };
    let (hard_mesh, mesh) =
        (mesh_section(&map, section, geometry(), &hard), mesh_section(&map, section, geometry(), &blended));
    // Every triangle is drawn once, in a band or a border, and counted by the rule alike.
    let drawn: usize = mesh.bands.iter().chain(&mesh.borders).map(|m| m.triangles.len()).sum();
    assert_eq!(drawn, 2 * 47 * 47);
    assert_eq!(mesh.counts, hard_mesh.counts);
    assert!(mesh.borders.iter().filter(|m| !m.triangles.is_empty()).count() >= 4, "borders used");
    assert!(mesh.borders.iter().all(|m| m.blend.len() == m.positions.len()));
    assert!(mesh.borders.iter().flat_map(|m| &m.blend).all(|b| (0.0..=1.0).contains(b)));
    // Hard bands change along triangle edges; blended ones agree at every shared vertex
    // but a few where three bands meet.
    let (hard_seams, blended_seams) = (seams(&hard_mesh), seams(&mesh));
    assert!(hard_seams > 0.05, "hard bands: {hard_seams}");
    assert!(blended_seams < 0.01, "blended: {blended_seams}");
}

#[test]
fn normals_are_unit_point_up_and_match_a_flat_or_sloped_plane() {
    let slope = Heightmap::from_fn(10, 10, |x, _| x as f32 * 0.1).unwrap();
    let mesh = mesh_section(&slope, Section { origin: [0, 0], size: [10, 10] }, geometry(), &BandRule::default());
    // Height rises 0.4 m per 0.5 m along x: the normal is (-0.4, 0.5, 0) normalised.
    let expected = Vec3::new(-0.4, 0.5, 0.0).normalize();
    for (_, normal) in vertices(&mesh) {
        assert!(normal.distance(expected) < 1e-5, "{normal}");
    }
}

#[test]
fn a_moved_section_keeps_the_normals_where_it_overlaps() {
    let map = bumpy(40, 30);
    let rule = BandRule::default();
    // A spacing that is no power of two: positions are not exact, normals still are.
    let geometry = Geometry { cell_m: 0.3, ..geometry() };
    let at = |origin: [u32; 2]| {
        let mesh = mesh_section(&map, Section { origin, size: [12, 10] }, geometry, &rule);
        let sample = |p: Vec3| {
            let [x, z] = [p.x, p.z].map(|v| (v / geometry.cell_m).round() as u32);
            [origin[0] + x, origin[1] + z]
        };
        vertices(&mesh).into_iter().map(|(p, n)| (sample(p), n)).collect::<HashMap<_, _>>()
    };
    let (first, moved) = (at([5, 5]), at([15, 8]));
    let shared: Vec<_> = first.iter().filter_map(|(p, n)| moved.get(p).map(|m| (n, m))).collect();
    assert!(shared.len() >= 10, "the sections overlap");
    for (a, b) in shared {
        assert_eq!(a, b, "the same normal bit for bit");
    }
}

#[test]
fn moves_stop_at_the_edges_and_sizes_fit() {
    let map = bumpy(64, 48);
    let section = Section { origin: [10, 10], size: [32, 32] };
    assert_eq!(section.moved(10, 0, &map).origin, [20, 10]);
    assert_eq!(section.moved(100, 100, &map).origin, [32, 16]);
    assert_eq!(section.moved(-100, 0, &map).origin, [0, 10]);
    assert_eq!(Section { origin: [0, 0], size: [65, 2] }.check(&map), Err(SectionError::TooLarge(65, 2, 64, 48)));
    assert_eq!(Section { origin: [0, 0], size: [1, 2] }.check(&map), Err(SectionError::TooSmall(1, 2)));
    assert_eq!(Section { origin: [60, 0], size: [8, 8] }.clamped(&map).origin, [56, 0]);
}

#[test]
fn triangles_fall_into_bands_by_height() {
    // Heights rising along x by 0.01 a sample: the triangles of cell x have mean heights
    // (3x + 1) / 300 and (3x + 2) / 300, none at a threshold; two rows of cells.
    let map = Heightmap::from_fn(101, 3, |x, _| x as f32 / 100.0).unwrap();
    let rule = BandRule::default();
    let mesh = mesh_section(&map, Section { origin: [0, 0], size: [101, 3] }, geometry(), &rule);
    let mut expected = [0; 5];
    for x in 0..100 {
        for t in 1..=2 {
            expected[rule.band((3 * x + t) as f32 / 300.0, 1.0).index()] += 2;
        }
    }
    assert_eq!(mesh.counts, expected);
    assert!(expected.iter().all(|&c| c > 0), "{expected:?}");
    for (band, band_mesh) in Band::ALL.iter().zip(&mesh.bands) {
        assert_eq!(band_mesh.triangles.len(), mesh.counts[band.index()]);
        for t in &band_mesh.triangles {
            let mean = t.iter().map(|&i| (band_mesh.positions[i as usize] + mesh.barycentre).y).sum::<f32>() / 3.0;
            assert_eq!(rule.band(mean / geometry().height_m, 1.0), *band, "mean height {mean}");
        }
    }
}
