//! The parallel-jaw gripper's dimensions (Robotiq 2F-85 size): the one description that the
//! simulator builds, the planner plans for and the collision check keeps clear.
//!
//! Lengths are in metres, in the tool0 frame, whose z axis points out of the flange; "along" is
//! the closing direction and "across" the pads' width. docs/workcell.md draws the hand.

/// The hand below tool0.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct GripperGeometry {
    /// Largest distance between the pads' inner faces.
    pub(crate) max_opening: f32,
    /// Distance from tool0 to the TCP (the fingertips' lower edge) along the tool axis.
    pub(crate) tcp_offset: f32,
    /// Pad width across the closing direction.
    pub(crate) pad_width: f32,
    /// Pad height along the tool axis.
    pub(crate) pad_height: f32,
    /// Pad thickness along the closing direction.
    pub(crate) pad_thickness: f32,
    /// Palm (coupling and body) length below tool0.
    pub(crate) palm_length: f32,
    /// Palm half extent across the closing direction.
    pub(crate) palm_half_across: f32,
    /// Palm half extent along the closing direction.
    pub(crate) palm_half_along: f32,
}

/// The gripper of the workcell.
pub(crate) const GRIPPER: GripperGeometry = GripperGeometry {
    max_opening: 0.085,
    tcp_offset: 0.15,
    pad_width: 0.022,
    pad_height: 0.035,
    pad_thickness: 0.010,
    palm_length: 0.060,
    palm_half_across: 0.035,
    palm_half_along: 0.062,
};

impl GripperGeometry {
    /// Height of the palm's lower face above the TCP.
    pub(crate) const fn palm_height(&self) -> f32 {
        self.tcp_offset - self.palm_length
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_palm_sits_above_the_pads() {
        // The finger links between palm and pads need room: 0.15 − 0.035 − 0.06 = 55 mm.
        assert!(GRIPPER.palm_height() > GRIPPER.pad_height);
        assert_eq!(GRIPPER.palm_height(), 0.09);
    }
}
