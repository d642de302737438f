use super::*;
use crate::terrain::recipe::Function;

fn recipe(yaml: &str) -> Recipe {
    serde_yaml::from_str(yaml).unwrap()
}

#[test]
fn the_same_seed_makes_the_same_map() {
    for layer in ["{perlin: {scale: 16, octaves: 4}}", "{diamond_square: {roughness: 0.6}}", "{hills: {count: 30}}"] {
        let r = recipe(&format!("{{size: [65, 40], seed: 3, layers: [{layer}]}}"));
        r.check().unwrap();
        let (a, b, c) = (r.generate(3).unwrap(), r.generate(3).unwrap(), r.generate(4).unwrap());
        assert_eq!(a.checksum(), b.checksum(), "{layer}");
        assert_ne!(a.checksum(), c.checksum(), "{layer}");
        let stats = a.stats();
        assert!(stats.min >= 0.0 && stats.max <= 1.0 && stats.max > stats.min, "{layer}: {stats:?}");
    }
}

#[test]
fn layers_combine_by_their_ops_weights_and_functions() {
    let base = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}]}");
    let single = base.generate(1).unwrap();
    let doubled = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}, weight: 2}]}").generate(1).unwrap();
    for (a, b) in single.values().iter().zip(doubled.values()) {
        assert_eq!(a * 2.0, *b);
    }
    let squared = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}], apply: [{power: 2}, {offset: 1}]}")
        .generate(1)
        .unwrap();
    for (a, b) in single.values().iter().zip(squared.values()) {
        assert_eq!(a.powf(2.0) + 1.0, *b);
    }
    // A second layer equal to the first (same seed stream offset aside) subtracted: the
    // first layer minus another map.
    let two = recipe("{size: [32, 32], seed: 1, layers: [{perlin: {scale: 8}}, {hills: {count: 5}, op: max}]}");
    two.check().unwrap();
    let hills_alone =
        hills(HillsLayer { count: 5, radius: [4.0, 32.0], ..hills_layer() }, 1 + 0x1_0000, 32, 32).unwrap();
    let combined = two.generate(1).unwrap();
    for ((a, b), c) in single.values().iter().zip(hills_alone.values()).zip(combined.values()) {
        assert_eq!(a.max(*b), *c);
    }
}

#[test]
fn functions_give_hand_computed_values() {
    let mut map = Heightmap::from_values(4, 1, vec![-0.5, 0.0, 0.3, 1.0]).unwrap();
    Function::Clamp([0.0, 0.5]).apply(&mut map);
    assert_eq!(map.values(), &[0.0, 0.0, 0.3, 0.5]);
    Function::Terraces(2).apply(&mut map);
    // 0.3 * 2 = 0.6: floor 0, fraction 0.6, 0.6^4 / 2 = 0.0648; 0.5 * 2 = 1: one step up.
    assert!((map.values()[2] - 0.0648).abs() < 1e-6);
    assert_eq!(map.values()[3], 0.5);
    Function::Invert.apply(&mut map);
    assert_eq!(map.values()[0], 1.0);
    Function::Scale(-2.0).apply(&mut map);
    Function::Abs.apply(&mut map);
    assert_eq!(map.values()[0], 2.0);
}

#[test]
fn hills_are_paraboloids() {
    // One hill: the normalised, squared paraboloid peaks at 1 at its centre and is zero
    // beyond its radius.
    let map = hills(HillsLayer { count: 1, radius: [5.0, 5.0], ..hills_layer() }, 9, 64, 64).unwrap();
    let stats = map.stats();
    assert_eq!((stats.min, stats.max), (0.0, 1.0));
    let raised = map.values().iter().filter(|&&h| h > 0.0).count() as f32;
    // The disc of radius 5 holds about 78.5 samples (fewer when cut by the border).
    assert!(raised <= 90.0 && raised > 20.0, "{raised}");
}

/// Hills inside the map, raised.
fn hills_layer() -> HillsLayer {
    HillsLayer { count: 200, radius: [4.0, 32.0], centres: HillCentres::Inside, lakes: false }
}

