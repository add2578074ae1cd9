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
    let blocks: Vec<[u32; 4]> = block_half
        .map(|[hu, hv]| [64 - hu, 64 + hu, 64 - hv, 64 + hv])
        .into_iter()
        .collect();
    blocks_frame(camera, &blocks)
}

/// The tote floor with 5 cm tall blocks, each [first column, last column, first row, last row].
pub(crate) fn blocks_frame(camera: &Camera, blocks: &[[u32; 4]]) -> Frame {
    let mut depth = Vec::new();
    for v in 0..128u32 {
        for u in 0..128u32 {
            let on_block = blocks
                .iter()
                .any(|b| (b[0]..=b[1]).contains(&u) && (b[2]..=b[3]).contains(&v));
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
