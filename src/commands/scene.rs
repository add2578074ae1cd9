//! `graspmap scene`: drop objects into bin 1 and save what the top-down camera sees.

use std::time::Instant;

use anyhow::Context as _;

use std::path::PathBuf;

use super::Context;
use crate::data::atomic::save_image_atomic;
use crate::data::output::check_output_file;
use crate::present::envelope::write_report;
use crate::sim::{Workcell, WorkcellConfig};

/// What `graspmap scene` drops and where it writes the views.
#[derive(Debug, Clone)]
pub(crate) struct SceneConfig {
    /// Object names, dropped in this order.
    pub(crate) objects: Vec<String>,
    /// Seed of the drop poses.
    pub(crate) seed: u64,
    /// The RGB image (.png).
    pub(crate) out: PathBuf,
    /// The depth image as 16-bit PNG in millimetres, if wanted.
    pub(crate) depth: Option<PathBuf>,
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
    let models = context.objects.load_all(&args.objects)?;
    let config = WorkcellConfig::default();
    let mut cell = Workcell::new(&config)?;
    cell.drop_objects(&models, args.seed)?;
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
            "objects": args.objects,
        });
        write_report(json, "scene", args.seed, &resolved, &results)?;
    }
    Ok(())
}
