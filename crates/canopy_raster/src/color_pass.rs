//! The colour bands: each band of tile rows sets up the triangles reaching it, in draw order,
//! and draws each into the band's tiles it touches.
//!
//! A triangle's walk over a tile finds its covered pixels row by row with its exact edge
//! functions, [`MASK_PIXELS`] pixels at a time. Pixels are then depth-tested, shaded and stored
//! in runs of [`LANES`] along a row, with lane masks instead of a branch per pixel.
//!
//! Each tile keeps a conservative farthest depth of what it holds; a triangle entirely behind
//! it is skipped before any of its pixels is visited.
//!
//! With shadows, pixels are drawn lit as if the light reached them all; once a band's
//! triangles are drawn, its visible pixels look the shadow map up, once each, and those the
//! light does not reach are darkened.

use crate::camera::{Camera, Light};
use crate::clip::outside;
use crate::coverage::{RowMasks, RunVisitor, Walk, covered};
use crate::frame::{Fog, Frame, Span, View, flat_diffuse};
use crate::framebuffer::{Band, FAR_DEPTH};
use crate::lanes::{BYTE_TO_UNIT, LANE_OFFSETS, LANES, bytes_of, lanes_of};
use crate::screen::{PixelBounds, ScreenVertex, TILE_HEIGHT, TILE_WIDTH, tile_rect};
use crate::setup::{DEPTH, INV_W, PACKS, Planes, Surface, TriangleSetup, packs_read};
use crate::shade::{
    CompiledPass, Material, Pass, Shading, VARYINGS, Varyings, affine_tolerances, slot, with_compiled_pass,
};
use crate::shadow::{PixelsInMap, ShadowMap, Taps};
use crate::sort::{Corners, Sorted};
use crate::texture::{Filter, Texture, UvDerivatives};
use bevy_math::{Vec3, Vec4};
use std::iter::Peekable;
use std::marker::PhantomData;
use wide::{f32x4, i16x8, i32x4, u8x16, u32x4};

/// A tile's farthest depth is read anew once this many pixels have been covered in it since the
/// last reading, times the tile's area: the reading then costs at most one depth read per
/// covered pixel.
const OCCLUSION_REFRESH: u64 = 1;

/// What the colour bands read, shared by every band.
pub(crate) struct TileContext<'a> {
    pub frame: &'a Frame<'a>,
    pub spans: &'a [Span],
    /// World positions, for clipping and flat shading.
    pub world: &'a [Vec3],
    pub varyings: &'a [Varyings],
    /// The camera's projection, its projected vertices and the target.
    pub view: View<'a>,
    /// The triangles reaching each band.
    pub sorted: &'a Sorted,
    /// The shadow map and how the bands' pixels find their place in it, when shadows are on.
    pub shadow: Option<BandShadow<'a>>,
}

/// A band's working buffers, kept between frames so that a frame of steady size does not
/// allocate.
#[derive(Debug, Default)]
pub(crate) struct BandScratch {
    /// The band's tiles, left to right.
    tiles: Vec<TileState>,
}

/// What drawing a band (or several) counted.
#[derive(Debug, Default)]
pub(crate) struct BandCounts {
    /// Pixels covered, counted once per triangle covering them.
    pub fragments: u64,
    /// Triangle-tile pairs skipped as occluded.
    pub occluded: u64,
    /// Triangles set up whose first row is in the band.
    pub triangles: usize,
}

impl BandCounts {
    /// Adds another band's counts.
    pub fn add(&mut self, other: Self) {
        self.fragments += other.fragments;
        self.occluded += other.occluded;
        self.triangles += other.triangles;
    }
}

/// A set-up triangle as a colour tile draws it.
struct Triangle<'a> {
    setup: &'a TriangleSetup,
    planes: &'a Planes,
    material: &'a Material,
}

