//! Golden-image tests of the rasterizer, each with a direct check of the property it shows.
//!
//! The reference images live in `tests/golden/`. A test fails when more than
//! [`MAX_DIFFERENT_SHARE`] of the pixels differ from the reference by more than
//! [`CHANNEL_TOLERANCE`] in some channel. Run with `CANOPY_BLESS=1` to write the references
//! anew after an intended change (and look at them before committing).

use bevy_math::{Mat4, Vec2, Vec3};
use bevy_tasks::TaskPool;
use canopy_raster::benchmark_scene as standard;
use canopy_raster::{
    Address, Camera, Filter, Fog, Frame, Framebuffer, Instance, Lens, Light, Material, MeshData, RenderSettings,
    RenderStats, Renderer, Sampler, Shading, Texture,
};
use std::f32::consts::FRAC_PI_2;
use std::path::PathBuf;
use std::sync::Arc;

/// Largest per-channel difference a pixel may show and still count as equal.
const CHANNEL_TOLERANCE: u8 = 8;

/// Share of pixels allowed to differ by more than the tolerance.
const MAX_DIFFERENT_SHARE: f64 = 0.002;

const SKY: [u8; 4] = [40, 60, 90, 255];

/// The reference image `name`, from the crate's folder, where cargo runs its tests.
fn golden_path(name: &str) -> PathBuf {
    PathBuf::from("tests/golden").join(format!("{name}.png"))
}

/// Compares `image` with the reference `name`, or writes it when blessing.
fn assert_golden(name: &str, image: &Framebuffer) {
    let path = golden_path(name);
    if std::env::var_os("CANOPY_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image.save_png(&path).unwrap();
        return;
    }
    let reference = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (run with CANOPY_BLESS=1 to create it)", path.display()))
        .into_rgba8();
    assert_eq!(reference.dimensions(), (image.width(), image.height()), "{name}: size");
    let different = reference
        .as_raw()
        .chunks_exact(4)
        .zip(image.color().chunks_exact(4))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > CHANNEL_TOLERANCE))
        .count();
    let share = different as f64 / (image.width() * image.height()) as f64;
    if share > MAX_DIFFERENT_SHARE {
        let actual = std::env::temp_dir().join(format!("canopy-golden-{name}.png"));
        image.save_png(&actual).unwrap();
        panic!(
            "{name}: {:.2}% of pixels differ from {} (written to {})",
            share * 100.0,
            path.display(),
            actual.display()
        );
    }
}

fn render(
    camera: Camera,
    light: Light,
    instances: &[Instance],
    settings: RenderSettings,
) -> (Framebuffer, RenderStats) {
    let mut target = Framebuffer::new(160, 120);
    let frame = Frame { camera, light, background: SKY, instances, settings };
    let stats = Renderer::default().render(&mut target, &TaskPool::new(), &frame);
    (target, stats)
}

fn sun() -> Light {
    Light { direction: Vec3::new(-0.5, -1.0, -0.3).normalize(), diffuse: 0.8, fill: 0.0, ambient: 0.2 }
}

fn colored(mesh: MeshData, model: Mat4, color: Vec3) -> Instance {
    Instance { mesh: Arc::new(mesh), model, material: Material::colored(color) }
}

/// A ground plane running from the camera's feet far into the distance, textured with a
/// horizontal gradient along `v` (red = `v`) and a checkerboard in green.
fn steep_plane() -> (Camera, Instance) {
    let texture = Texture::from_fn(8, 256, |x, y| {
        let check = if (x + y / 32) % 2 == 0 { 1.0 } else { 0.0 };
        Vec3::new((y as f32 + 0.5) / 256.0, check, 0.5)
    });
    let material = Material {
        color: Vec3::ONE,
        texture: Some(Arc::new(texture)),
        blend: None,
        sampler: Sampler { filter: Filter::Nearest, address: Address::Clamp },
        uv_scale: Vec2::ONE,
    };
    // A single quad (two triangles), 4 m wide and 20 m deep: v = 0 at the near edge (z = 1),
    // v = 1 at the far edge (z = -19).
    let mesh = MeshData {
        positions: vec![
            Vec3::new(-2.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, -19.0),
            Vec3::new(-2.0, 0.0, -19.0),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)],
        colors: vec![],
        blend: vec![],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        morph: None,
    };
    let camera = Camera {
        eye: Vec3::new(0.0, 1.0, 1.5),
        target: Vec3::new(0.0, 0.0, -3.0),
        lens: Lens::FieldOfView(1.0),
        near: 0.1,
        far: 100.0,
    };
    (camera, Instance { mesh: Arc::new(mesh), model: Mat4::IDENTITY, material })
}