#[test]
fn islands_leave_the_edges_at_zero_and_hills_beyond_the_edges_raise_them() {
    let (w, h) = (48, 40);
    let island =
        hills(HillsLayer { count: 60, radius: [3.0, 12.0], centres: HillCentres::Island, ..hills_layer() }, 5, w, h)
            .unwrap();
    let border = |map: &Heightmap| -> Vec<f32> {
        let (w, h) = (map.width(), map.height());
        (0..w)
            .flat_map(|x| [(x, 0), (x, h - 1)])
            .chain((0..h).flat_map(|z| [(0, z), (w - 1, z)]))
            .map(|(x, z)| map.values()[(z * w + x) as usize])
            .collect()
    };
    assert!(border(&island).iter().all(|&v| v == 0.0), "an island's shore is at sea level");
    assert_eq!(island.stats().max, 1.0);
    // One hill a map: beyond the edges, its highest point is on the edge in some maps; inside,
    // where its centre is, a sample's width from the edge at most.
    let on_edge = |centres: HillCentres| {
        (0..40u64)
            .filter(|&seed| {
                let map =
                    hills(HillsLayer { count: 1, radius: [6.0, 6.0], centres, ..hills_layer() }, seed, 32, 32).unwrap();
                let peak = map.values().iter().position(|&v| v == 1.0).unwrap_or(0) as u32;
                let (x, z) = (peak % 32, peak / 32);
                x == 0 || z == 0 || x == 31 || z == 31
            })
            .count()
    };
    let (beyond, inside) = (on_edge(HillCentres::BeyondEdges), on_edge(HillCentres::Inside));
    assert!(beyond >= 10 && beyond > 3 * inside, "{beyond} maps peak on the edge beyond, {inside} inside");
    // Many hills: the edges as high as the rest beyond, lower inside (cut-off hills).
    let edge_share = |centres| {
        let map = hills(HillsLayer { centres, ..hills_layer() }, 3, 64, 64).unwrap();
        let edge = border(&map).iter().sum::<f32>() / border(&map).len() as f32;
        edge / (map.values().iter().sum::<f32>() / map.values().len() as f32)
    };
    let (beyond, inside) = (edge_share(HillCentres::BeyondEdges), edge_share(HillCentres::Inside));
    assert!(beyond > 0.6 && beyond > inside * 1.5, "edges {beyond} of the mean beyond, {inside} inside");
}

#[test]
fn lakes_are_the_same_hills_dug_down() {
    // The same seed draws the same hills: raised, `s^2`; dug down, `(1 - s)^2`.
    let raised = hills(hills_layer(), 11, 40, 40).unwrap();
    let lakes = hills(HillsLayer { lakes: true, ..hills_layer() }, 11, 40, 40).unwrap();
    for (a, b) in raised.values().iter().zip(lakes.values()) {
        assert!((a.sqrt() + b.sqrt() - 1.0).abs() < 1e-5, "{a} and {b}");
    }
    assert_eq!(lakes.stats().max, 1.0, "the plateau");
    // And the same every time.
    assert_eq!(lakes, hills(HillsLayer { lakes: true, ..hills_layer() }, 11, 40, 40).unwrap());
}