/// Clears one band of the framebuffer and draws every triangle reaching it, in order: each is
/// set up, then drawn into the band's tiles it touches.
pub(crate) fn draw_band(context: &TileContext, row: u32, band: Band, scratch: &mut BandScratch) -> BandCounts {
    band.color.fill(context.frame.background);
    band.depth.fill(FAR_DEPTH);
    let (rows, width) = (band.rows, band.width);
    let mut target = band;
    scratch.tiles.clear();
    scratch
        .tiles
        .extend((0..width.div_ceil(TILE_WIDTH)).map(|tx| TileState::new(tile_rect(tx, target.y0, width, rows))));
    let mut masks = [0; TILE_HEIGHT as usize];
    let mut counts = BandCounts::default();
    let mut entries = context.sorted.strip(row as usize).peekable();
    let spans = context.spans;
    let mut instance = 0;
    // Runs of one instance's triangles, each drawn by the loop compiled for its pass.
    while let Some(first) = entries.peek() {
        // Instances' vertices follow one another in the global numbering.
        while instance + 1 < spans.len() && first[0] as usize >= spans[instance + 1].first_vertex {
            instance += 1;
        }
        let material = &context.frame.instances[instance].material;
        let pass = Pass {
            shading: context.frame.settings.shading,
            textured: material.texture.is_some(),
            shadowed: context.shadow.is_some(),
        };
        let draw = Draw { instance, material, context };
        counts.triangles +=
            with_compiled_pass!(pass, draw_instance(&mut entries, &draw, scratch, &mut masks, &mut target));
    }
    if let Some(shadow) = &context.shadow {
        // Compiled once per lookup kind, so that the loops do not test it per run.
        match shadow.filtered {
            true => light_band::<true>(&mut target, &scratch.tiles, shadow),
            false => light_band::<false>(&mut target, &scratch.tiles, shadow),
        }
    }
    if let Some(fog) = context.frame.settings.fog {
        let [r, g, b, _] = context.frame.background;
        fog_band(&mut target, fog, fog.color.unwrap_or([r, g, b]), &context.frame.camera);
    }
    for tile in &scratch.tiles {
        counts.fragments += tile.fragments;
        counts.occluded += tile.occluded;
    }
    counts
}

/// What drawing a tile keeps from one triangle to the next.
#[derive(Debug)]
struct TileState {
    rect: PixelBounds,
    /// Pixels in the rect.
    area: u64,
    /// A conservative farthest depth of what the rect holds.
    farthest: f32,
    /// Pixels covered since `farthest` was last read.
    covered_since_refresh: u64,
    fragments: u64,
    occluded: u64,
}

impl TileState {
    /// An empty tile covering `rect`.
    fn new(rect: PixelBounds) -> Self {
        let area = u64::from(rect.max_x - rect.min_x + 1) * u64::from(rect.max_y - rect.min_y + 1);
        Self { rect, area, farthest: FAR_DEPTH, covered_since_refresh: 0, fragments: 0, occluded: 0 }
    }
}

/// One instance, and what its triangles are drawn with.
struct Draw<'a> {
    instance: usize,
    material: &'a Material,
    context: &'a TileContext<'a>,
}

/// Draws the triangles of `entries` into `band` in order, for as long as they belong to
/// `draw`'s instance, with the setup and pixel loop compiled for its pass; returns how many
/// triangles were set up with their first row in the band.
fn draw_instance<'a, C: CompiledPass>(
    entries: &mut Peekable<impl Iterator<Item = &'a Corners>>,
    draw: &Draw,
    scratch: &mut BandScratch,
    masks: &mut RowMasks,
    band: &mut Band,
) -> usize {
    let context = draw.context;
    let (view, world) = (context.view, context.world);
    let next_instance = context.spans.get(draw.instance + 1).map_or(usize::MAX, |span| span.first_vertex);
    let pass = <C as CompiledPass>::PASS;
    let tolerance = affine_tolerances(pass, draw.material.texture.as_deref());
    let flat = pass.shading == Shading::Flat;
    let mut triangles = 0;
    while let Some(corners) = entries.next_if(|corners| (corners[0] as usize) < next_instance) {
        let indices = corners.map(|i| i as usize);
        let vertices = indices.map(|i| &view.vertices[i]);
        let flat_diffuse = if flat { flat_diffuse(indices.map(|i| world[i]), &context.frame.light) } else { 0.0 };
        let surface = Surface { tolerance: &tolerance, flat_diffuse };
        let varyings = |i: usize| &context.varyings[i];
        if (vertices[0].code | vertices[1].code | vertices[2].code) & outside::CLIPPED == 0 {
            triangles += draw_triangle::<C>(vertices, indices.map(varyings), surface, draw, scratch, masks, band);
        } else {
            view.clip(world, indices, varyings, |vertices, varyings| {
                triangles += draw_triangle::<C>(vertices, varyings, surface, draw, scratch, masks, band);
            });
        }
    }
    triangles
}

