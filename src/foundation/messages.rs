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

/// A drag with the primary button on the 3D view, for what can be grabbed there: where the
/// pointer is, in normalized device coordinates as in [`ViewClicked`].
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct ViewDragged {
    /// Whether the drag starts (at the point pressed), goes on or ends.
    pub phase: DragPhase,
    /// The pointer.
    pub ndc: Vec2,
    /// Width / height of the view.
    pub aspect: f32,
}

/// A drag's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DragPhase {
    /// The button went down here and the pointer started to move.
    Start,
    /// The pointer moved with the button held.
    Move,
    /// The button was let go.
    End,
}

/// Whether something in the scene holds the view's drag (a body being dragged): the camera
/// stays still meanwhile.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ViewGrab {
    /// A drag is held.
    pub held: bool,
}

/// Asks the window to select (show the parameters of) the scene entity with this name.
#[derive(Message, Debug, Clone, PartialEq, Eq)]
pub struct SelectEntity(pub String);

/// A hand took hold of a support at `point` (metres): what hangs from the support within reach
/// of it may be shaken loose. Animals send it; what hangs answers it.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct HandPlanted {
    /// Where the hand grips.
    pub point: Vec3,
}

/// Registers the messages.
pub(crate) fn add_messages(app: &mut App) {
    app.add_message::<ReloadScene>()
        .add_message::<SaveScreenshot>()
        .add_message::<ViewClicked>()
        .add_message::<ViewDragged>()
        .add_message::<SelectEntity>()
        .add_message::<HandPlanted>()
        .init_resource::<ViewGrab>();
}
