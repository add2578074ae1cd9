//! The trial store: every grasp attempt `graspmap collect` ran, successes and failures, with its
//! observation, in DATA/trials/ (docs/data.md, "Trials").
//!
//! Layout: `collect.json` (the settings every scene was collected with, and the shard a store
//! holds), then one folder per scene, `scene_NNNNNN/`, holding `trials.json` and each attempt's
//! `AA_rgb.png` and `AA_depth.png`. A scene is the unit of work and of resume: its `trials.json`
//! is rewritten atomically after every attempt and says `"complete": true` after its last, so a
//! killed run leaves whole attempts, and the next run redoes only the unfinished scenes (one per
//! thread, each from its seed, to the same bytes). Shards hold disjoint scenes, so merging is copying folders.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use image::{GrayImage, RgbImage};
use serde::{Deserialize, Serialize};

use super::atomic::{save_image_atomic, write_atomic};
use super::input::{decode_depth_png, height_from_depth_mm, InputKind};
use super::shard::Shard;
use crate::grasp::{PixelGrasp, IMAGE_SIZE};

/// The settings file's name.
pub(crate) const MANIFEST_FILE: &str = "collect.json";
/// One scene's record, inside its folder.
pub(crate) const SCENE_FILE: &str = "trials.json";
const SCENE_PREFIX: &str = "scene_";

/// `collect.json`: what the store's scenes were collected with. Two stores merge, and a run
/// resumes a store, only when their `settings` are equal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// `graspmap.trials/1`.
    pub schema: String,
    /// The collection's settings, as `graspmap collect` records them.
    pub settings: serde_json::Value,
    /// The part of the scenes this store holds; absent for a whole (or merged) run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// A merge of some of the shards only (`merge --allow-partial`): these were missing.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub missing_shards: Vec<Shard>,
}

impl Manifest {
    /// The schema name.
    pub const SCHEMA: &'static str = "graspmap.trials/1";
}

/// One attempt of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trial {
    /// 0-based attempt within the scene; the observation is `AA_rgb.png` / `AA_depth.png`.
    pub attempt: u32,
    /// Who chose the grasp: `model`, `explore` (sampled from the model's maps), `oracle` or
    /// `random`.
    pub policy: String,
    /// The executed grasp in the observation: column, row and angle (degrees, clockwise).
    pub grasp: PixelGrasp,
    /// The rotation bin of the grasp's angle (0..8): the map it is trained on.
    pub rotation: usize,
    /// The network's score of the action, when a model chose it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub score: Option<f32>,
    /// Whether the grasp lifted and held an object.
    pub success: bool,
    /// The outcome's reason, as `eval` reports it.
    pub reason: String,
    /// The object under the grasp centre, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aimed_at: Option<String>,
    /// The object the grasp held, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held: Option<String>,
}

/// One scene's `trials.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneTrials {
    /// 0-based scene number of the run.
    pub scene: u64,
    /// Seed of the drop (and, with the attempt, of the policy's own draws).
    pub drop_seed: u64,
    /// The objects dropped, in drop order.
    pub objects: Vec<String>,
    /// Whether every attempt of the scene is here.
    pub complete: bool,
    /// The attempts so far.
    pub trials: Vec<Trial>,
}

/// What some scenes of a store hold, counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct TrialTally {
    /// Scenes counted.
    pub(crate) scenes: usize,
    /// Their attempts.
    pub(crate) trials: usize,
    /// Those that succeeded.
    pub(crate) successes: usize,
    /// Attempts and successes by who chose the grasp.
    pub(crate) by_policy: BTreeMap<String, (usize, usize)>,
}

impl TrialTally {
    /// The count of `records`.
    pub(crate) fn of<'a>(records: impl IntoIterator<Item = &'a SceneTrials>) -> Self {
        let mut tally = Self::default();
        for record in records {
            tally.scenes += 1;
            for trial in &record.trials {
                tally.trials += 1;
                tally.successes += usize::from(trial.success);
                let entry = tally.by_policy.entry(trial.policy.clone()).or_default();
                entry.0 += 1;
                entry.1 += usize::from(trial.success);
            }
        }
        tally
    }
}