/// Sets a triangle up and draws it into the tiles of `band` it touches, skipping those whose
/// farthest depth is nearer than all of it; returns 1 when it was set up and its first row is
/// in the band (so that each triangle is counted once), 0 otherwise.
#[inline(always)]
fn draw_triangle<C: CompiledPass>(
    vertices: [&ScreenVertex; 3],
    varyings: [&Varyings; 3],
    surface: Surface,
    draw: &Draw,
    scratch: &mut BandScratch,
    masks: &mut RowMasks,
    band: &mut Band,
) -> usize {
    let viewport = draw.context.view.viewport;
    let Some((setup, planes)) = TriangleSetup::new::<C>(vertices, varyings, viewport, surface) else { return 0 };
    let bounds = setup.edges.bounds;
    let last_row = band.y0 + band.rows - 1;
    if bounds.max_y < band.y0 || bounds.min_y > last_row {
        // Part of a clipped triangle that reaches other bands.
        return 0;
    }
    let triangle = Triangle { setup: &setup, planes: &planes, material: draw.material };
    for tile in &mut scratch.tiles[(bounds.min_x / TILE_WIDTH) as usize..=(bounds.max_x / TILE_WIDTH) as usize] {
        if setup.nearest >= tile.farthest {
            tile.occluded += 1;
            continue;
        }
        let Some(walk) = Walk::new(&setup.edges, tile.rect) else { continue };
        let covered = fill_pass::<C>(&walk, masks, &triangle, draw.context, band);
        tile.fragments += covered;
        tile.covered_since_refresh += covered;
        if tile.covered_since_refresh >= tile.area * OCCLUSION_REFRESH {
            tile.covered_since_refresh = 0;
            tile.farthest = farthest_depth(band.depth, band.width, band.y0, tile.rect);
        }
    }
    usize::from(bounds.min_y >= band.y0)
}

/// The farthest depth held in `rect` of a band, four depths at a time.
fn farthest_depth(depth: &[f32], width: u32, y0: u32, rect: PixelBounds) -> f32 {
    let mut farthest = Vec4::ZERO;
    let mut rest = 0.0f32;
    for y in rect.min_y..=rect.max_y {
        let row = ((y - y0) * width) as usize;
        let depths = &depth[row + rect.min_x as usize..=row + rect.max_x as usize];
        let runs = depths.chunks_exact(LANES);
        rest = runs.remainder().iter().fold(rest, |m, &d| m.max(d));
        farthest = runs.fold(farthest, |m, run| m.max(Vec4::from_slice(run)));
    }
    farthest.max_element().max(rest)
}

/// 2^23: added to a float in `[0, 2^23)`, it leaves the rounded whole number in the low bits.
const ROUNDING_BIAS: f32 = 8_388_608.0;

/// The colour pixel loop for one combination of shading mode, texture and shadows.
///
/// Coverage is decided per pixel, exactly, as one interval per row; depth tests, interpolation
/// and lighting run on runs of [`LANES`] pixels of that interval at once.
#[inline(always)]
fn fill_pass<C: CompiledPass>(
    walk: &Walk,
    rows: &mut RowMasks,
    triangle: &Triangle,
    context: &TileContext,
    band: &mut Band,
) -> u64 {
    let pass = C::PASS;
    // The packs the pass does not read are zero, and the code reading them folds away.
    let planes = triangle.planes;
    let uses = |k: usize| k >= VARYINGS || pass.uses(k) && !colors_per_pixel(pass);
    let color_pack = &planes[slot::COLOR / LANES];
    let shading = TriangleShading {
        lane_steps: std::array::from_fn(|k| if uses(k) { planes[k / LANES].lane_steps(k % LANES) } else { Vec4::ZERO }),
        pixel_steps: std::array::from_fn(
            |k| if colors_per_pixel(pass) { color_pack.dx * k as f32 } else { Vec4::ZERO },
        ),
        planes,
        affine: triangle.setup.affine,
        origin: (triangle.setup.edges.bounds.min_x, triangle.setup.edges.bounds.min_y),
        triangle,
        context,
    };
    walk.visit_runs(
        rows,
        &mut RunShader::<C> { shading: &shading, band, at: 0, px: 0.0, row: [Vec4::ZERO; PACKS], pass: PhantomData },
    )
}

/// What the runs of a triangle share.
struct TriangleShading<'a> {
    planes: &'a Planes,
    /// Each value's change from a run's first pixel to its lanes (only depth's and `1/w`'s
    /// when [`colors_per_pixel`]).
    lane_steps: [Vec4; VARYINGS + 2],
    /// The colour pack's change from a run's first pixel to each of its pixels, when
    /// [`colors_per_pixel`].
    pixel_steps: [Vec4; LANES],
    /// Whether the values are interpolated in screen space.
    affine: bool,
    /// The first pixel of the triangle's bounds, where its planes start.
    origin: (u32, u32),
    triangle: &'a Triangle<'a>,
    context: &'a TileContext<'a>,
}

impl TriangleShading<'_> {
    /// Value `k`'s lanes in a run whose packs of values start at `at_run`.
    #[inline(always)]
    fn lane_value(&self, at_run: &[Vec4; PACKS], k: usize) -> Vec4 {
        Vec4::splat(at_run[k / LANES][k % LANES]) + self.lane_steps[k]
    }
}