#[test]
fn textures_are_perspective_correct_on_a_steep_plane() {
    let (camera, plane) = steep_plane();
    let full = Light { direction: Vec3::NEG_Y, diffuse: 1.0, fill: 0.0, ambient: 0.0 };
    let (image, _) = render(camera, full, std::slice::from_ref(&plane), RenderSettings::default());
    assert_golden("textured_steep_plane", &image);

    // Cast a ray through a column of pixel centres and compare the texture coordinate drawn
    // there (red channel) with where the ray meets the plane. Affine interpolation would make
    // v linear in screen y; perspective-correct interpolation makes it follow the ray.
    let (width, height) = (image.width() as f32, image.height() as f32);
    let clip_from_world = camera.view_projection(width / height);
    let world_from_ndc = clip_from_world.inverse();
    let near_edge_y = (1.0 - clip_from_world.project_point3(Vec3::new(0.0, 0.0, 1.0)).y) * 0.5 * height;
    let far_edge_y = (1.0 - clip_from_world.project_point3(Vec3::new(0.0, 0.0, -19.0)).y) * 0.5 * height;
    let mut checked = 0;
    let mut largest_affine_error = 0.0f32;
    for py in (far_edge_y.ceil() as u32 + 2)..(near_edge_y.floor() as u32).min(image.height()) - 2 {
        let ndc_y = 1.0 - (py as f32 + 0.5) / height * 2.0;
        let ndc_x = (80.0 + 0.5) / width * 2.0 - 1.0;
        let a = world_from_ndc.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
        let b = world_from_ndc.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
        let hit = a + (b - a) * (a.y / (a.y - b.y));
        let v = (1.0 - hit.z) / 20.0;
        let drawn = image.pixel(80, py)[0] as f32 / 255.0;
        // One texel of the 256-texel gradient plus rounding.
        assert!((drawn - v).abs() < 1.5 / 256.0 + 1.0 / 255.0, "row {py}: drawn v {drawn}, ray v {v}");
        let affine = (near_edge_y - (py as f32 + 0.5)) / (near_edge_y - far_edge_y);
        largest_affine_error = largest_affine_error.max((affine - v).abs());
        checked += 1;
    }
    assert!(checked > 20, "only {checked} rows checked");
    assert!(largest_affine_error > 0.2, "affine and perspective agree too well: {largest_affine_error}");
}