/// A trial store's folder.
#[derive(Debug, Clone)]
pub struct TrialStore {
    dir: PathBuf,
}

impl TrialStore {
    /// The store in `dir` (which need not exist yet).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The store's folder.
    pub(crate) fn dir(&self) -> &Path {
        &self.dir
    }

    /// `collect.json`.
    pub(crate) fn manifest_path(&self) -> PathBuf {
        self.dir.join(MANIFEST_FILE)
    }

    /// Scene `scene`'s folder.
    pub(crate) fn scene_dir(&self, scene: u64) -> PathBuf {
        self.dir.join(format!("{SCENE_PREFIX}{scene:06}"))
    }

    /// An attempt's RGB observation.
    pub(crate) fn rgb_path(&self, scene: u64, attempt: u32) -> PathBuf {
        self.scene_dir(scene).join(format!("{attempt:02}_rgb.png"))
    }

    /// An attempt's depth observation (16-bit millimetres).
    pub(crate) fn depth_path(&self, scene: u64, attempt: u32) -> PathBuf {
        self.scene_dir(scene)
            .join(format!("{attempt:02}_depth.png"))
    }

    /// The settings, or `None` for a store not started.
    pub(crate) fn load_manifest(&self) -> anyhow::Result<Option<Manifest>> {
        let path = self.manifest_path();
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        let manifest: Manifest = serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not a trial store's settings file (collect --force starts over)",
                path.display()
            )
        })?;
        if manifest.schema != Manifest::SCHEMA {
            bail!(
                "{} has schema '{}', expected '{}' (collect --force starts over)",
                path.display(),
                manifest.schema,
                Manifest::SCHEMA
            );
        }
        Ok(Some(manifest))
    }

    /// Writes `collect.json` atomically.
    pub(crate) fn save_manifest(&self, manifest: &Manifest) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(manifest)? + "\n";
        write_atomic(&self.manifest_path(), text.as_bytes())
    }

    /// The scene numbers that have a folder, ascending.
    pub(crate) fn scenes(&self) -> anyhow::Result<Vec<u64>> {
        let mut scenes = Vec::new();
        let entries = match std::fs::read_dir(&self.dir) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(scenes),
            Err(e) => return Err(e).with_context(|| format!("reading {}", self.dir.display())),
        };
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", self.dir.display()))?;
            let name = entry.file_name();
            let Some(number) = name.to_str().and_then(|n| n.strip_prefix(SCENE_PREFIX)) else {
                continue;
            };
            if let Ok(scene) = number.parse() {
                scenes.push(scene);
            }
        }
        scenes.sort_unstable();
        Ok(scenes)
    }

    /// Scene `scene`'s record, or `None` when its folder has none yet.
    pub(crate) fn load_scene(&self, scene: u64) -> anyhow::Result<Option<SceneTrials>> {
        let path = self.scene_dir(scene).join(SCENE_FILE);
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        let record: SceneTrials = serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not a scene's trial record (remove its folder, and collect again to redo it)",
                path.display()
            )
        })?;
        if record.scene != scene {
            bail!(
                "{} says it is scene {}; it lies in the folder of scene {scene} (remove the folder, and collect again to redo it)",
                path.display(),
                record.scene
            );
        }
        Ok(Some(record))
    }

    /// Saves an attempt's observation, then the scene's record with it: the record never names
    /// an attempt whose images are not on disk.
    pub(crate) fn append(
        &self,
        record: &SceneTrials,
        rgb: &RgbImage,
        depth_mm: &image::ImageBuffer<image::Luma<u16>, Vec<u16>>,
    ) -> anyhow::Result<()> {
        if let Some(trial) = record.trials.last() {
            save_image_atomic(rgb, &self.rgb_path(record.scene, trial.attempt))?;
            save_image_atomic(depth_mm, &self.depth_path(record.scene, trial.attempt))?;
        }
        self.save_scene(record)
    }

    /// Writes a scene's `trials.json` atomically.
    pub(crate) fn save_scene(&self, record: &SceneTrials) -> anyhow::Result<()> {
        let text = serde_json::to_string_pretty(record)? + "\n";
        write_atomic(
            &self.scene_dir(record.scene).join(SCENE_FILE),
            text.as_bytes(),
        )
    }

    /// The trials of `scenes`, counted; a scene without its record is an error.
    pub(crate) fn tally(&self, scenes: &[u64]) -> anyhow::Result<TrialTally> {
        let mut records = Vec::with_capacity(scenes.len());
        for &scene in scenes {
            records.push(
                self.load_scene(scene)?.with_context(|| {
                    format!("scene {scene} vanished from {}", self.dir.display())
                })?,
            );
        }
        Ok(TrialTally::of(&records))
    }

    /// Removes a scene's folder (an unfinished scene that is redone from its seed).
    pub(crate) fn remove_scene(&self, scene: u64) -> anyhow::Result<()> {
        let dir = self.scene_dir(scene);
        std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))
    }

    /// Every problem a run, a merge or training would refuse, one line each.
    pub fn check(&self) -> Vec<String> {
        let mut problems = Vec::new();
        match self.load_manifest() {
            Ok(Some(_)) => {}
            Ok(None) => problems.push(format!(
                "{}: missing (this folder is not a trial store; write one with graspmap collect)",
                self.manifest_path().display()
            )),
            Err(e) => problems.push(format!("{e:#}")),
        }
        let scenes = match self.scenes() {
            Ok(scenes) => scenes,
            Err(e) => {
                problems.push(format!("{e:#}"));
                return problems;
            }
        };
        for scene in scenes {
            let record = match self.load_scene(scene) {
                Ok(Some(record)) => record,
                Ok(None) => {
                    problems.push(format!(
                        "{}: missing (remove the folder, and collect again to redo the scene)",
                        self.scene_dir(scene).join(SCENE_FILE).display()
                    ));
                    continue;
                }
                Err(e) => {
                    problems.push(format!("{e:#}"));
                    continue;
                }
            };
            if !record.complete {
                problems.push(format!(
                    "{}: unfinished (collect again to finish it)",
                    self.scene_dir(scene).display()
                ));
            }
            for (i, trial) in record.trials.iter().enumerate() {
                if trial.attempt as usize != i {
                    problems.push(format!(
                        "{}: attempt {} listed as number {i} (remove the folder, and collect again to redo it)",
                        self.scene_dir(scene).join(SCENE_FILE).display(),
                        trial.attempt
                    ));
                }
                let rgb = self.rgb_path(scene, trial.attempt);
                if let Err(e) = read_rgb(&rgb) {
                    problems.push(format!("{e:#}"));
                }
                let depth = self.depth_path(scene, trial.attempt);
                if let Err(e) = std::fs::read(&depth)
                    .with_context(|| format!("{}: missing or unreadable", depth.display()))
                    .and_then(|bytes| decode_depth_png(&bytes, &depth).map(|_| ()))
                {
                    problems.push(format!(
                        "{e:#} (remove the scene's folder, and collect again to redo it)"
                    ));
                }
            }
        }
        problems
    }

    /// Every complete scene's trials with their observations, in scene and attempt order; the
    /// height plane is loaded for rgbd. Fails on the first problem, naming the file.
    pub(crate) fn load_all(&self, input: InputKind) -> anyhow::Result<Vec<LoadedTrial>> {
        if self.load_manifest()?.is_none() {
            bail!(
                "{} has no {MANIFEST_FILE}: not a trial store (write one with graspmap collect)",
                self.dir.display()
            );
        }
        let mut loaded = Vec::new();
        for scene in self.scenes()? {
            let Some(record) = self.load_scene(scene)? else {
                continue;
            };
            if !record.complete {
                bail!(
                    "{}: scene {scene} is unfinished; finish it with graspmap collect (same flags), or remove its folder",
                    self.dir.display()
                );
            }
            for trial in record.trials {
                let image = read_rgb(&self.rgb_path(scene, trial.attempt))?;
                let height = match input {
                    InputKind::Rgb => None,
                    InputKind::Rgbd => {
                        let path = self.depth_path(scene, trial.attempt);
                        let bytes = std::fs::read(&path)
                            .with_context(|| format!("reading {}", path.display()))?;
                        Some(height_from_depth_mm(&decode_depth_png(&bytes, &path)?))
                    }
                };
                loaded.push(LoadedTrial {
                    scene,
                    trial,
                    image,
                    height,
                });
            }
        }
        Ok(loaded)
    }
}