/// Depth-tests, shades and stores a triangle's runs into a band, stepping from run to run
/// along a row.
struct RunShader<'a, 'b, C> {
    shading: &'a TriangleShading<'a>,
    band: &'a mut Band<'b>,
    /// The next run's first pixel, as an index into the band.
    at: usize,
    /// The next run's first pixel, in pixels right of the triangle's bounds.
    px: f32,
    /// What the row adds to each plane's values (see [`Plane::at`]).
    row: [Vec4; PACKS],
    pass: PhantomData<C>,
}

impl<C: CompiledPass> RunVisitor for RunShader<'_, '_, C> {
    #[inline(always)]
    fn row(&mut self, y: u32, x: u32) {
        let (origin, planes) = (self.shading.origin, self.shading.planes);
        self.at = (y - self.band.y0) as usize * self.band.width as usize + x as usize;
        self.px = (x - origin.0) as f32;
        let py = (y - origin.1) as f32;
        let read = const { packs_read(C::PASS) };
        self.row = std::array::from_fn(|p| if read[p] { planes[p].dy * py } else { Vec4::ZERO });
    }

    /// A run reaching past the end of its row covers the first pixels of the next row too,
    /// which its clear lanes leave as they are; only in the band's last row may fewer than
    /// [`LANES`] pixels be left.
    #[inline(always)]
    fn run(&mut self, lanes: u32) {
        let (at, px) = (self.at, self.px);
        self.at += LANES;
        // Whole numbers far below 2^24: the float steps exactly.
        self.px += LANES as f32;
        let band = &mut *self.band;
        match (band.depth.get_mut(at..at + LANES), band.color.get_mut(at..at + LANES)) {
            (Some(depths), Some(colors)) => {
                let run = Run { depths: depths.try_into().expect("a run"), colors: colors.try_into().expect("a run") };
                shade_pixels::<C>(self.shading, px, &self.row, lanes, run);
            }
            _ => shade_band_end::<C>(self.shading, band, px, &self.row, lanes, at),
        }
    }
}

/// [`RunShader::run`] of a run reaching past the end of the band, through a copy of its
/// pixels.
#[cold]
#[inline(never)]
fn shade_band_end<C: CompiledPass>(
    shading: &TriangleShading,
    band: &mut Band,
    px: f32,
    row: &[Vec4; PACKS],
    lanes: u32,
    at: usize,
) {
    let (mut depths, mut colors) = (run_of(&band.depth[at..], FAR_DEPTH), run_of(&band.color[at..], [0; 4]));
    let valid = band.depth.len() - at;
    shade_pixels::<C>(shading, px, row, lanes, Run { depths: &mut depths, colors: &mut colors });
    band.depth[at..].copy_from_slice(&depths[..valid]);
    band.color[at..].copy_from_slice(&colors[..valid]);
}

/// The depths and colours of the [`LANES`] pixels of a run.
struct Run<'a> {
    depths: &'a mut [f32; LANES],
    colors: &'a mut [[u8; 4]; LANES],
}

/// Depth-tests, shades and stores the pixels of `run` of `lanes`' set bits; the run starts `px`
/// pixels right of the triangle's bounds, in a row adding `row` to the planes' values.
#[inline(always)]
fn shade_pixels<C: CompiledPass>(shading: &TriangleShading, px: f32, row: &[Vec4; PACKS], lanes: u32, run: Run) {
    let TriangleShading { planes, pixel_steps, affine, .. } = shading;
    let shadowed = C::PASS.shadowed;
    let at_run: [Vec4; PACKS] = std::array::from_fn(|p| planes[p].at_row(px, row[p]));
    let lane_value = |k: usize| shading.lane_value(&at_run, k);
    let z = lanes_of(lane_value(DEPTH));
    let depth = f32x4::new(*run.depths);
    let drawn = z.simd_lt(depth) & covered(lanes);
    let drawn_lanes = drawn.to_bitmask();
    if drawn_lanes == 0 {
        return;
    }
    *run.depths = drawn.bitselect(z, depth).to_array();
    let w = if *affine { Vec4::ONE } else { lane_value(INV_W).recip() };
    let pixels = match colors_per_pixel(C::PASS) {
        true => pixel_colors(at_run[slot::COLOR / LANES], pixel_steps, (!*affine).then_some(w), shadowed),
        false => lane_colors::<C>(shading, &at_run, w),
    };
    *run.colors = colors_of(drawn.to_bits().bitselect(pixels, words_of(*run.colors)));
}

