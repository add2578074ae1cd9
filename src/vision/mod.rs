//! Vision: the top-down camera, the software ray caster that renders it, and colour maps.
//!
//! Pure core: scenes come in as plain [`render::Drawable`]s and frames go out as arrays, so
//! nothing here knows rapier's world or tch. It may use only rapier's math types. The camera's
//! numbers and conventions are in docs/camera.md.

pub mod camera;
pub(crate) mod colormap;
pub(crate) mod raycast;
pub mod render;
