//! The app-wide requests that input sends and the scene, the renderer and the window answer.

use bevy::prelude::*;

/// Asks for the scene to be read from disk again.
#[derive(Message, Debug, Clone, Copy)]
pub struct ReloadScene;

/// Asks for a screenshot of the 3D view.
#[derive(Message, Debug, Clone, Copy)]
pub struct SaveScreenshot;

/// A click on the 3D view: where, in normalized device coordinates (x right, y up, -1 to 1),
/// and the view's width / height ratio.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct ViewClicked {
    /// The point clicked.
    pub ndc: Vec2,
    /// Width / height of the view.
    pub aspect: f32,
}

/// Asks the window to select (show the parameters of) the scene entity with this name.
#[derive(Message, Debug, Clone, PartialEq, Eq)]
pub struct SelectEntity(pub String);

/// Registers the messages.
pub(crate) fn add_messages(app: &mut App) {
    app.add_message::<ReloadScene>()
        .add_message::<SaveScreenshot>()
        .add_message::<ViewClicked>()
        .add_message::<SelectEntity>();
}
