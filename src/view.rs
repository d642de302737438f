//! The scene's camera and light as entities with parameters, their keyboard controls, and the
//! [`RenderView`] they produce for the rasterizer.
//!
//! The camera orbits its target: arrows turn it around the target, PageUp/PageDown move it
//! nearer or farther. The light is set by azimuth (degrees about +y, 0 = from +z, 90 = from +x)
//! and elevation (degrees above the horizon); I/K and J/L turn it.
//!
//! With Shift, the arrows fly the camera instead (eye and target together) at
//! `camera.fly_speed_m_s`. In the window, a drag on the view orbits the camera and the wheel
//! moves it nearer or farther; with Shift (or the right button) a drag looks around from the
//! eye ([`CameraParams::looked_around`]) and the wheel changes the fly speed.
//!
//! Parameters: `camera.{target.x|y|z, yaw_deg, pitch_deg, distance, fov_deg, fly_speed_m_s}` and
//! `light.{azimuth_deg, elevation_deg, diffuse, ambient}`.

use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::entity::FocusPoint;
use crate::foundation::keys::{KeyHelp, KeyScope, RegisterKeys};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, RenderSystems};
use crate::foundation::values::wrap_degrees;
use crate::raster::{Camera, Lens, Light, RenderView};
use crate::scene::schema::{Background, CameraDef, LightDef};
use bevy::color::ColorToPacked;
use bevy::prelude::*;
use serde_json::{Map, Value, json};

/// Orbit speed of the camera keys, degrees per second.
const ORBIT_DEG_PER_S: f32 = 60.0;
/// Zoom speed of the camera keys: the distance changes by this factor per second.
const ZOOM_PER_S: f32 = 2.0;
/// Turning speed of the light keys, degrees per second.
const LIGHT_DEG_PER_S: f32 = 60.0;
/// The camera never pitches past this, in degrees, so that it never flips over the pole.
const MAX_PITCH_DEG: f32 = 89.0;

/// Camera keys: (key, action, yaw sign, pitch sign, zoom sign).
const CAMERA_KEYS: [(KeyCode, &str, f32, f32, f32); 6] = [
    (KeyCode::ArrowLeft, "orbit the camera left (Shift: fly left)", -1.0, 0.0, 0.0),
    (KeyCode::ArrowRight, "orbit the camera right (Shift: fly right)", 1.0, 0.0, 0.0),
    (KeyCode::ArrowUp, "orbit the camera up (Shift: fly forward)", 0.0, 1.0, 0.0),
    (KeyCode::ArrowDown, "orbit the camera down (Shift: fly back)", 0.0, -1.0, 0.0),
    (KeyCode::PageUp, "move the camera nearer", 0.0, 0.0, -1.0),
    (KeyCode::PageDown, "move the camera farther", 0.0, 0.0, 1.0),
];

/// Light keys: (key, action, azimuth sign, elevation sign).
const LIGHT_KEYS: [(KeyCode, &str, f32, f32); 4] = [
    (KeyCode::KeyJ, "turn the light left", -1.0, 0.0),
    (KeyCode::KeyL, "turn the light right", 1.0, 0.0),
    (KeyCode::KeyI, "raise the light", 0.0, 1.0),
    (KeyCode::KeyK, "lower the light", 0.0, -1.0),
];

/// The orbiting camera of the scene.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct CameraParams {
    /// The point orbited and looked at, metres.
    pub target: Vec3,
    /// Angle about +y from +z to the eye, degrees.
    pub yaw_deg: f32,
    /// Angle of the eye above the target's horizontal plane, degrees, within +-89.
    pub pitch_deg: f32,
    /// Distance from target to eye, metres.
    pub distance: f32,
    /// Vertical field of view, degrees.
    pub fov_deg: f32,
    /// Near clipping distance, metres.
    pub near: f32,
    /// Far clipping distance, metres.
    pub far: f32,
    /// How fast Shift and the arrows fly the camera (eye and target together, level with the
    /// ground), metres per second.
    pub fly_speed_m_s: f32,
    /// Whether the camera follows the scene's first focus point (an animal's body): its target
    /// moves as the point does, so that the view keeps its offset and turns as the user turns it.
    pub follow: bool,
}