/// The RGBA8 words of a run whose values start at `at_run` and reach the pixel's `w` when
/// interpolated perspective-correctly, shaded value by value: each value's lanes (its pixels)
/// are lit, textured and turned into bytes together.
#[inline(always)]
fn lane_colors<C: CompiledPass>(shading: &TriangleShading, at_run: &[Vec4; PACKS], w: Vec4) -> u32x4 {
    let TriangleShading { affine, triangle, context, .. } = shading;
    let Pass { shading: mode, textured, shadowed } = C::PASS;
    let light = &context.frame.light;
    let material = triangle.material;
    let value = |k: usize| {
        let lanes = shading.lane_value(at_run, k);
        if *affine { lanes } else { lanes * w }
    };
    let diffuse = match mode {
        Shading::Flat => Vec4::splat(triangle.setup.flat_diffuse),
        Shading::Gouraud if !shadowed => Vec4::ZERO,
        Shading::Gouraud => value(slot::DIFFUSE),
        Shading::Phong => {
            let (nx, ny, nz) = (value(slot::NORMAL), value(slot::NORMAL + 1), value(slot::NORMAL + 2));
            let towards = -light.direction;
            let cosine = (nx * towards.x + ny * towards.y + nz * towards.z)
                / (nx * nx + ny * ny + nz * nz).max(Vec4::splat(1e-12)).sqrt();
            cosine.max(Vec4::ZERO) * light.diffuse
        }
    };
    let mut rgb = [value(slot::COLOR), value(slot::COLOR + 1), value(slot::COLOR + 2)];
    // Lit as if the light reached every pixel (Gouraud's colours were lit at the vertices);
    // with shadows, `light_band` darkens those it does not reach once the band is drawn.
    if mode != Shading::Gouraud {
        let intensity = light.combine_lanes(diffuse, Vec4::ONE);
        for c in &mut rgb {
            *c *= intensity;
        }
    }
    if textured && let Some(texture) = material.texture.as_deref() {
        let (u, v) = (value(slot::UV), value(slot::UV + 1));
        // The coordinates' screen derivatives, once for both images; each image turns them
        // into the level its own size gives.
        let derivatives = (material.sampler.filter == Filter::Trilinear).then(|| uv_derivatives(shading, u, v, w));
        let lod = |image: &Texture| derivatives.map_or(Vec4::ZERO, |d| image.lod_lanes(d));
        let mut texels = texture.sample_lanes(u, v, lod(texture), material.sampler);
        if let Some(blend) = material.blend.as_deref() {
            let others = blend.sample_lanes(u, v, lod(blend), material.sampler);
            let weight = value(slot::BLEND).clamp(Vec4::ZERO, Vec4::ONE);
            for (texel, other) in texels.iter_mut().zip(others) {
                *texel += (other - *texel) * weight;
            }
        }
        for (c, texel) in rgb.iter_mut().zip(texels) {
            *c *= texel;
        }
    }
    let [r, g, b] = rgb.map(unit_bytes);
    let alpha = if shadowed { unit_bytes(diffuse) } else { u32x4::splat(0xff) };
    r | g << 8 | b << 16 | alpha << 24
}

/// The screen derivatives `[du/dx, dv/dx, du/dy, dv/dy]` of the texture coordinates at a run's
/// pixels, whose coordinates are `u` and `v` and whose `w` is `w`: a perspective-correct
/// interpolation of `t = (t / w) / (1 / w)` gives `dt/dx = w (d(t / w)/dx - t d(1 / w)/dx)`
/// (and along y alike).
#[inline(always)]
fn uv_derivatives(shading: &TriangleShading, u: Vec4, v: Vec4, w: Vec4) -> UvDerivatives {
    let planes = shading.planes;
    let steps = |k: usize| (planes[k / LANES].dx[k % LANES], planes[k / LANES].dy[k % LANES]);
    let (inv_w_dx, inv_w_dy) = steps(INV_W);
    let derivatives = |k: usize, t: Vec4| {
        let (dx, dy) = steps(k);
        if shading.affine {
            (Vec4::splat(dx), Vec4::splat(dy))
        } else {
            ((Vec4::splat(dx) - t * inv_w_dx) * w, (Vec4::splat(dy) - t * inv_w_dy) * w)
        }
    };
    let ((du_dx, du_dy), (dv_dx, dv_dy)) = (derivatives(slot::UV, u), derivatives(slot::UV + 1, v));
    [du_dx, dv_dx, du_dy, dv_dy]
}

/// Whether `pass` stores each pixel's interpolated colour pack (red, green, blue and the
/// diffuse term) as it is: Gouraud shading without a texture, whose colours were lit at the
/// vertices. Its runs then turn each pixel's pack into bytes at once (see [`pixel_colors`])
/// instead of each value's lanes.
const fn colors_per_pixel(pass: Pass) -> bool {
    matches!(pass.shading, Shading::Gouraud) && !pass.textured
}

