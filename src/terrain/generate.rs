//! Heightmap generators: fBm Perlin noise, diamond-square and the hill algorithm, and a
//! [`Recipe`]'s heights made from them, as a whole map or at any grid of world samples.

use super::heightmap::{Heightmap, SizeError, check_size};
use super::noise::{Fbm, FbmSettings};
use super::recipe::{DiamondSquareLayer, Generator, HillCentres, HillsLayer, Layer, PerlinLayer, Recipe};
use crate::foundation::random::Random;

impl Recipe {
    /// The heights of this recipe (checked, and unbounded by [`Recipe::check_unbounded`]) with
    /// `seed` at the world samples `(x0 + i * step, z0 + j * step)` for `i < width`,
    /// `j < depth`, row by row. A sample's height depends on its position alone: grids that
    /// share a sample give it bit for bit.
    pub fn sample_grid(&self, seed: u64, origin: [i32; 2], step: i32, size: [usize; 2]) -> Vec<f32> {
        self.sample_grid_with(&self.noises(seed), origin, step, size)
    }

    /// Each layer's fractal sum for `seed` (none for a layer without Perlin noise): what
    /// [`sample_grid_with`](Self::sample_grid_with) samples, made once for many small grids
    /// (making them costs far more than sampling a few points).
    pub fn noises(&self, seed: u64) -> Vec<Option<Fbm>> {
        let noise =
            |(index, layer): (usize, &Layer)| layer.perlin.map(|p| Fbm::new(fbm_settings(p, layer_seed(seed, index))));
        self.layers.iter().enumerate().map(noise).collect()
    }

    /// [`sample_grid`](Self::sample_grid) with the layers' `noises` made already.
    pub fn sample_grid_with(
        &self,
        noises: &[Option<Fbm>],
        [x0, z0]: [i32; 2],
        step: i32,
        [width, depth]: [usize; 2],
    ) -> Vec<f32> {
        let step = step.max(1);
        let mut grid = vec![0.0; width * depth];
        let mut layer_heights = vec![0.0; width * depth];
        for ((index, layer), fbm) in self.layers.iter().enumerate().zip(noises) {
            let Some(fbm) = fbm else { continue };
            for (j, row) in layer_heights.chunks_exact_mut(width.max(1)).enumerate() {
                fbm.fill_row_every(x0, step, z0 + j as i32 * step, row);
            }
            for (sum, &h) in grid.iter_mut().zip(&layer_heights) {
                let h = layer.apply.iter().fold(h, |h, f| f.of_height(h).unwrap_or(h)) * layer.weight;
                *sum = if index == 0 { h } else { layer.op.apply(*sum, h) };
            }
        }
        for h in &mut grid {
            *h = self.apply.iter().fold(*h, |h, f| f.of_height(h).unwrap_or(h));
        }
        grid
    }

    /// The map of this (checked) recipe with `seed`.
    pub fn generate(&self, seed: u64) -> Result<Heightmap, SizeError> {
        let [width, height] = self.size;
        let mut map: Option<Heightmap> = None;
        for (index, layer) in self.layers.iter().enumerate() {
            let layer_seed = layer_seed(seed, index);
            let mut heights = match layer.generator() {
                Ok(Generator::Perlin(p)) => perlin(p, layer_seed, width, height)?,
                Ok(Generator::DiamondSquare(d)) => diamond_square(d, layer_seed, width, height)?,
                Ok(Generator::Hills(h)) => hills(h, layer_seed, width, height)?,
                Err(_) => Heightmap::filled(width, height, 0.0)?,
            };
            layer.apply.iter().for_each(|f| f.apply(&mut heights));
            if layer.weight != 1.0 {
                let weight = layer.weight;
                heights.apply(|h| h * weight);
            }
            match &mut map {
                None => map = Some(heights),
                Some(map) => map.combine(&heights, |a, b| layer.op.apply(a, b))?,
            }
        }
        let mut map = match map {
            Some(map) => map,
            None => Heightmap::filled(width, height, 0.0)?,
        };
        self.apply.iter().for_each(|f| f.apply(&mut map));
        Ok(map)
    }
}

/// The seed of layer `index` of a recipe with `seed`: layers draw from streams far apart, so
/// that no two share an octave's tables.
fn layer_seed(seed: u64, index: usize) -> u64 {
    seed.wrapping_add((index as u64).wrapping_mul(0x1_0000))
}

/// The fractal sum of a Perlin layer with `seed`.
fn fbm_settings(layer: PerlinLayer, seed: u64) -> FbmSettings {
    FbmSettings {
        seed,
        scale: layer.scale,
        octaves: layer.octaves,
        lacunarity: layer.lacunarity,
        persistence: layer.persistence,
    }
}