impl From<&CameraDef> for CameraParams {
    fn from(def: &CameraDef) -> Self {
        let offset = def.position.0 - def.look_at.0;
        let distance = offset.length();
        Self {
            target: def.look_at.0,
            yaw_deg: offset.x.atan2(offset.z).to_degrees(),
            pitch_deg: (offset.y / distance).clamp(-1.0, 1.0).asin().to_degrees().clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG),
            distance,
            fov_deg: def.fov_deg.0,
            near: def.near.0,
            far: def.far.0,
            fly_speed_m_s: def.fly_speed_m_s.0,
            follow: def.follow,
        }
    }
}

/// Where the followed point was when the camera last moved with it.
#[derive(Component, Debug, Default)]
struct Followed(Option<Vec3>);

/// The key that switches following on and off.
const FOLLOW_KEY: KeyCode = KeyCode::Home;

impl CameraParams {
    /// The eye position, metres.
    pub fn eye(&self) -> Vec3 {
        self.target
            + self.distance * unit_from_angles(self.yaw_deg, self.pitch_deg.clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG))
    }

    /// The camera turned by `yaw_deg` and `pitch_deg` about its target (orbiting).
    pub fn orbited(&self, yaw_deg: f32, pitch_deg: f32) -> Self {
        let yaw_deg = wrap_degrees(self.yaw_deg + yaw_deg);
        let pitch_deg = (self.pitch_deg + pitch_deg).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
        Self { yaw_deg, pitch_deg, ..self.clone() }
    }

    /// The camera turned by `yaw_deg` and `pitch_deg` about its eye instead of its target:
    /// the eye stays, and the view turns as a head does (looking around while flying).
    pub fn looked_around(&self, yaw_deg: f32, pitch_deg: f32) -> Self {
        let turned = self.orbited(yaw_deg, pitch_deg);
        let target = self.eye() - self.distance * unit_from_angles(turned.yaw_deg, turned.pitch_deg);
        Self { target, ..turned }
    }

    /// The rasterizer's camera, with edited values brought back into their valid ranges.
    pub fn camera(&self) -> Camera {
        let near = self.near.max(1e-4);
        Camera {
            eye: self.eye(),
            target: self.target,
            lens: Lens::FieldOfView(self.fov_deg.clamp(1.0, 179.0).to_radians()),
            near,
            far: self.far.max(near * 2.0),
        }
    }
}

/// The unit vector at `azimuth_deg` about +y (0 = +z, 90 = +x) and `elevation_deg` above the
/// xz plane.
fn unit_from_angles(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

/// The directional light of the scene.
#[derive(Component, Reflect, Debug, Clone, PartialEq)]
#[reflect(Component)]
pub struct LightParams {
    /// Where the light comes from: degrees about +y, 0 = from +z, 90 = from +x.
    pub azimuth_deg: f32,
    /// Where the light comes from: degrees above the horizon.
    pub elevation_deg: f32,
    /// Diffuse coefficient, 0 to 1.
    pub diffuse: f32,
    /// Least intensity, 0 to 1.
    pub ambient: f32,
}

impl From<&LightDef> for LightParams {
    fn from(def: &LightDef) -> Self {
        let towards_light = -def.direction.0.normalize();
        Self {
            azimuth_deg: towards_light.x.atan2(towards_light.z).to_degrees(),
            elevation_deg: towards_light.y.clamp(-1.0, 1.0).asin().to_degrees(),
            diffuse: def.diffuse.0,
            ambient: def.ambient.0,
        }
    }
}

impl LightParams {
    /// The rasterizer's light, with coefficients brought back into `[0, 1]`.
    pub fn light(&self) -> Light {
        Light {
            direction: -unit_from_angles(self.azimuth_deg, self.elevation_deg),
            diffuse: self.diffuse.clamp(0.0, 1.0),
            fill: 0.0,
            ambient: self.ambient.clamp(0.0, 1.0),
        }
    }
}

impl DumpState for CameraParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("position".into(), json!(self.eye().to_array()));
        out.insert("target".into(), json!(self.target.to_array()));
        out.insert("fov_deg".into(), json!(self.fov_deg));
        out.insert("fly_speed_m_s".into(), json!(self.fly_speed_m_s));
        out.insert("follow".into(), json!(self.follow));
    }
}