/// A ground plane 200 m square seen from 1.5 m above it, checkered in black and white squares
/// of 25 cm, read with `filter`; at 320 x 240 pixels, and which rows of the image see the ground
/// farther than 15 m (where a pixel spans more than two squares) and nearer than 4 m.
fn receding_checkerboard(filter: Filter) -> (Framebuffer, Vec<u32>, Vec<u32>) {
    // Eight by eight squares of eight texels; the plane repeats the texture every 2 m.
    let texture = Texture::from_fn(64, 64, |x, y| Vec3::splat(((x / 8 + y / 8) % 2) as f32));
    let material = Material {
        color: Vec3::ONE,
        texture: Some(Arc::new(texture)),
        blend: None,
        sampler: Sampler { filter, address: Address::Repeat },
        uv_scale: Vec2::splat(100.0),
    };
    let ground = Instance {
        mesh: Arc::new(MeshData::plane(1)),
        model: Mat4::from_translation(Vec3::new(0.0, 0.0, -99.5)) * Mat4::from_scale(Vec3::new(200.0, 1.0, 200.0)),
        material,
    };
    let camera = Camera {
        eye: Vec3::new(0.0, 1.5, 0.0),
        target: Vec3::new(0.0, 0.0, -6.0),
        lens: Lens::FieldOfView(1.0),
        near: 0.1,
        far: 300.0,
    };
    let full = Light { direction: Vec3::NEG_Y, diffuse: 1.0, fill: 0.0, ambient: 0.0 };
    let (width, height) = (320, 240);
    let mut image = Framebuffer::new(width, height);
    let frame =
        Frame { camera, light: full, background: SKY, instances: &[ground], settings: RenderSettings::default() };
    Renderer::default().render(&mut image, &TaskPool::new(), &frame);

    // The distance at which the ray through the middle of each row meets the ground.
    let world_from_ndc = camera.view_projection(width as f32 / height as f32).inverse();
    let distance = |py: u32| {
        let ndc_y = 1.0 - (py as f32 + 0.5) / height as f32 * 2.0;
        let a = world_from_ndc.project_point3(Vec3::new(0.0, ndc_y, 0.0));
        let b = world_from_ndc.project_point3(Vec3::new(0.0, ndc_y, 1.0));
        let t = a.y / (a.y - b.y);
        (t > 0.0 && b.y < a.y).then(|| (a + (b - a) * t).distance(camera.eye))
    };
    let far = (0..height).filter(|&py| distance(py).is_some_and(|d| (15.0..150.0).contains(&d))).collect();
    let near = (0..height).filter(|&py| distance(py).is_some_and(|d| d < 4.0)).collect();
    (image, far, near)
}

/// How far the pixels of `rows` lie from mid grey, the mean of black and white squares, on
/// average, in steps of the 8-bit channel.
fn deviation_from_grey(image: &Framebuffer, rows: &[u32]) -> f64 {
    let pixels = rows.iter().flat_map(|&y| (0..image.width()).map(move |x| (x, y)));
    let deviations: Vec<f64> = pixels.map(|(x, y)| (f64::from(image.pixel(x, y)[1]) - 127.5).abs()).collect();
    deviations.iter().sum::<f64>() / deviations.len() as f64
}

#[test]
fn textures_fade_to_their_mean_at_a_distance() {
    let (trilinear, far, near) = receding_checkerboard(Filter::Trilinear);
    assert_golden("receding_checkerboard", &trilinear);
    assert!(far.len() >= 15 && near.len() >= 15, "{} far rows, {} near rows", far.len(), near.len());
    // Far off, mip maps leave the mean of many squares in each pixel: no moire.
    let far_trilinear = deviation_from_grey(&trilinear, &far);
    assert!(far_trilinear < 12.0, "far rows stray {far_trilinear:.1} from grey on average");
    // Reading only the image, each far pixel is one point of a square, black or white: the
    // pattern aliases into moire (and the measure above tells the two apart).
    let (bilinear, _, _) = receding_checkerboard(Filter::Bilinear);
    let far_bilinear = deviation_from_grey(&bilinear, &far);
    assert!(far_bilinear > 60.0, "the image alone strays only {far_bilinear:.1}");
    // Close by, the squares stay black and white: the levels are chosen per pixel, not blurred
    // everywhere.
    let near_trilinear = deviation_from_grey(&trilinear, &near);
    assert!(near_trilinear > 100.0, "near rows stray only {near_trilinear:.1}");
}

/// A box standing on a plane, lit from the upper left.
fn box_on_plane() -> (Camera, Vec<Instance>) {
    let ground = colored(MeshData::plane(8), Mat4::from_scale(Vec3::splat(8.0)), Vec3::new(0.8, 0.8, 0.7));
    let block = colored(
        MeshData::cube(),
        Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)) * Mat4::from_rotation_y(0.4),
        Vec3::new(0.9, 0.4, 0.3),
    );
    let camera = Camera {
        eye: Vec3::new(1.5, 3.0, 5.0),
        target: Vec3::new(0.3, 0.0, 0.0),
        lens: Lens::FieldOfView(0.9),
        near: 0.1,
        far: 50.0,
    };
    (camera, vec![ground, block])
}