/// The RGBA8 words of a run whose colour pack is `first` at its first pixel and steps by
/// `steps` to each pixel, times the pixel's `w` (lane `k` for pixel `k`) when interpolated
/// perspective-correctly: red, green and blue, and in alpha the diffuse term with shadows
/// (see [`light_band`]) or opaque without.
///
/// The same bytes as [`unit_bytes`] of each value: the conversion rounds to the nearest whole
/// number (ties to even) and the narrowing to bytes saturates at 0 and 255, so only values
/// too large to convert need clamping first.
#[inline(always)]
fn pixel_colors(first: Vec4, steps: &[Vec4; LANES], w: Option<Vec4>, shadowed: bool) -> u32x4 {
    let words: [i32x4; LANES] = std::array::from_fn(|k| {
        let pack = first + steps[k];
        let pack = w.map_or(pack, |w| pack * w[k]);
        lanes_of((pack * 255.0).min(Vec4::splat(255.0))).fast_round_int()
    });
    let narrow = |a: i32x4, b: i32x4| i16x8::from_i32x8_saturate(bytemuck::cast([a, b]));
    let bytes = u8x16::narrow_i16x8(narrow(words[0], words[1]), narrow(words[2], words[3]));
    let pixels = words_of(bytemuck::cast(bytes));
    if shadowed { pixels } else { pixels | u32x4::splat(0xff << 24) }
}

/// Each lane of `v`, clamped to `[0, 1]`, as a byte (0 to 255) in the low bits of its lane.
#[inline(always)]
fn unit_bytes(v: Vec4) -> u32x4 {
    rounded_bytes(v.clamp(Vec4::ZERO, Vec4::ONE) * 255.0)
}

/// Each lane of `v`, in `[0, 255]`, rounded to the nearest whole number, in the low bits of its
/// lane.
#[inline(always)]
fn rounded_bytes(v: Vec4) -> u32x4 {
    lanes_of(v + ROUNDING_BIAS).to_bits() & u32x4::splat(0xff)
}

/// A run's RGBA8 colours as one little-endian word per pixel, red in the low byte.
#[inline(always)]
fn words_of(colors: [[u8; 4]; LANES]) -> u32x4 {
    u32x4::from(bytemuck::cast::<_, [u32; LANES]>(colors).map(u32::from_le))
}

/// The RGBA8 colours of [`words_of`]'s words.
#[inline(always)]
fn colors_of(words: u32x4) -> [[u8; 4]; LANES] {
    bytemuck::cast(words.to_array().map(u32::to_le))
}

/// Fades the drawn pixels of a band into `color` by their distance in front of `camera` as
/// `fog` says, four pixels at a time; pixels no triangle covers keep the background.
///
/// A pixel's normalised depth `d` (0 at the near plane, 1 at the far) is a distance `D` along
/// the view direction of `D = near far / (far - d (far - near))`.
fn fog_band(band: &mut Band, fog: Fog, color: [u8; 3], camera: &Camera) {
    let (near, far) = (camera.near, camera.far);
    let span = (fog.end_m - fog.start_m).max(1e-6);
    let colour = color.map(|c| Vec4::splat(f32::from(c)));
    for (depths, colors) in band.depth.chunks_exact(LANES).zip(band.color.chunks_exact_mut(LANES)) {
        let depth = Vec4::from_slice(depths);
        let drawn = depth.cmplt(Vec4::splat(FAR_DEPTH));
        if !drawn.any() {
            continue;
        }
        let distance = Vec4::splat(near * far) / (Vec4::splat(far) - depth * (far - near));
        let amount = ((distance - fog.start_m) / span).clamp(Vec4::ZERO, Vec4::ONE);
        let amount = Vec4::select(drawn, amount, Vec4::ZERO);
        let run: &mut [[u8; 4]; LANES] = colors.try_into().expect("a run of four pixels");
        let words = words_of(*run);
        let faded: [u32x4; 3] = std::array::from_fn(|c| {
            let channel = bytes_of(words, 8 * c as u32);
            rounded_bytes(channel + (colour[c] - channel) * amount) << (8 * c as u32)
        });
        *run = colors_of(faded[0] | faded[1] | faded[2] | (words & u32x4::splat(0xff00_0000)));
    }
    let rest = band.depth.len() / LANES * LANES;
    for (depth, pixel) in band.depth[rest..].iter().zip(&mut band.color[rest..]) {
        if *depth < FAR_DEPTH {
            let distance = near * far / (far - depth * (far - near));
            let amount = ((distance - fog.start_m) / span).clamp(0.0, 1.0);
            for (channel, target) in pixel.iter_mut().zip(color) {
                *channel = (f32::from(*channel) + (f32::from(target) - f32::from(*channel)) * amount).round() as u8;
            }
        }
    }
}

