//! Synthetic top-down frames for the policy checks' tests: a tote floor, and a block on it.

use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// A frame of the empty tote floor, with an optional 5 cm tall block of `half` pixels around
/// the image centre, seen by the top-down camera.
pub(crate) fn floor_frame(camera: &Camera, block_half: Option<u32>) -> Frame {
    block_frame(camera, block_half.map(|h| [h, h]))
}

/// Like [`floor_frame`], with a block of [`half columns, half rows`] pixels.
pub(crate) fn block_frame(camera: &Camera, block_half: Option<[u32; 2]>) -> Frame {
    let mut depth = Vec::new();
    for v in 0..128u32 {
        for u in 0..128u32 {
            let on_block =
                block_half.is_some_and(|[hu, hv]| u.abs_diff(64) <= hu && v.abs_diff(64) <= hv);
            let z = if on_block { 0.07 } else { 0.02 };
            // The depth at which pixel (u, v)'s ray meets height z.
            let far = camera.pixel_to_world(u, v, 1.0);
            let eye = camera.eye();
            depth.push((eye.z - z) / (eye.z - far.z));
        }
    }
    Frame {
        width: 128,
        height: 128,
        rgb: vec![0; 3 * 128 * 128],
        depth,
        mask: vec![0; 128 * 128],
    }
}
