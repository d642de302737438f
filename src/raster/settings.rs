//! The scene's `render` entity: shading mode and shadows as parameters and keys, switched at
//! run time.
//!
//! Parameters: `render.shading` (`flat`, `gouraud` or `phong`), `render.shadows` and
//! `render.pcf` (true or false). Keys: V cycles the shading mode, H switches shadows. The
//! scene's distance fog and shadow distance are settings of the file alone.

use super::{Fog, RenderSettings, RenderView, Shading};
use crate::foundation::dump::{DumpState, RegisterDump};
use crate::foundation::keys::{KeyHelp, KeyScope, RegisterKeys};
use crate::foundation::params::RegisterParams;
use crate::foundation::schedule::{ControlSystems, RenderSystems};
use crate::scene::schema::{FogDef, RenderDef};
use bevy::color::ColorToPacked;
use bevy::prelude::*;
use serde_json::{Map, Value, json};

/// Key that cycles the shading mode.
const SHADING_KEY: KeyCode = KeyCode::KeyV;
/// Key that switches shadows on and off.
const SHADOWS_KEY: KeyCode = KeyCode::KeyH;

/// How the scene is drawn; the parameters of the `render` entity.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component)]
pub struct RenderParams {
    /// The lighting computation.
    pub shading: Shading,
    /// Whether the light casts shadows.
    pub shadows: bool,
    /// Whether shadow edges are filtered (bilinear percentage-closer filtering).
    pub pcf: bool,
    /// The scene's distance fog, if any (a scene setting, not a parameter).
    #[reflect(ignore)]
    pub fog: Option<FogDef>,
    /// The scene's shadow distance in metres, if any (a scene setting).
    #[reflect(ignore)]
    pub shadow_distance_m: Option<f32>,
}

impl From<&RenderDef> for RenderParams {
    fn from(def: &RenderDef) -> Self {
        Self {
            shading: def.shading,
            shadows: def.shadows,
            pcf: def.pcf,
            fog: def.fog,
            shadow_distance_m: def.shadow_distance_m.map(|d| d.0),
        }
    }
}

impl DumpState for RenderParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        out.insert("shading".into(), json!(self.shading.key()));
        out.insert("shadows".into(), json!(self.shadows));
        out.insert("pcf".into(), json!(self.pcf));
        let fog = self.fog.map(|fog| json!({ "start_m": fog.start_m.0, "depth_m": fog.depth_m.0 }));
        out.insert("fog".into(), fog.unwrap_or(Value::Null));
        out.insert("shadow_distance_m".into(), json!(self.shadow_distance_m));
    }
}

/// The `render` entity's parameters, keys and their effect on the [`RenderView`].
#[derive(Default)]
pub struct RenderSettingsPlugin;

impl Plugin for RenderSettingsPlugin {
    fn build(&self, app: &mut App) {
        let scope = KeyScope::Global;
        app.register_params::<RenderParams>()
            .register_dump::<RenderParams>()
            .register_keys(&[
                KeyHelp { key: SHADING_KEY, action: "next shading mode (flat, Gouraud, Phong)", scope },
                KeyHelp { key: SHADOWS_KEY, action: "switch shadows on or off", scope },
            ])
            .add_observer(params_of_render_section)
            .add_systems(Update, switch_render_settings.in_set(ControlSystems::Input))
            .add_systems(PostUpdate, write_render_settings.in_set(RenderSystems::Collect));
    }
}

/// Gives the scene's `render` entity its parameters when it is spawned.
fn params_of_render_section(add: On<Add, RenderDef>, sections: Query<&RenderDef>, mut commands: Commands) {
    if let Ok(def) = sections.get(add.entity) {
        commands.entity(add.entity).insert(RenderParams::from(def));
    }
}

fn switch_render_settings(keys: Res<ButtonInput<KeyCode>>, mut params: Query<&mut RenderParams>) {
    for mut params in &mut params {
        if keys.just_pressed(SHADING_KEY) {
            params.shading = params.shading.next();
        }
        if keys.just_pressed(SHADOWS_KEY) {
            params.shadows = !params.shadows;
        }
    }
}

fn write_render_settings(params: Query<&RenderParams>, mut view: ResMut<RenderView>) {
    if let Some(params) = params.iter().next() {
        let fog = params.fog.map(|fog| Fog {
            color: fog.color.map(|c| c.0.to_u8_array_no_alpha()),
            start_m: fog.start_m.0,
            end_m: fog.start_m.0 + fog.depth_m.0,
        });
        view.settings = RenderSettings {
            shading: params.shading,
            shadows: params.shadows,
            pcf: params.pcf,
            fog,
            shadow_distance_m: params.shadow_distance_m,
            ..view.settings
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shading_cycles_through_all_three_modes() {
        let mut mode = Shading::Flat;
        let mut seen = vec![];
        for _ in 0..3 {
            seen.push(mode);
            mode = mode.next();
        }
        assert_eq!(seen, Shading::ALL);
        assert_eq!(mode, Shading::Flat);
    }

    #[test]
    fn the_section_defaults_to_gouraud_with_shadows() {
        let def: RenderDef = serde_yaml::from_str("pcf: false").unwrap();
        assert_eq!(def, RenderDef { shading: Shading::Gouraud, shadows: true, pcf: false, ..RenderDef::default() });
        let error = serde_yaml::from_str::<RenderDef>("shading: toon").unwrap_err().to_string();
        assert!(error.contains("unknown variant `toon`"), "{error}");
    }

    #[test]
    fn fog_has_the_background_colour_unless_given_one() {
        let mut app = App::new();
        app.init_resource::<RenderView>().add_systems(Update, write_render_settings);
        let def: RenderDef = serde_yaml::from_str("fog: { start_m: 20, depth_m: 60 }").unwrap();
        app.world_mut().spawn(RenderParams::from(&def));
        app.update();
        let fog = app.world().resource::<RenderView>().settings.fog;
        assert_eq!(fog, Some(Fog { color: None, start_m: 20.0, end_m: 80.0 }), "the frame's background");
        let coloured: RenderDef = serde_yaml::from_str("fog: { start_m: 5, depth_m: 5, color: '#ff0000' }").unwrap();
        assert_eq!(coloured.fog.and_then(|f| f.color).map(|c| c.0.to_u8_array_no_alpha()), Some([255, 0, 0]));
        for bad in ["fog: { start_m: 0, depth_m: 5 }", "fog: { start_m: 5 }", "fog: { start_m: 5, depth_m: -1 }"] {
            assert!(serde_yaml::from_str::<RenderDef>(bad).is_err(), "{bad}");
        }
    }
}