/// Darkens the pixels of a band drawn with shadows where the light does not reach them: each
/// drawn pixel holds its colour lit as if it did and, in alpha, its diffuse term; its
/// shadow-map position follows from its depth.
///
/// The band is worked through tile by tile (`tiles`, so that the texels read stay few), a tile
/// row at a time: first the map positions of all its runs of [`LANES`] drawn pixels; then the
/// one read per pixel that finds most runs lit in full (see [`ShadowMap::lit_in_full`]), which
/// only become opaque; then the full reads and colours of the others. Each step's reads of many
/// runs wait on memory together. Kept out of line: a pass of its own after the triangles, it
/// does not belong in their loops' code.
#[inline(never)]
fn light_band<const FILTERED: bool>(band: &mut Band, tiles: &[TileState], shadow: &BandShadow) {
    let width = band.width as usize;
    // A tile row's whole runs, and the pixels left at the end of the band's last tile.
    let mut pending = [PendingRun::default(); TILE_WIDTH as usize / LANES + 1];
    // The light reaching the runs a tile row leaves for full reads, in their order.
    let mut visibility = [Vec4::ZERO; TILE_WIDTH as usize / LANES + 1];
    // Tiles nothing was drawn into (the sky, say) have nothing to darken.
    for tile in tiles.iter().filter(|tile| tile.fragments > 0) {
        let (x0, x1) = (tile.rect.min_x as usize, tile.rect.max_x as usize + 1);
        for row in 0..band.rows as usize {
            let in_map = shadow.pixels.row(band.y0 + row as u32);
            let pixels = row * width + x0..row * width + x1;
            let (depth_runs, depth_rest) = band.depth[pixels.clone()].as_chunks::<LANES>();
            let (color_runs, color_rest) = band.color[pixels].as_chunks_mut::<LANES>();
            let mut count = 0;
            // Run `run`, its pixels' depths and columns (`x`, as floats).
            let mut find = |run: usize, depths: [f32; LANES], x: Vec4| {
                let depth = Vec4::from_array(depths);
                let drawn = lanes_of(depth).simd_lt(f32x4::splat(FAR_DEPTH));
                if drawn.any() {
                    let [tx, ty, light_depth] = shadow.pixels.locate(in_map, x, depth);
                    let taps = shadow.map.taps(tx, ty, light_depth, FILTERED);
                    pending[count] = PendingRun { run, drawn, taps };
                    count += 1;
                }
            };
            // Whole columns are exact as floats: stepped, not converted per run.
            let mut x = Vec4::splat(x0 as f32) + LANE_OFFSETS;
            for (run, depths) in depth_runs.iter().enumerate() {
                find(run, *depths, x);
                x += LANES as f32;
            }
            if !depth_rest.is_empty() {
                find(depth_runs.len(), run_of(depth_rest, FAR_DEPTH), x);
            }
            // Runs the light reaches in full (most) keep their colours and only become opaque.
            // The others move to the front of `pending`, read in place (not copied whole).
            let mut left = 0;
            for k in 0..count {
                let PendingRun { run, drawn, ref taps } = pending[k];
                if (shadow.map.lit_in_full(taps, FILTERED) | !drawn).all() {
                    shade_colors(color_runs, color_rest, run, |colors| opaque(colors, drawn));
                } else {
                    pending[left] = pending[k];
                    left += 1;
                }
            }
            for (run, visibility) in pending[..left].iter().zip(&mut visibility) {
                *visibility = shadow.map.read(&run.taps, FILTERED);
            }
            for (run, &visibility) in pending[..left].iter().zip(&visibility) {
                // A filtered lookup may still find the light in full (its shadowing texels
                // weigh nothing).
                let darkened = (lanes_of(visibility).simd_lt(f32x4::ONE) & run.drawn).any();
                shade_colors(color_runs, color_rest, run.run, |colors| match darkened {
                    true => light_run(colors, run.drawn, visibility, &shadow.light),
                    false => opaque(colors, run.drawn),
                });
            }
        }
    }
}

/// Replaces the colours of run `run` of a tile row by `shade` of them; the row's whole runs are
/// `runs`, and `rest` its pixels past them (the last run when it is cut short).
fn shade_colors(
    runs: &mut [[[u8; 4]; LANES]],
    rest: &mut [[u8; 4]],
    run: usize,
    shade: impl FnOnce([[u8; 4]; LANES]) -> [[u8; 4]; LANES],
) {
    match runs.get_mut(run) {
        Some(colors) => *colors = shade(*colors),
        None => {
            let shaded = shade(run_of(rest, [0; 4]));
            rest.copy_from_slice(&shaded[..rest.len()]);
        }
    }
}

