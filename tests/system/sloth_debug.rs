//! The sloth's debug view: at the end of the study's pole, where the leading feet's searches
//! refuse every grip, each search's crosses are drawn where its probes are, in the colour of
//! its verdict, and nothing of the view is drawn while it is off.

use crate::common::{count_pixels, live_app, path};
use bevy::math::UVec2;
use canopy::foundation::params::{ParamValue, set_param};
use canopy::raster::lines::pixel_of;
use canopy::raster::plugin::{RasterTarget, RenderPolicy, RenderView};
use canopy::sloth::SlothBody;
use canopy::sloth::debug::{CHAIN, TAKEN, refused};

const SIZE: UVec2 = UVec2::new(640, 360);

/// Draws a frame and returns it.
fn frame(app: &mut bevy::app::App) -> canopy::raster::Framebuffer {
    app.world_mut().resource_mut::<RenderPolicy>().requested = true;
    app.update();
    app.world().resource::<RasterTarget>().framebuffer.clone()
}

#[test]
fn the_debug_view_draws_every_probe_where_it_is_in_its_verdicts_colour() {
    let mut app = live_app(&path("scenes/sloth/pole.yaml"), SIZE);
    // Walked to the end of the pole, the sloth is blocked there.
    for _ in 0..(17 * 60) {
        app.update();
    }
    let off = frame(&mut app);
    assert_eq!(count_pixels(&off, CHAIN), 0, "no debug lines while the view is off");
    for (name, value) in [("sloth.debug_view", true), ("sloth.debug_on_top", true)] {
        set_param(app.world_mut(), name, ParamValue::Bool(value)).unwrap();
    }
    let on = frame(&mut app);
    let world = app.world_mut();
    let view = *world.resource::<RenderView>();
    let body = world.query::<&SlothBody>().single(world).unwrap();
    assert!(body.sloth.blocked.is_some(), "blocked at the end of the pole");
    let probes: Vec<_> = body.sloth.probes.iter().flatten().collect();
    let refusals: Vec<_> = probes.iter().filter_map(|p| p.refusal).collect();
    assert!(!refusals.is_empty(), "the leading feet's last searches refused grips");
    // Every refusal's colour is in the frame; the last probe of each search (drawn last) shows
    // its own colour at its place.
    for refusal in &refusals {
        assert!(count_pixels(&on, refused(*refusal)) > 0, "{refusal:?} is drawn");
    }
    for search in body.sloth.probes.iter().filter(|s| !s.is_empty()) {
        let last = search.last().unwrap();
        let rgba = last.refusal.map_or(TAKEN, refused);
        let at = pixel_of(&view, SIZE, last.grip).expect("in front of the camera");
        let near = (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))).any(|(dx, dy)| {
            let (x, y) = (at.x as i32 + dx, at.y as i32 + dy);
            (0..SIZE.x as i32).contains(&x) && (0..SIZE.y as i32).contains(&y) && on.pixel(x as u32, y as u32) == rgba
        });
        assert!(near, "the probe at {} shows {rgba:?} at pixel {at}", last.grip);
    }
    assert!(count_pixels(&on, CHAIN) > 50, "the limb chains are drawn");
}
