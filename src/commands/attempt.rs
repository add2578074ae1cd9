//! What every pick attempt of `collect` and `eval` starts from: the camera's frame of the
//! workcell, the objects still in bin 1, and the policy's view of them with its own seed.

use image::RgbImage;

use crate::grasp::PixelGrasp;
use crate::policy::Observation;
use crate::sim::{ObjectLocation, Workcell};
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// One attempt's look at the workcell, before the policy decides.
pub(crate) struct Look {
    /// The top-down camera's frame.
    pub(crate) frame: Frame,
    /// The frame's RGB as an image.
    pub(crate) rgb: RgbImage,
    /// The camera it was taken with.
    pub(crate) camera: Camera,
    /// Mask ids of the objects in bin 1.
    pub(crate) in_bin: Vec<u16>,
    /// The policy's own random stream for this attempt.
    pub(crate) attempt_seed: u64,
}

impl Look {
    /// Captures the frame of attempt `attempt` of the scene dropped with `drop_seed`;
    /// `in_bin` as [`objects_in_bin`] gives it.
    pub(crate) fn take(cell: &Workcell, in_bin: Vec<u16>, drop_seed: u64, attempt: u32) -> Self {
        let frame = cell.capture();
        let rgb = frame.to_rgb_image();
        Self {
            frame,
            rgb,
            camera: *cell.camera(),
            in_bin,
            attempt_seed: attempt_seed(drop_seed, attempt),
        }
    }

    /// What the policy sees.
    pub(crate) fn observation(&self) -> Observation<'_> {
        Observation {
            camera: &self.camera,
            frame: &self.frame,
            rgb: &self.rgb,
            in_bin: &self.in_bin,
            attempt_seed: self.attempt_seed,
        }
    }

    /// The object whose surface the camera saw at the grasp's centre (ground truth, for the
    /// records only).
    pub(crate) fn aimed_at(&self, cell: &Workcell, grasp: PixelGrasp) -> Option<String> {
        let id = self.frame.id_at(grasp.u, grasp.v);
        cell.objects()
            .iter()
            .find(|o| o.id == id)
            .map(|o| o.model.name.clone())
    }
}

/// Mask ids of the objects resting in bin 1.
pub(crate) fn objects_in_bin(cell: &Workcell) -> Vec<u16> {
    cell.objects()
        .iter()
        .enumerate()
        .filter(|(i, _)| cell.locate(*i) == ObjectLocation::Bin1)
        .map(|(_, o)| o.id)
        .collect()
}

/// The seed of the policy's own stream for attempt `attempt` of a scene: one per attempt,
/// independent of the drop. A hash of the drop seed, not a seed a user gives or a sequence of
/// them (data::seeds): collect's drop seeds are random 64-bit numbers, so it wraps by design,
/// and every recorded trial and report depends on these exact values.
fn attempt_seed(drop_seed: u64, attempt: u32) -> u64 {
    drop_seed
        .wrapping_mul(1_000)
        .wrapping_add(u64::from(attempt))
}