#[test]
fn mistakes_name_their_field() {
    let cases = [
        ("{size: [0, 5], layers: [{perlin: {}}]}", "size"),
        ("{size: [5000, 5], layers: [{perlin: {}}]}", "size"),
        ("{size: [5, 5], seed: -2, layers: [{perlin: {}}]}", "seed"),
        ("{size: [5, 5], layers: []}", "layers"),
        ("{size: [5, 5], layers: [{weight: 2}]}", "layers[0]"),
        ("{size: [5, 5], layers: [{perlin: {}, hills: {}}]}", "layers[0]"),
        ("{size: [5, 5], layers: [{perlin: {octaves: 40}}]}", "layers[0].perlin"),
        ("{size: [5, 5], layers: [{perlin: {scale: .nan}}]}", "layers[0].perlin"),
        ("{size: [5, 5], layers: [{perlin: {}}, {diamond_square: {roughness: 2}}]}", "layers[1].diamond_square"),
        ("{size: [5, 5], layers: [{hills: {radius: [3, 1]}}]}", "layers[0].hills"),
        ("{size: [5, 5], layers: [{perlin: {}, op: multiply}]}", "layers[0].op"),
        ("{size: [5, 5], layers: [{perlin: {}, weight: .inf}]}", "layers[0].weight"),
        ("{size: [5, 5], layers: [{perlin: {}}], apply: [{power: -1}]}", "apply"),
        ("{size: [5, 5], layers: [{perlin: {}, apply: [{terraces: 0}]}]}", "layers[0].apply"),
    ];
    for (yaml, field) in cases {
        let error = recipe(yaml).check().unwrap_err();
        assert_eq!(error.field, field, "{yaml}: {error}");
    }
    let error = serde_yaml::from_str::<Recipe>("{size: [5, 5], layers: [{ridged: {}}]}").unwrap_err();
    assert!(error.to_string().contains("unknown field `ridged`"), "{error}");
}

/// A recipe of two Perlin layers, a weight, an operation and pointwise functions.
fn unbounded() -> Recipe {
    recipe(
        "{size: [40, 30], seed: 5, layers: [{perlin: {scale: 24, octaves: 4}}, \
         {perlin: {scale: 60, octaves: 2}, op: max, weight: 0.7, apply: [{power: 3}]}], apply: [{terraces: 4}]}",
    )
}

#[test]
fn an_unbounded_grid_is_the_map_and_grids_agree_where_they_meet() {
    let recipe = unbounded();
    recipe.check().unwrap();
    recipe.check_unbounded().unwrap();
    // At the map's own samples, the grid is the map, bit for bit.
    let map = recipe.generate(5).unwrap();
    let grid = recipe.sample_grid(5, [0, 0], 1, [40, 30]);
    assert!(grid.iter().zip(map.values()).all(|(a, b)| a.to_bits() == b.to_bits()));
    // A grid elsewhere (negative positions too) and a coarser one give the samples they
    // share with it bit for bit.
    let shifted = recipe.sample_grid(5, [-13, 7], 1, [40, 30]);
    let wide = recipe.sample_grid(5, [-13, -1], 1, [60, 40]);
    for (j, row) in shifted.chunks_exact(40).enumerate() {
        assert_eq!(row, &wide[(j + 8) * 60..(j + 8) * 60 + 40]);
    }
    let coarse = recipe.sample_grid(5, [-13, -1], 4, [15, 10]);
    for (j, row) in coarse.chunks_exact(15).enumerate() {
        for (i, h) in row.iter().enumerate() {
            assert_eq!(h.to_bits(), wide[j * 4 * 60 + i * 4].to_bits(), "({i}, {j})");
        }
    }
}

#[test]
fn only_heights_of_their_own_position_make_an_unbounded_world() {
    let refused = |yaml: &str| recipe(yaml).check_unbounded().unwrap_err();
    let hills = refused("{size: [8, 8], layers: [{perlin: {scale: 4}}, {hills: {count: 3}}]}");
    assert_eq!((hills.field.as_str(), hills.key), ("layers[1]", "hills"));
    let squares = refused("{size: [8, 8], layers: [{diamond_square: {roughness: 0.5}}]}");
    assert_eq!(squares.key, "diamond_square");
    let normalize = refused("{size: [8, 8], layers: [{perlin: {scale: 4}, apply: [{power: 2}]}], apply: [normalize]}");
    assert_eq!((normalize.field.as_str(), normalize.nth), ("apply", 1));
    assert!(normalize.message.contains("whole map"), "{}", normalize.message);
}

#[test]
fn recipes_save_as_they_were_written() {
    let text = "size: [8, 8]\nseed: 4\nlayers:\n- perlin: {scale: 4}\n  apply: [{power: 2}, normalize]\napply: [{terraces: 3}]\n";
    let read = recipe(text);
    let saved = serde_yaml::to_string(&read).unwrap();
    assert!(saved.contains("power: 2.0") && !saved.contains('!'), "{saved}");
    assert_eq!(recipe(&saved), read);
}
