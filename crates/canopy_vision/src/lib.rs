//! Canopy's marker tracking, pure and independent of Bevy's world: the camera images' side of
//! augmented reality.
//!
//! | module | what it holds |
//! |---|---|
//! | [`gray`] | grey images, made from RGB(A) pixels, sampled between pixel centres |
//! | [`contour`] | adaptive threshold, dark regions' outer boundaries, polygon simplification |
//! | [`dictionary`] | OpenCV's predefined ArUco and AprilTag dictionaries and matching with error correction |
//! | [`detect`] | the marker detector: candidates, cells, ids, sub-pixel corners |
//! | [`calibrate`] | a camera calibrated from views of a flat target: Zhang's closed form refined by Levenberg-Marquardt |
//! | [`camera`] | the calibrated camera: pinhole with OpenCV's distortion model |
//! | [`fit`] | a camera frame fitted into a view of another size, its distortion removed |
//! | [`pose`] | a square marker's pose: both planar solutions (IPPE) refined on reprojection error |
//! | [`grid`] | ArUco grid boards in OpenCV's layout, printable |
//! | [`charuco`] | ChArUco boards in OpenCV's layout, printable; their chessboard corners found between their markers |
//! | [`saddle`] | a chessboard corner placed to a fraction of a pixel (OpenCV's `cornerSubPix`) |
//! | [`board`] | either board, and its pose from every point of it found |
//! | [`steady`] | poses followed from frame to frame without flipping between the two solutions |
//! | [`synth`] | printable markers and synthetic camera frames with known poses |
//! | [`sweep`] | harder frames swept one condition at a time: detection rate and pose error at each step |
//! | [`least_squares`] | Levenberg-Marquardt on small problems, the Jacobian by central differences |
//! | [`evaluate`] | the detector and pose measured against a synthetic sequence's known answers |
//!
//! Pixel coordinates are OpenCV's throughout: pixel `(x, y)`'s centre is at `(x, y)`.

pub mod board;
pub mod calibrate;
pub mod camera;
pub mod charuco;
pub mod contour;
pub mod detect;
mod dictionaries;
pub mod dictionary;
pub mod evaluate;
pub mod fit;
pub mod gray;
pub mod grid;
pub mod least_squares;
mod linear;
pub mod pose;
pub mod saddle;
pub mod steady;
pub mod sweep;
pub mod synth;

pub use camera::{Distortion, Intrinsics};
pub use detect::{Marker, Scratch, Settings, detect};
pub use dictionary::Dictionary;
pub use gray::Gray;
pub use pose::{Pose, PoseEstimate};