/// Fractal Perlin noise of `width x height` samples, in `[0, 1]`.
pub fn perlin(layer: PerlinLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    let fbm = Fbm::new(fbm_settings(layer, seed));
    let mut map = Heightmap::filled(width, height, 0.0)?;
    for (z, row) in map.values_mut().chunks_exact_mut(width as usize).enumerate() {
        fbm.fill_row(0, z as i32, row);
    }
    Ok(map)
}

/// Diamond-square of `width x height` samples, normalised to `[0, 1]`.
pub fn diamond_square(layer: DiamondSquareLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    check_size(width, height)?;
    let side = (width.max(height) - 1).max(1).next_power_of_two() as usize + 1;
    let mut random = Random::new(seed);
    let mut grid = vec![0.0f32; side * side];
    let last = side - 1;
    for (x, z) in [(0, 0), (last, 0), (0, last), (last, last)] {
        grid[z * side + x] = random.between(-1.0, 1.0);
    }
    let mut amplitude = 1.0;
    let mut step = last;
    while step > 1 {
        let half = step / 2;
        // Diamond: the centre of each square from its four corners.
        for z in (half..side).step_by(step) {
            for x in (half..side).step_by(step) {
                let corners = grid[(z - half) * side + x - half]
                    + grid[(z - half) * side + x + half]
                    + grid[(z + half) * side + x - half]
                    + grid[(z + half) * side + x + half];
                grid[z * side + x] = corners / 4.0 + random.between(-amplitude, amplitude);
            }
        }
        // Square: the midpoint of each edge from its (three or four) neighbours.
        for z in (0..side).step_by(half) {
            let first = if (z / half).is_multiple_of(2) { half } else { 0 };
            for x in (first..side).step_by(step) {
                let neighbours = [
                    (x >= half).then(|| grid[z * side + x - half]),
                    (x + half < side).then(|| grid[z * side + x + half]),
                    (z >= half).then(|| grid[(z - half) * side + x]),
                    (z + half < side).then(|| grid[(z + half) * side + x]),
                ];
                let (sum, count) = neighbours.iter().flatten().fold((0.0, 0.0), |(s, c), v| (s + v, c + 1.0));
                grid[z * side + x] = sum / count + random.between(-amplitude, amplitude);
            }
        }
        amplitude *= layer.roughness;
        step = half;
    }
    let mut map = Heightmap::from_fn(width, height, |x, z| grid[z as usize * side + x as usize])?;
    map.normalize();
    Ok(map)
}

/// The hill algorithm on `width x height` samples: summed paraboloids, normalised, squared;
/// their centres inside the map, beyond its edges too, or kept to an island, and dug down as
/// lakes instead of raised if the layer says.
pub fn hills(layer: HillsLayer, seed: u64, width: u32, height: u32) -> Result<Heightmap, SizeError> {
    let mut map = Heightmap::filled(width, height, 0.0)?;
    let mut random = Random::new(seed);
    let [low, high] = layer.radius;
    let (w, h) = (width as f32, height as f32);
    for _ in 0..layer.count {
        let (cx, cz, radius) = match layer.centres {
            HillCentres::Inside => {
                let (cx, cz) = (random.between(0.0, w), random.between(0.0, h));
                (cx, cz, random.between(low, high.max(low)))
            }
            HillCentres::BeyondEdges => {
                let (cx, cz) = (random.between(-high, w + high), random.between(-high, h + high));
                (cx, cz, random.between(low, high.max(low)))
            }
            HillCentres::Island => {
                // The disc of the hill within the circle inscribed in the map's samples.
                let radius = random.between(low, high.max(low));
                let room = ((w.min(h) - 1.0) * 0.5 - radius).max(0.0);
                let (angle, distance) = (random.between(0.0, std::f32::consts::TAU), random.between(0.0, room));
                ((w - 1.0) * 0.5 + distance * angle.cos(), (h - 1.0) * 0.5 + distance * angle.sin(), radius)
            }
        };
        let r2 = radius * radius;
        let span = |c: f32, size: u32| {
            let first = (c - radius).floor().max(0.0) as u32;
            let last = ((c + radius).ceil() as u32).min(size - 1);
            first..=last
        };
        for z in span(cz, height) {
            let dz = z as f32 - cz;
            let row = z as usize * width as usize;
            for x in span(cx, width) {
                let dx = x as f32 - cx;
                let raise = r2 - (dx * dx + dz * dz);
                if raise > 0.0 {
                    map.values_mut()[row + x as usize] += raise;
                }
            }
        }
    }
    map.normalize();
    if layer.lakes {
        // Dug down from a plateau, then squared: the lakes' beds flatten as the valleys do.
        map.apply(|h| (1.0 - h) * (1.0 - h));
    } else {
        map.apply(|h| h * h);
    }
    Ok(map)
}

#[cfg(test)]
mod tests;
