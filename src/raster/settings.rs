//! The scene's `render` entity: shading mode and shadows as parameters, keys and a scene
//! section, switched at run time.
//!
//! Parameters: `render.shading` (`flat`, `gouraud` or `phong`), `render.shadows` and
//! `render.pcf` (true or false). Keys: V cycles the shading mode, H switches shadows.

use super::{RenderSettings, RenderSystems, RenderView, Shading};
use crate::controls::{KeyHelp, KeyScope, RegisterKeys};
use crate::dump::{DumpState, RegisterDump};
use crate::params::RegisterParams;
use crate::schedule::ControlSystems;
use bevy::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};

/// Key that cycles the shading mode.
const SHADING_KEY: KeyCode = KeyCode::KeyV;
/// Key that switches shadows on and off.
const SHADOWS_KEY: KeyCode = KeyCode::KeyH;

/// The shading modes as a scene value and parameter.
#[derive(Reflect, Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShadingMode {
    /// One intensity per triangle.
    Flat,
    /// Intensity per vertex, interpolated.
    #[default]
    Gouraud,
    /// Normal per pixel.
    Phong,
}

impl ShadingMode {
    /// The rasterizer's mode.
    pub fn shading(self) -> Shading {
        match self {
            ShadingMode::Flat => Shading::Flat,
            ShadingMode::Gouraud => Shading::Gouraud,
            ShadingMode::Phong => Shading::Phong,
        }
    }

    /// The mode after this one: flat, Gouraud, Phong, flat...
    fn next(self) -> Self {
        match self {
            ShadingMode::Flat => ShadingMode::Gouraud,
            ShadingMode::Gouraud => ShadingMode::Phong,
            ShadingMode::Phong => ShadingMode::Flat,
        }
    }
}

/// The `render` section of a scene file.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderDef {
    /// Shading mode: `flat`, `gouraud` (the default) or `phong`.
    pub shading: ShadingMode,
    /// Whether the light casts shadows (on by default).
    pub shadows: bool,
    /// Whether shadow edges are filtered (on by default).
    pub pcf: bool,
}

impl Default for RenderDef {
    fn default() -> Self {
        Self { shading: ShadingMode::Gouraud, shadows: true, pcf: true }
    }
}

/// How the scene is drawn; the parameters of the `render` entity.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component)]
pub struct RenderParams {
    /// The lighting computation.
    pub shading: ShadingMode,
    /// Whether the light casts shadows.
    pub shadows: bool,
    /// Whether shadow edges are filtered (bilinear percentage-closer filtering).
    pub pcf: bool,
}

impl From<&RenderDef> for RenderParams {
    fn from(def: &RenderDef) -> Self {
        Self { shading: def.shading, shadows: def.shadows, pcf: def.pcf }
    }
}

impl DumpState for RenderParams {
    fn dump(&self, out: &mut Map<String, Value>) {
        let shading = match self.shading {
            ShadingMode::Flat => "flat",
            ShadingMode::Gouraud => "gouraud",
            ShadingMode::Phong => "phong",
        };
        out.insert("shading".into(), json!(shading));
        out.insert("shadows".into(), json!(self.shadows));
        out.insert("pcf".into(), json!(self.pcf));
    }
}

/// The `render` entity's parameters, keys and their effect on the [`RenderView`].
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
            .add_systems(Update, switch_render_settings.in_set(ControlSystems::Input))
            .add_systems(PostUpdate, write_render_settings.in_set(RenderSystems::Collect));
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
        view.settings = RenderSettings {
            shading: params.shading.shading(),
            shadows: params.shadows,
            pcf: params.pcf,
            ..view.settings
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shading_cycles_through_all_three_modes() {
        let mut mode = ShadingMode::Flat;
        let mut seen = vec![];
        for _ in 0..3 {
            seen.push(mode.shading());
            mode = mode.next();
        }
        assert_eq!(seen, Shading::ALL);
        assert_eq!(mode, ShadingMode::Flat);
    }

    #[test]
    fn the_section_defaults_to_gouraud_with_shadows() {
        let def: RenderDef = serde_yaml::from_str("pcf: false").unwrap();
        assert_eq!(def, RenderDef { shading: ShadingMode::Gouraud, shadows: true, pcf: false });
        let error = serde_yaml::from_str::<RenderDef>("shading: toon").unwrap_err().to_string();
        assert!(error.contains("unknown variant `toon`"), "{error}");
    }
}
