//! The detector and the pose on synthetic sequences with known poses: a marker on a table seen
//! by a camera circling it, with noise, blur, changing light, occlusions and frames looking
//! away.

use canopy_vision::camera::{Distortion, Intrinsics};
use canopy_vision::detect::Settings;
use canopy_vision::dictionary::Dictionary;
use canopy_vision::evaluate::{Evaluation, evaluate};
use canopy_vision::synth::SequenceSettings;

fn sequence(camera: Intrinsics, dictionary: &str, id: u32) -> SequenceSettings {
    SequenceSettings {
        camera,
        dictionary: Dictionary::named(dictionary).unwrap(),
        id,
        side_m: 0.1,
        frames: 60,
        distance_m: [0.3, 0.7],
        seed: 7,
        noise: 4.0,
        max_blur_px: 1.2,
        lighting: true,
        occlusion: true,
        look_away: true,
    }
}

fn check(name: &str, figures: &Evaluation) {
    println!("{name}: {figures:?}, detection rate {:.3}", figures.detection_rate());
    assert!(figures.whole[0] >= 30 && figures.absent >= 3, "{name}: the sequence shows too little: {figures:?}");
    assert_eq!(figures.false_detections, 0, "{name}");
    assert!(figures.detection_rate() >= 0.95, "{name}: {figures:?}");
    assert!(figures.corner_px[0] < 0.3, "{name}: corner error {:?}", figures.corner_px);
    assert!(figures.position_rel[1] < 0.01, "{name}: position error {:?}", figures.position_rel);
    assert!(figures.angle_deg[1] < 1.0, "{name}: angle error {:?}", figures.angle_deg);
}

#[test]
fn vga_6x6_with_noise_blur_light_and_occlusion() {
    let camera = Intrinsics::pinhole([640, 480], 60.0);
    check("640x480 6x6_250", &evaluate(&sequence(camera, "6x6_250", 23), &Settings::default()));
}

#[test]
fn hd_4x4_through_a_distorting_lens() {
    let camera = Intrinsics {
        distortion: Distortion([-0.25, 0.08, 0.0008, -0.0005, -0.01, 0.0, 0.0, 0.0]),
        ..Intrinsics::pinhole([1280, 720], 55.0)
    };
    check("1280x720 4x4_50", &evaluate(&sequence(camera, "4x4_50", 7), &Settings::default()));
}

#[test]
fn vga_original_and_5x5() {
    let camera = Intrinsics::pinhole([640, 480], 60.0);
    check("640x480 aruco_original", &evaluate(&sequence(camera, "aruco_original", 300), &Settings::default()));
    check("640x480 5x5_100", &evaluate(&sequence(camera, "5x5_100", 42), &Settings::default()));
}
