//! The primary window's pixels on the display server: a `softbuffer` surface on the handles
//! `bevy_winit` puts on the window entity. No GPU and no graphics driver take part; on X11 the
//! buffer is shared memory the server reads from.

use bevy::prelude::*;
use bevy::window::{RawHandleWrapper, ThreadLockedRawWindowHandleWrapper};
use softbuffer::{Buffer, Context, Surface};
use std::num::NonZeroU32;

type Handle = ThreadLockedRawWindowHandleWrapper;

/// The surface of the primary window, made when the window first has its handles. Non-send
/// data: systems that use it run on the main thread, where window handles may be used on every
/// platform.
#[derive(Default)]
pub struct WindowSurface {
    surface: Option<Surface<Handle, Handle>>,
    /// The size the surface's buffers have, in physical pixels.
    size: UVec2,
}

/// Why the window could not be shown.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw into the window: {0}")]
pub struct SurfaceError(#[from] softbuffer::SoftBufferError);

impl WindowSurface {
    /// The buffer of the next picture, `size` pixels (`0RGB`), made or resized as needed.
    /// Its contents are unspecified: the caller writes every pixel.
    pub fn buffer(
        &mut self,
        handles: &RawHandleWrapper,
        size: UVec2,
    ) -> Result<Option<Buffer<'_, Handle, Handle>>, SurfaceError> {
        let (Some(width), Some(height)) = (NonZeroU32::new(size.x), NonZeroU32::new(size.y)) else {
            return Ok(None);
        };
        let surface = match &mut self.surface {
            Some(surface) => surface,
            empty => empty.insert(new_surface(handles)?),
        };
        if self.size != size {
            surface.resize(width, height)?;
            self.size = size;
        }
        Ok(Some(surface.buffer_mut()?))
    }
}

/// A surface on the window of `handles`.
#[allow(unsafe_code)]
fn new_surface(handles: &RawHandleWrapper) -> Result<Surface<Handle, Handle>, softbuffer::SoftBufferError> {
    // SAFETY: window handles may only be used where the platform allows. `WindowSurface` is
    // non-send data, so this runs on the main thread, where every platform allows it; the
    // handles keep a reference to the window, so it outlives the surface.
    let (display, window) = unsafe { (handles.get_handle(), handles.get_handle()) };
    let context = Context::new(display)?;
    Surface::new(&context, window)
}
