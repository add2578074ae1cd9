//! The two totes' layout: where bin 1 (pick) and bin 2 (place) stand and how big they are.
//!
//! The simulator builds its totes from these numbers, and the collision check and the random
//! policy keep to them, so the three cannot drift apart. Metres, world frame (docs/workcell.md).

/// Top surface of a tote's floor above the ground.
pub const FLOOR_TOP: f32 = 0.02;
/// Height of a tote's wall tops above the ground.
pub(crate) const WALL_TOP: f32 = 0.21;
/// Thickness of a tote's walls.
pub(crate) const WALL_THICKNESS: f32 = 0.03;
/// Half extents (x, y) of a tote's inner floor.
pub(crate) const INNER_HALF: [f32; 2] = [0.30, 0.40];

/// The inside of a tote.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct Tote {
    /// Centre of the floor (x, y).
    pub(crate) center: [f32; 2],
    /// Half extents of the inner floor (x, y).
    pub(crate) inner_half: [f32; 2],
    /// Height of the wall tops.
    pub(crate) wall_top: f32,
    /// Height of the floor's top surface.
    pub(crate) floor_top: f32,
}

/// Bin 1, where objects are dropped and picked.
pub(crate) const PICK_TOTE: Tote = Tote {
    center: [0.5, 0.0],
    inner_half: INNER_HALF,
    wall_top: WALL_TOP,
    floor_top: FLOOR_TOP,
};

/// Bin 2, where picked objects are placed.
pub(crate) const PLACE_TOTE: Tote = Tote {
    center: [-0.5, 0.0],
    inner_half: INNER_HALF,
    wall_top: WALL_TOP,
    floor_top: FLOOR_TOP,
};