#[test]
fn a_box_casts_a_shadow_onto_the_plane() {
    let (camera, scene) = box_on_plane();
    let shadowed = RenderSettings { shadows: true, ..RenderSettings::default() };
    // The light comes from behind the box, so its shadow falls towards the camera.
    let light = Light { direction: Vec3::new(0.4, -1.0, 0.5).normalize(), ..sun() };
    let (with, stats) = render(camera, light, &scene, shadowed);
    let (without, _) = render(camera, light, &scene, RenderSettings::default());
    assert!(stats.shadow_triangles > 0);
    assert_golden("box_shadow", &with);

    // A ground point whose path to the light passes through the box, and one in the open.
    let clip = camera.view_projection(160.0 / 120.0);
    let pixel_of = |p: Vec3| {
        let ndc = clip.project_point3(p);
        (((ndc.x + 1.0) * 80.0) as u32, ((1.0 - ndc.y) * 60.0) as u32)
    };
    let (sx, sy) = pixel_of(Vec3::new(0.6, 0.0, 0.6));
    let (lx, ly) = pixel_of(Vec3::new(-1.5, 0.0, 1.5));
    let brightness = |image: &Framebuffer, x, y| image.pixel(x, y)[..3].iter().map(|&c| c as u32).sum::<u32>();
    assert!(
        brightness(&with, sx, sy) * 2 < brightness(&with, lx, ly),
        "shadowed {:?} vs lit {:?}",
        with.pixel(sx, sy),
        with.pixel(lx, ly)
    );
    // Without shadows the same ground point is lit like its neighbours.
    assert!(brightness(&without, sx, sy).abs_diff(brightness(&without, lx, ly)) < 30);
    // Lit ground looks the same with and without the shadow map (no acne).
    assert_eq!(with.pixel(lx, ly), without.pixel(lx, ly));
}

#[test]
fn the_three_shading_modes() {
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 2.2),
        target: Vec3::ZERO,
        lens: Lens::FieldOfView(0.7),
        near: 0.1,
        far: 10.0,
    };
    let sphere = [colored(MeshData::sphere(8, 12), Mat4::IDENTITY, Vec3::new(0.3, 0.7, 0.9))];
    let light = Light { direction: Vec3::new(-1.0, -0.6, -1.0).normalize(), diffuse: 0.9, fill: 0.0, ambient: 0.1 };
    let mut images = Vec::new();
    for shading in Shading::ALL {
        let settings = RenderSettings { shading, ..RenderSettings::default() };
        let (image, _) = render(camera, light, &sphere, settings);
        assert_golden(&format!("shading_{shading:?}").to_lowercase(), &image);
        images.push(image);
    }
    // Flat shading gives each facet one colour, so far fewer distinct colours than Gouraud,
    // and Phong differs from Gouraud inside facets.
    let distinct = |image: &Framebuffer| {
        let mut colors: Vec<&[u8]> = image.color().chunks_exact(4).collect();
        colors.sort();
        colors.dedup();
        colors.len()
    };
    assert!(distinct(&images[0]) * 4 < distinct(&images[1]), "{} vs {}", distinct(&images[0]), distinct(&images[1]));
    let differing = images[1].color().chunks_exact(4).zip(images[2].color().chunks_exact(4)).filter(|(a, b)| a != b);
    assert!(differing.count() > 500);
}