impl DumpState for LightParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        let light = self.light();
        out.insert("direction".into(), json!(light.direction.to_array()));
        out.insert("azimuth_deg".into(), json!(self.azimuth_deg));
        out.insert("elevation_deg".into(), json!(self.elevation_deg));
        out.insert("diffuse".into(), json!(light.diffuse));
        out.insert("ambient".into(), json!(light.ambient));
    }
}

/// Camera and light parameters, controls and the render view.
#[derive(Default)]
pub struct ViewPlugin;

impl Plugin for ViewPlugin {
    fn build(&self, app: &mut App) {
        let camera_help = CAMERA_KEYS.map(|(key, action, ..)| KeyHelp { key, action, scope: KeyScope::Global });
        let light_help = LIGHT_KEYS.map(|(key, action, ..)| KeyHelp { key, action, scope: KeyScope::Global });
        app.register_params::<CameraParams>()
            .register_params::<LightParams>()
            .register_dump::<CameraParams>()
            .register_dump::<LightParams>()
            .register_keys(&camera_help)
            .register_keys(&light_help)
            .register_keys(&[KeyHelp {
                key: FOLLOW_KEY,
                action: "camera follows the animal / stays",
                scope: KeyScope::Global,
            }])
            .add_observer(params_of_camera_section)
            .add_observer(params_of_light_section)
            .add_systems(Update, (orbit_camera, turn_light, switch_follow).in_set(ControlSystems::Input))
            .add_systems(Update, follow_focus.after(ControlSystems::Input))
            .add_systems(PostUpdate, write_render_view.in_set(RenderSystems::Collect));
    }
}

/// Gives the scene's camera entity its parameters when it is spawned.
fn params_of_camera_section(add: On<Add, CameraDef>, sections: Query<&CameraDef>, mut commands: Commands) {
    if let Ok(def) = sections.get(add.entity) {
        commands.entity(add.entity).insert((CameraParams::from(def), Followed::default()));
    }
}

/// Gives the scene's light entity its parameters when it is spawned.
fn params_of_light_section(add: On<Add, LightDef>, sections: Query<&LightDef>, mut commands: Commands) {
    if let Ok(def) = sections.get(add.entity) {
        commands.entity(add.entity).insert(LightParams::from(def));
    }
}

/// Orbits the camera with the arrows and PageUp/PageDown; with Shift, the arrows fly it
/// instead: eye and target move together, forward and back along the horizontal direction of
/// view and sideways across it.
fn orbit_camera(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut cameras: Query<&mut CameraParams>) {
    let dt = time.delta_secs();
    let flying = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    let (mut yaw, mut pitch, mut zoom) = (0.0, 0.0, 0.0);
    for (key, _, dy, dp, dz) in CAMERA_KEYS {
        if keys.pressed(key) {
            (yaw, pitch, zoom) = (yaw + dy, pitch + dp, zoom + dz);
        }
    }
    if (yaw, pitch, zoom) == (0.0, 0.0, 0.0) {
        return;
    }
    for mut camera in &mut cameras {
        if flying {
            // Towards the target from the eye, level, and to its right.
            let towards = -unit_from_angles(camera.yaw_deg, 0.0);
            let right = towards.cross(Vec3::Y);
            let step = camera.fly_speed_m_s * dt;
            camera.target += (towards * pitch + right * yaw) * step;
            camera.distance = (camera.distance * ZOOM_PER_S.powf(zoom * dt)).max(camera.near * 2.0);
            continue;
        }
        *camera = camera.orbited(yaw * ORBIT_DEG_PER_S * dt, pitch * ORBIT_DEG_PER_S * dt);
        camera.distance = (camera.distance * ZOOM_PER_S.powf(zoom * dt)).max(camera.near * 2.0);
    }
}

fn switch_follow(keys: Res<ButtonInput<KeyCode>>, mut cameras: Query<&mut CameraParams>) {
    if keys.just_pressed(FOLLOW_KEY) {
        for mut camera in &mut cameras {
            camera.follow = !camera.follow;
        }
    }
}