/// What [`light_band`] reads.
pub(crate) struct BandShadow<'a> {
    pub map: &'a ShadowMap,
    pub pixels: PixelsInMap,
    pub light: Light,
    pub filtered: bool,
}

/// A run of pixels whose map lookups are known but not yet read.
#[derive(Clone, Copy, Default)]
struct PendingRun {
    /// Which run of its tile row it is.
    run: usize,
    /// Its drawn pixels (nearer than the far depth).
    drawn: f32x4,
    taps: Taps,
}

/// The values of a run cut short, `fill` past them.
fn run_of<T: Copy>(values: &[T], fill: T) -> [T; LANES] {
    std::array::from_fn(|k| values.get(k).copied().unwrap_or(fill))
}

/// The colours of a run whose `drawn` pixels hold their colour lit in full and their diffuse
/// term (see [`light_band`]), for the light reaching them in full: opaque, and otherwise as they
/// are.
#[inline(always)]
fn opaque(colors: [[u8; 4]; LANES], drawn: f32x4) -> [[u8; 4]; LANES] {
    colors_of(words_of(colors) | drawn.to_bits() & u32x4::splat(0xff << 24))
}

/// The colours of a run whose `drawn` pixels hold their colour lit in full and their diffuse
/// term (see [`light_band`]), with `light` reaching them by `visibility`; the others keep
/// theirs. A pixel the light reaches in full keeps its colour exactly.
#[inline(always)]
fn light_run(colors: [[u8; 4]; LANES], drawn: f32x4, visibility: Vec4, light: &Light) -> [[u8; 4]; LANES] {
    let old = words_of(colors);
    let diffuse = bytes_of(old, 24) * BYTE_TO_UNIT;
    // The colour pass lit the pixel with `full`; a pixel with no light at all is black either way.
    let full = light.combine_lanes(diffuse, Vec4::ONE);
    let scale = light.combine_lanes(diffuse, visibility) / full.max(Vec4::splat(f32::MIN_POSITIVE));
    let [r, g, b] =
        [0, 8, 16].map(|shift| rounded_bytes((bytes_of(old, shift) * scale).clamp(Vec4::ZERO, Vec4::splat(255.0))));
    let lit = r | g << 8 | b << 16 | u32x4::splat(0xff) << 24;
    colors_of(drawn.to_bits().bitselect(lit, old))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_farthest_depth_is_found_in_whole_runs_and_in_the_rest_of_a_row() {
        // A band 13 pixels wide from row 8 on; the rect's rows are 6 pixels long: one run of
        // four and a rest of two.
        let (width, y0) = (13, 8);
        let rect = PixelBounds { min_x: 3, max_x: 8, min_y: 9, max_y: 11 };
        let mut depth = vec![0.9; width as usize * 4];
        for y in rect.min_y..=rect.max_y {
            let row = ((y - y0) * width) as usize;
            depth[row + 3..=row + 8].fill(0.25);
        }
        let at = |x: u32, y: u32| ((y - y0) * width + x) as usize;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.25, "pixels outside the rect do not count");
        depth[at(5, 10)] = 0.5;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.5, "inside a run");
        depth[at(8, 11)] = 0.75;
        assert_eq!(farthest_depth(&depth, width, y0, rect), 0.75, "in the rest of a row");
    }

    /// A colour value: mostly within a channel's range or near it, sometimes far outside.
    fn color_value() -> impl Strategy<Value = f32> {
        prop_oneof![4 => -0.5f32..1.5, 1 => -1e12f32..1e12]
    }

    proptest! {
        /// A run's colours made pixel by pixel are the bytes the value-by-value conversion
        /// makes of each value, in and out of range, with and without a pixel's `w`.
        #[test]
        fn pixel_colors_are_the_bytes_of_each_value(
            packs in prop::array::uniform4(prop::array::uniform4(color_value())),
            w in prop::option::of(prop::array::uniform4(0.01f32..100.0)),
            shadowed: bool,
        ) {
            let steps = packs.map(Vec4::from_array);
            let pixels = pixel_colors(Vec4::ZERO, &steps, w.map(Vec4::from_array), shadowed).to_array();
            for (k, (&pixel, pack)) in pixels.iter().zip(steps).enumerate() {
                let value = pack * w.map_or(1.0, |w| w[k]);
                let byte = |v: f32| unit_bytes(Vec4::splat(v)).to_array()[0];
                let alpha = if shadowed { byte(value.w) } else { 0xff };
                prop_assert_eq!(pixel, byte(value.x) | byte(value.y) << 8 | byte(value.z) << 16 | alpha << 24);
            }
        }

    }
}
