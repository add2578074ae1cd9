//! Scene files in the workcell (`scene --load`, `eval --task scenes`): their objects loaded and
//! coloured, the layout checked for overlaps before any work, and placed with a seeded jitter.

use std::path::PathBuf;

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::{Pose, Rotation, Vector};

use super::Context;
use crate::assets::objects::ObjectModel;
use crate::data::scene_file::{Scene, SceneFormat};
use crate::grasp::tote::PICK_TOTE;
use crate::sim::{Workcell, WorkcellConfig};

/// Two listed objects may overlap this deep (m) and still be placed: the solver parts them
/// while the scene settles. VPG's cases overlap by less than a millimetre.
pub(crate) const OVERLAP_LIMIT: f32 = 0.003;
/// The largest shift of an object's position by a seed's jitter (m).
pub(crate) const JITTER_SHIFT: f32 = 0.002;
/// The largest turn of an object about the vertical by a seed's jitter (degrees).
pub(crate) const JITTER_TURN_DEG: f32 = 2.0;

/// A scene file with its objects' models, ready to place.
#[derive(Debug, Clone)]
pub(crate) struct ArrangedScene {
    /// The file as read.
    pub(crate) scene: Scene,
    /// One model per listed object, coloured as the file says.
    pub(crate) models: Vec<ObjectModel>,
}

impl ArrangedScene {
    /// Reads the scene files that `paths` name (files, or directories of them) and checks
    /// each: its objects exist in the library and, placed as listed, no two overlap by more
    /// than [`OVERLAP_LIMIT`].
    pub(crate) fn load_all(context: &Context, paths: &[PathBuf]) -> anyhow::Result<Vec<Self>> {
        let scenes = Scene::read_all(paths)?;
        let mut arranged = Vec::new();
        for scene in scenes {
            let mut models = Vec::new();
            for object in &scene.objects {
                let model = context.objects.load(&object.name).map_err(|e| {
                    let hint = match scene.format {
                        SceneFormat::Vpg => {
                            "; VPG's test cases place VPG's blocks: add --objects-dir assets/blocks"
                        }
                        SceneFormat::Graspmap => "",
                    };
                    anyhow::anyhow!("scene file {}: {e}{hint}", scene.path.display())
                })?;
                models.push(recoloured(model, object.color));
            }
            let placed = Self { scene, models };
            placed.check_overlaps()?;
            arranged.push(placed);
        }
        Ok(arranged)
    }

    /// The objects' poses in the world: as listed for seed 0, and for any other seed each
    /// shifted by at most [`JITTER_SHIFT`] and turned about the vertical by at most
    /// [`JITTER_TURN_DEG`], so that repeated runs differ as VPG's repeated runs did.
    pub(crate) fn poses(&self, seed: u64) -> Vec<(ObjectModel, Pose)> {
        let floor = Vector::new(
            PICK_TOTE.center[0],
            PICK_TOTE.center[1],
            PICK_TOTE.floor_top,
        );
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        self.scene
            .objects
            .iter()
            .zip(&self.models)
            .map(|(object, model)| {
                let mut pose = object.world_pose(floor);
                if seed != 0 {
                    let heading = rng.random_range(0.0..std::f32::consts::TAU);
                    let shift = JITTER_SHIFT * rng.random_range(0.0f32..=1.0).sqrt();
                    let turn = rng
                        .random_range(-JITTER_TURN_DEG..=JITTER_TURN_DEG)
                        .to_radians();
                    pose.translation +=
                        Vector::new(heading.cos() * shift, heading.sin() * shift, 0.0);
                    pose.rotation = (Rotation::from_rotation_z(turn) * pose.rotation).normalize();
                }
                (model.clone(), pose)
            })
            .collect()
    }

    /// Places the scene in `cell` for `seed` and lets it settle.
    pub(crate) fn place(&self, cell: &mut Workcell, seed: u64) -> anyhow::Result<()> {
        cell.place_at_rest(&self.poses(seed))?;
        cell.settle_arrangement();
        Ok(())
    }

    fn check_overlaps(&self) -> anyhow::Result<()> {
        let mut cell = Workcell::new(&WorkcellConfig::default())?;
        cell.place_at_rest(&self.poses(0))?;
        if let Some(overlap) = cell.deepest_overlap() {
            if overlap.depth > OVERLAP_LIMIT {
                let name = |i: usize| format!("object {} ({})", i + 1, self.models[i].name);
                bail!(
                    "scene file {}: {} and {} overlap by {:.1} mm (at most {:.0} mm is parted while the scene settles); move them apart",
                    self.scene.path.display(),
                    name(overlap.first),
                    name(overlap.second),
                    overlap.depth * 1000.0,
                    OVERLAP_LIMIT * 1000.0
                );
            }
        }
        Ok(())
    }
}

/// The model with every visual in `color`, when the scene gives one.
fn recoloured(mut model: ObjectModel, color: Option<[f32; 3]>) -> ObjectModel {
    if let Some(color) = color {
        for visual in &mut model.visuals {
            visual.color = color;
        }
    }
    model
}