/// Moves a following camera's target with the focus point, after the frame's fixed steps have
/// moved it.
fn follow_focus(mut cameras: Query<(&mut CameraParams, &mut Followed)>, foci: Query<&FocusPoint>) {
    let point = foci.iter().next().map(|focus| focus.0);
    for (mut camera, mut followed) in &mut cameras {
        if !camera.follow || point.is_none() {
            followed.0 = None;
            continue;
        }
        if let (Some(now), Some(before)) = (point, followed.0)
            && now != before
        {
            camera.target += now - before;
        }
        followed.0 = point;
    }
}

fn turn_light(keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut lights: Query<&mut LightParams>) {
    let step = LIGHT_DEG_PER_S * time.delta_secs();
    let (mut azimuth, mut elevation) = (0.0, 0.0);
    for (key, _, da, de) in LIGHT_KEYS {
        if keys.pressed(key) {
            (azimuth, elevation) = (azimuth + da, elevation + de);
        }
    }
    if (azimuth, elevation) == (0.0, 0.0) {
        return;
    }
    for mut light in &mut lights {
        light.azimuth_deg = wrap_degrees(light.azimuth_deg + azimuth * step);
        light.elevation_deg = (light.elevation_deg + elevation * step).clamp(-90.0, 90.0);
    }
}

fn write_render_view(
    cameras: Query<&CameraParams>,
    lights: Query<&LightParams>,
    background: Res<Background>,
    mut view: ResMut<RenderView>,
) {
    if let Some(camera) = cameras.iter().next() {
        view.camera = camera.camera();
    }
    if let Some(light) = lights.iter().next() {
        view.light = light.light();
    }
    view.background = background.0.to_u8_array();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::foundation::values::{FieldOfView, Point, PositiveMetres, UnitInterval};

    #[test]
    fn camera_params_reproduce_the_file_camera() {
        let def = CameraDef {
            position: Point(Vec3::new(3.0, 2.0, -4.0)),
            look_at: Point(Vec3::new(0.5, 0.5, 0.5)),
            fov_deg: FieldOfView(50.0),
            near: PositiveMetres(0.1),
            far: PositiveMetres(100.0),
            fly_speed_m_s: PositiveMetres(10.0),
            follow: false,
        };
        let camera = CameraParams::from(&def).camera();
        assert!((camera.eye - def.position.0).length() < 1e-5, "{}", camera.eye);
        assert_eq!(camera.target, def.look_at.0);
    }

    #[test]
    fn looking_around_keeps_the_eye_and_turns_the_view() {
        let camera = CameraParams {
            target: Vec3::new(3.0, 1.0, -2.0),
            yaw_deg: 20.0,
            pitch_deg: 30.0,
            distance: 12.0,
            fov_deg: 60.0,
            near: 0.1,
            far: 500.0,
            fly_speed_m_s: 30.0,
            follow: false,
        };
        let turned = camera.looked_around(-90.0, -10.0);
        assert!((turned.eye() - camera.eye()).length() < 1e-4, "the eye stays");
        assert_eq!((turned.yaw_deg, turned.pitch_deg, turned.distance), (-70.0, 20.0, 12.0));
        // Yaw down by 90 degrees turns the horizontal direction of view a quarter turn to
        // the right (clockwise seen from above).
        let view = |c: &CameraParams| (c.target - c.eye()).with_y(0.0).normalize();
        let right = view(&camera).cross(Vec3::Y);
        assert!((view(&turned) - right).length() < 1e-4, "{} vs {right}", view(&turned));
        assert_eq!(camera.looked_around(0.0, 80.0).pitch_deg, MAX_PITCH_DEG);
    }

    #[test]
    fn light_angles_reproduce_the_file_direction() {
        let def = LightDef {
            direction: Point(Vec3::new(-0.4, -1.0, -0.3)),
            diffuse: UnitInterval(0.8),
            ambient: UnitInterval(0.1),
        };
        let light = LightParams::from(&def).light();
        assert!((light.direction - def.direction.0.normalize()).length() < 1e-5);
        let from_x = LightParams { azimuth_deg: 90.0, elevation_deg: 0.0, diffuse: 1.0, ambient: 0.0 };
        assert!((from_x.light().direction - Vec3::NEG_X).length() < 1e-6);
    }
}
