//! Vision: the top-down camera, the software ray caster that renders it, colour maps and the
//! words drawn on pictures.
//!
//! Pure core: scenes come in as plain [`render::Drawable`]s and frames go out as arrays, so
//! nothing here knows rapier's world or tch. It may use only rapier's math types. The camera's
//! numbers and conventions are in docs/camera.md.

pub(crate) mod annotate;
pub mod camera;
pub(crate) mod colormap;
pub(crate) mod raycast;
pub mod render;