#[test]
fn a_triangle_crossing_the_near_plane_is_cut() {
    // One long triangle from behind the eye to far ahead, seen from just above it.
    let mesh = MeshData {
        positions: vec![Vec3::new(0.0, 0.0, 2.0), Vec3::new(3.0, 0.0, -8.0), Vec3::new(-3.0, 0.0, -8.0)],
        normals: vec![Vec3::Y; 3],
        uvs: vec![],
        colors: vec![Vec3::X, Vec3::Y, Vec3::Z],
        blend: vec![],
        triangles: vec![[0, 1, 2]],
        morph: None,
    };
    let camera = Camera {
        eye: Vec3::new(0.0, 0.3, 0.0),
        target: Vec3::new(0.0, 0.0, -3.0),
        lens: Lens::FieldOfView(1.2),
        near: 0.1,
        far: 20.0,
    };
    let full = Light { direction: Vec3::NEG_Y, diffuse: 1.0, fill: 0.0, ambient: 0.0 };
    let (image, stats) = render(camera, full, &[colored(mesh, Mat4::IDENTITY, Vec3::ONE)], RenderSettings::default());
    assert_golden("near_plane_triangle", &image);
    // Cutting off the corner behind the eye leaves a quad: two triangles drawn from one.
    assert_eq!((stats.triangles_submitted, stats.triangles_rasterized), (1, 2));
    // The bottom row is covered (the cut part reaches the screen's edge), the top is sky.
    assert_ne!(image.pixel(80, 119), SKY);
    assert_eq!(image.pixel(80, 0), SKY);
}

#[test]
fn a_watertight_mesh_shows_no_background_through_its_edges() {
    // The standard grid seen from straight above, filling the whole image: every pixel is
    // drawn exactly once (no gaps, no doubles) and none shows the sky.
    let camera = Camera {
        eye: Vec3::new(0.05, 2.6, 0.02),
        target: Vec3::new(0.05, 0.0, 0.02),
        lens: Lens::FieldOfView(0.45),
        near: 0.1,
        far: 10.0,
    };
    let grid = [standard::instance()];
    let (image, stats) = render(camera, sun(), &grid, RenderSettings::default());
    assert_golden("watertight_grid", &image);
    let sky = image.color().chunks_exact(4).filter(|p| *p == SKY).count();
    assert_eq!(sky, 0);
    assert_eq!(stats.fragments, 160 * 120);
}

#[test]
fn interpenetrating_triangles_meet_on_their_intersection() {
    let tilted = |angle: f32, color| {
        let model =
            Mat4::from_rotation_y(angle) * Mat4::from_rotation_x(FRAC_PI_2) * Mat4::from_scale(Vec3::splat(3.0));
        colored(MeshData::plane(1), model, color)
    };
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 2.0),
        target: Vec3::ZERO,
        lens: Lens::FieldOfView(FRAC_PI_2),
        near: 0.1,
        far: 100.0,
    };
    let full = Light { direction: Vec3::NEG_Z, diffuse: 0.0, fill: 0.0, ambient: 1.0 };
    let (image, _) = render(camera, full, &[tilted(0.4, Vec3::X), tilted(-0.4, Vec3::Y)], RenderSettings::default());
    assert_golden("interpenetrating", &image);
    // The planes cross along the vertical line x = 0; turning the red one by +0.4 rad about
    // +y takes its right half away from the camera, so red owns the left, green the right.
    for y in [10, 60, 110] {
        assert_eq!(image.pixel(40, y), [255, 0, 0, 255], "row {y}");
        assert_eq!(image.pixel(120, y), [0, 255, 0, 255], "row {y}");
    }
}

