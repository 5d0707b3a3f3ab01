//! The `[camera]` section: how a filmed track maps to the machine frame (frame rate, image
//! size, scale/origin/axes or four reference points, the marker's offset on the parcel).

use super::bounds::Bound;
use super::Problem;
use divertsim_core::analysis::measurement::track::CameraMap;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The camera that filmed a track (`divertsim track`, `compare`, `calibrate`). Default: the
/// paper's set-up, a camera square to the belt at 304 px per 0.6 m, 640 × 480 px, 25 fps.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are schema descriptions: [m] is a unit
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, divertsim_keys::Keys)]
#[serde(deny_unknown_fields, default)]
#[keys(section = "camera", default)]
pub struct CameraConfig {
    /// Frames per second (for a track given by frame number) [1/s].
    #[key(default = 25.0, range = Bound::open_closed(0.0, 1e5, "1/s"))]
    pub frame_rate: f64,
    /// Image width and height [px]; a point outside is an error.
    #[key(default = [640.0, 480.0])]
    #[key(at = "[]", name = IMAGE_SIZE, range = Bound::closed(1.0, 1e6, "px"))]
    pub image_size: [f64; 2],
    /// Pixels per metre on the belt plane (a camera square to the belt), > 0.
    /// Default 304/0.6 (the paper's ruler).
    #[key(default = 304.0 / 0.6)]
    pub px_per_m: f64,
    /// The pixel of the machine origin (the arm pivot) [px].
    #[key(default = [40.0, 440.0])]
    pub origin_px: [f64; 2],
    /// The pixel direction of machine +x (downstream).
    #[key(default = [1.0, 0.0])]
    pub x_axis_px: [f64; 2],
    /// The pixel direction of machine +y (across, away from the pivot). Image rows grow
    /// downwards.
    #[key(default = [0.0, -1.0])]
    pub y_axis_px: [f64; 2],
    /// For a camera not square to the belt: four points [u, v, x, y] (pixels, then machine
    /// metres) on the belt plane; they define a homography and replace px_per_m, origin_px
    /// and the axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_points: Option<Vec<[f64; 4]>>,
    /// The marker's offset from the parcel's centre, in the parcel's own axes (along its
    /// length, across it) [m].
    #[key(at = "[]", name = MARKER_OFFSET, range = Bound::closed(-5.0, 5.0, "m"))]
    pub marker_offset: [f64; 2],
}

impl CameraConfig {
    pub fn is_default(&self) -> bool {
        *self == CameraConfig::default()
    }

    /// The pixel-to-machine map.
    pub fn map(&self) -> Result<CameraMap, Problem> {
        match &self.reference_points {
            Some(p) if p.len() == 4 => {
                let pairs = [0, 1, 2, 3].map(|k| ([p[k][0], p[k][1]], [p[k][2], p[k][3]]));
                CameraMap::from_points(&pairs)
                    .map_err(|e| Problem::new("camera.reference_points", e.to_string()))
            }
            Some(p) => Err(Problem::new(
                "camera.reference_points",
                format!("{} points; allowed: exactly 4", p.len()),
            )),
            None => CameraMap::square(
                self.px_per_m,
                self.origin_px,
                self.x_axis_px,
                self.y_axis_px,
            )
            .map_err(|e| {
                let key = match e {
                    divertsim_core::analysis::measurement::track::CameraError::Scale => {
                        "camera.px_per_m"
                    }
                    _ => "camera.x_axis_px",
                };
                Problem::new(key, e.to_string())
            }),
        }
    }
}

/// The checks of `[camera]` beyond its ranges (those are checked by key path).
pub fn validate(c: &CameraConfig, problems: &mut Vec<Problem>) {
    let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if let Some(p) = &c.reference_points {
        if p.iter().any(|r| !fin(r)) {
            problems.push(Problem::new(
                "camera.reference_points",
                "every value must be a finite number",
            ));
            return;
        }
    }
    if !fin(&c.origin_px) {
        problems.push(Problem::new("camera.origin_px", "must be finite"));
        return;
    }
    if let Err(p) = c.map() {
        problems.push(p);
    }
}
