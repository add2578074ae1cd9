//! `graspmap scene`: drop objects into bin 1 and save what the top-down camera sees.

use std::time::Instant;

use anyhow::Context as _;

use std::path::PathBuf;

use super::arranged::ArrangedScene;
use super::Context;
use crate::data::atomic::{save_image_atomic, write_atomic};
use crate::data::output::check_output_file;
use crate::data::scene_file::{PlacedObject, Scene, SceneFormat};
use crate::grasp::tote::PICK_TOTE;
use crate::present::envelope::write_report;
use crate::sim::{Workcell, WorkcellConfig};

/// What `graspmap scene` drops and where it writes the views.
#[derive(Debug, Clone)]
pub(crate) struct SceneConfig {
    /// Where the objects come from.
    pub(crate) source: SceneSource,
    /// The RGB image (.png).
    pub(crate) out: PathBuf,
    /// The depth image as 16-bit PNG in millimetres, if wanted.
    pub(crate) depth: Option<PathBuf>,
    /// Where to write the settled scene as a scene file, if wanted.
    pub(crate) save: Option<PathBuf>,
}

/// How the scene comes about.
#[derive(Debug, Clone)]
pub(crate) enum SceneSource {
    /// Objects by name, dropped in this order from poses drawn with `seed`.
    Drop {
        /// Object names.
        objects: Vec<String>,
        /// Seed of the drop poses.
        seed: u64,
    },
    /// Placed as a scene file lists them (docs/scenes.md).
    Load(PathBuf),
}

#[derive(serde::Serialize)]
struct SceneResults {
    objects: Vec<ObjectResult>,
    image: String,
    depth: Option<String>,
    wall_seconds: f64,
    sim_seconds: f64,
}

#[derive(serde::Serialize)]
struct ObjectResult {
    name: String,
    position: [f32; 3],
    /// Quaternion x, y, z, w.
    orientation: [f32; 4],
    visible_pixels: usize,
}

/// Runs the command.
pub(crate) fn run(context: &Context, args: SceneConfig) -> anyhow::Result<()> {
    let start = Instant::now();
    check_output_file(&args.out, "--out")?;
    if let Some(depth) = &args.depth {
        check_output_file(depth, "--depth")?;
    }
    let config = WorkcellConfig::default();
    let (mut cell, seed, colors) = match &args.source {
        SceneSource::Drop { objects, seed } => {
            let models = context.objects.load_all(objects)?;
            let mut cell = Workcell::new(&config)?;
            cell.drop_objects(&models, *seed)?;
            (cell, *seed, vec![None; models.len()])
        }
        SceneSource::Load(file) => {
            let scene = ArrangedScene::load_all(context, std::slice::from_ref(file))?.remove(0);
            let colors = scene.scene.objects.iter().map(|o| o.color).collect();
            (replayed(&scene, &config)?, 0, colors)
        }
    };
    if let Some(save) = &args.save {
        let scene = settled_scene(&cell, save, &colors);
        write_atomic(save, scene.to_json().as_bytes())
            .with_context(|| format!("writing --save {}", save.display()))?;
        // What --out shows is the scene as the file replays it, so that `scene --load` and
        // `eval --task scenes` start from this very image.
        let arranged = ArrangedScene::load_all(context, std::slice::from_ref(save))?.remove(0);
        cell = replayed(&arranged, &config)?;
        context.say(&format!("wrote the scene file {}", save.display()));
    }
    let frame = cell.capture();
    save_image_atomic(&frame.to_rgb_image(), &args.out)
        .with_context(|| format!("writing --out {}", args.out.display()))?;
    if let Some(depth) = &args.depth {
        save_image_atomic(&frame.to_depth_image_mm(), depth)
            .with_context(|| format!("writing --depth {}", depth.display()))?;
    }
    let objects: Vec<ObjectResult> = cell
        .objects()
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let pose = cell.object_pose(i);
            ObjectResult {
                name: o.model.name.clone(),
                position: pose.translation.to_array(),
                orientation: pose.rotation.to_array(),
                visible_pixels: frame.mask.iter().filter(|&&id| id == o.id).count(),
            }
        })
        .collect();
    for o in &objects {
        context.say(&format!(
            "{:<18} at ({:.3}, {:.3}, {:.3}) m, {} pixels visible",
            o.name, o.position[0], o.position[1], o.position[2], o.visible_pixels
        ));
    }
    context.say(&format!("wrote {}", args.out.display()));
    let results = SceneResults {
        objects,
        image: args.out.display().to_string(),
        depth: args.depth.as_ref().map(|d| d.display().to_string()),
        wall_seconds: start.elapsed().as_secs_f64(),
        sim_seconds: cell.time(),
    };
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "workcell": config,
            "source": match &args.source {
                SceneSource::Drop { objects, .. } => serde_json::json!({"objects": objects}),
                SceneSource::Load(file) => serde_json::json!({"load": file}),
            },
            "save": args.save,
        });
        write_report(json, "scene", seed, &resolved, &results)?;
    }
    Ok(())
}

/// A fresh workcell with `scene` placed as listed (seed 0) and settled.
fn replayed(scene: &ArrangedScene, config: &WorkcellConfig) -> anyhow::Result<Workcell> {
    let mut cell = Workcell::new(config)?;
    scene.place(&mut cell, 0)?;
    Ok(cell)
}

/// The objects' poses now, as a scene file in bin 1's frame, with the colours the scene
/// was given (`None` keeps a model's own).
fn settled_scene(cell: &Workcell, path: &std::path::Path, colors: &[Option<[f32; 3]>]) -> Scene {
    let floor = rapier3d::math::Vector::new(
        PICK_TOTE.center[0],
        PICK_TOTE.center[1],
        PICK_TOTE.floor_top,
    );
    let objects = cell
        .objects()
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let pose = cell.object_pose(i);
            PlacedObject {
                name: o.model.name.clone(),
                position: (pose.translation - floor).to_array(),
                orientation: pose.rotation.to_array(),
                color: colors[i],
            }
        })
        .collect();
    Scene {
        name: String::new(),
        path: path.to_owned(),
        format: SceneFormat::Graspmap,
        objects,
    }
}