#[test]
fn blend_weights_fade_one_texture_into_another() {
    // A square facing the camera, red on the left edge's vertices and blue on the right's.
    let plain = |color: Vec3| Some(Arc::new(Texture::from_fn(4, 4, move |_, _| color)));
    let material = Material { texture: plain(Vec3::X), blend: plain(Vec3::Z), ..Material::colored(Vec3::ONE) };
    let mesh = MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::ZERO; 4],
        colors: vec![],
        blend: vec![0.0, 1.0, 1.0, 0.0],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        morph: None,
    };
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 3.0),
        target: Vec3::ZERO,
        lens: Lens::FieldOfView(0.9),
        near: 0.1,
        far: 10.0,
    };
    let full = Light { direction: Vec3::NEG_Z, diffuse: 1.0, fill: 0.0, ambient: 0.0 };
    let square = Instance { mesh: Arc::new(mesh), model: Mat4::IDENTITY, material };
    let (image, _) = render(camera, full, &[square], RenderSettings::default());
    // Along the middle row red falls and blue rises steadily; red and blue always sum to one.
    let row: Vec<[u8; 4]> = (0..160).map(|x| image.pixel(x, 60)).filter(|p| *p != SKY).collect();
    assert!(row.len() > 60, "{} pixels of the square", row.len());
    assert!(row[0][0] > 240 && row[0][2] < 15, "left edge {:?}", row[0]);
    assert!(row[row.len() - 1][2] > 240 && row[row.len() - 1][0] < 15, "right edge {:?}", row[row.len() - 1]);
    for pair in row.windows(2) {
        assert!(pair[1][0] <= pair[0][0] && pair[1][2] >= pair[0][2], "{pair:?}");
    }
    assert!(row.iter().all(|p| (i32::from(p[0]) + i32::from(p[2]) - 255).abs() <= 2 && p[1] == 0), "{row:?}");
}

#[test]
fn fog_fades_distant_pixels_into_its_colour() {
    // The receding checkerboard's plane, untextured, lit in full: white near and far.
    let ground = colored(MeshData::plane(1), Mat4::from_scale(Vec3::new(200.0, 1.0, 200.0)), Vec3::ONE);
    let camera = Camera {
        eye: Vec3::new(0.0, 1.5, 90.0),
        target: Vec3::new(0.0, 0.0, 84.0),
        lens: Lens::FieldOfView(1.0),
        near: 0.1,
        far: 300.0,
    };
    let full = Light { direction: Vec3::NEG_Y, diffuse: 1.0, fill: 0.0, ambient: 0.0 };
    // The background's colour, as a fog without one of its own takes.
    let fog = Fog { color: None, start_m: 10.0, end_m: 60.0 };
    let foggy = RenderSettings { fog: Some(fog), ..RenderSettings::default() };
    let (clear, _) = render(camera, full, std::slice::from_ref(&ground), RenderSettings::default());
    let (image, _) = render(camera, full, std::slice::from_ref(&ground), foggy);
    // Depth along the view direction of the ground under each row's middle pixel.
    let clip_from_world = camera.view_projection(160.0 / 120.0);
    let world_from_ndc = clip_from_world.inverse();
    let forward = (camera.target - camera.eye).normalize();
    let mut checked = 0;
    for py in 0..120 {
        let ndc_y = 1.0 - (py as f32 + 0.5) / 120.0 * 2.0;
        let (a, b) = (
            world_from_ndc.project_point3(Vec3::new(0.0, ndc_y, 0.0)),
            world_from_ndc.project_point3(Vec3::new(0.0, ndc_y, 1.0)),
        );
        if b.y >= a.y {
            assert_eq!(image.pixel(80, py), SKY, "the sky stays the background");
            continue;
        }
        let hit = a + (b - a) * (a.y / (a.y - b.y));
        let depth = (hit - camera.eye).dot(forward);
        let amount = ((depth - 10.0) / 50.0).clamp(0.0, 1.0);
        let expected: Vec<f32> = SKY[..3].iter().map(|&f| 255.0 + (f32::from(f) - 255.0) * amount).collect();
        let drawn = image.pixel(80, py);
        assert_eq!(clear.pixel(80, py)[..3], [255, 255, 255], "row {py} lit white without fog");
        for (channel, want) in drawn.iter().zip(&expected) {
            // Within what a pixel's depth varies over its height, near the horizon most.
            assert!((f32::from(*channel) - want).abs() <= 6.0, "row {py} at {depth:.1} m: {drawn:?} vs {expected:?}");
        }
        checked += 1;
    }
    assert!(checked > 30, "{checked} rows of ground");
}