/// A trial with its observation, ready to become a training sample.
pub(crate) struct LoadedTrial {
    /// Its scene.
    pub(crate) scene: u64,
    /// The record.
    pub(crate) trial: Trial,
    /// The RGB observation.
    pub(crate) image: RgbImage,
    /// The height plane (rgbd).
    pub(crate) height: Option<GrayImage>,
}

/// A 128 × 128 8-bit RGB PNG, or an error naming the file.
fn read_rgb(path: &Path) -> anyhow::Result<RgbImage> {
    let decoded = image::open(path).with_context(|| {
        format!(
            "{}: missing or unreadable (remove the scene's folder, and collect again to redo it)",
            path.display()
        )
    })?;
    if decoded.color() != image::ColorType::Rgb8
        || (decoded.width(), decoded.height()) != (IMAGE_SIZE, IMAGE_SIZE)
    {
        bail!(
            "{}: image is {}×{} {:?}, expected {IMAGE_SIZE}×{IMAGE_SIZE} Rgb8 (remove the scene's folder, and collect again to redo it)",
            path.display(),
            decoded.width(),
            decoded.height(),
            decoded.color()
        );
    }
    Ok(decoded.into_rgb8())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_round_trips_through_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let store = TrialStore::new(dir.path().join("trials"));
        store
            .save_manifest(&Manifest {
                schema: Manifest::SCHEMA.into(),
                settings: serde_json::json!({"seed": 3}),
                shard: None,
                missing_shards: Vec::new(),
            })
            .unwrap();
        let record = SceneTrials {
            scene: 4,
            drop_seed: 99,
            objects: vec!["YcbBanana".into(), "YcbHammer".into()],
            complete: true,
            trials: vec![Trial {
                attempt: 0,
                policy: "explore".into(),
                grasp: PixelGrasp {
                    u: 60,
                    v: 70,
                    angle_deg: 45.0,
                },
                rotation: 2,
                score: Some(0.25),
                success: false,
                reason: "missed".into(),
                aimed_at: Some("YcbBanana".into()),
                held: None,
            }],
        };
        let rgb = RgbImage::from_pixel(128, 128, image::Rgb([10, 20, 30]));
        let depth = image::ImageBuffer::from_pixel(128, 128, image::Luma([900u16]));
        store.append(&record, &rgb, &depth).unwrap();
        assert_eq!(store.scenes().unwrap(), [4]);
        assert_eq!(store.load_scene(4).unwrap().unwrap(), record);
        let tally = store.tally(&[4]).unwrap();
        assert_eq!((tally.scenes, tally.trials, tally.successes), (1, 1, 0));
        assert_eq!(tally.by_policy["explore"], (1, 0));
        assert!(store.tally(&[4, 5]).is_err(), "scene 5 has no record");
        assert!(store.check().is_empty(), "{:?}", store.check());
        let loaded = store.load_all(InputKind::Rgbd).unwrap();
        assert_eq!(loaded.len(), 1);
        assert_eq!(loaded[0].image, rgb);
        assert_eq!(loaded[0].trial, record.trials[0]);
        // A torn image is named by --check.
        std::fs::write(store.depth_path(4, 0), b"not a png").unwrap();
        let problems = store.check();
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert!(problems[0].contains("00_depth.png"), "{problems:?}");
    }
}
