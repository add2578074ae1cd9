//! `graspmap collect`: grasp trials in clutter on the training objects, every attempt stored
//! with its observation and outcome, for `train --trials` (docs/data.md, "Trials").

use std::path::PathBuf;
use std::time::Instant;

use anyhow::bail;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::attempt::{objects_in_bin, Look};
use super::{workers, Context, RunBy};
use crate::assets::objects::ObjectModel;
use crate::data::lock::StoreLock;
use crate::data::output::check_output_dir;
use crate::data::shard::Shard;
use crate::data::trials::{Manifest, SceneTrials, Trial, TrialStore, TrialTally};
use crate::grasp::angle_bin;
use crate::grasp::world::world_grasp;
use crate::interrupt;
use crate::model::checkpoint::file_sha256;
use crate::model::inference::AffordanceModel;
use crate::model::unet::Precision;
use crate::named::{counted, named_enum, Named};
use crate::policy::baselines::{OraclePolicy, RandomPolicy};
use crate::policy::model::{ModelPolicy, ModelPolicyConfig};
use crate::policy::suppression::{Suppression, SuppressionConfig};
use crate::policy::{Decision, Observation, Policy};
use crate::present::envelope::write_report;
use crate::sim::{Workcell, WorkcellConfig};

named_enum! {
    /// Who chooses the grasps that `collect` tries.
    #[derive(serde::Deserialize)]
    pub enum CollectPolicy {
        /// The model, with its checks, exploring with probability --explore.
        Model = "model", "the model with its checks; with probability --explore an action sampled from its maps instead",
        /// The oracle planner.
        Oracle = "oracle", "the oracle planner (ground-truth masks)",
        /// Uniformly random grasps over bin 1's floor.
        Random = "random", "a uniformly random point of bin 1's floor and angle",
        /// The oracle with probability --oracle-share, else the exploring model.
        Mix = "mix", "the oracle with probability --oracle-share, else the exploring model",
    }
}

/// What `graspmap collect` runs, resolved by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct CollectConfig {
    /// The store's folder (DATA/trials by default).
    pub(crate) out: PathBuf,
    /// Seed of every scene's drop and every draw of the policies.
    pub(crate) seed: u64,
    /// Scenes of the whole run (all shards together).
    pub(crate) scenes: u64,
    /// Training objects dropped per scene.
    pub(crate) clutter: usize,
    /// Most attempts per scene.
    pub(crate) max_attempts: u32,
    /// Who chooses the grasps.
    pub(crate) policy: CollectPolicy,
    /// Chance that a model attempt is an exploration.
    pub(crate) explore: f64,
    /// Exploration's temperature: actions drawn ∝ score^(1/T).
    pub(crate) temperature: f32,
    /// Mix: chance that the oracle chooses an attempt.
    pub(crate) oracle_share: f64,
    /// The model's weights (model and mix).
    pub(crate) checkpoint: PathBuf,
    /// Arithmetic of the network.
    pub(crate) precision: Precision,
    /// The model policy's checks.
    pub(crate) model: ModelPolicyConfig,
    /// Failure suppression within a scene.
    pub(crate) suppression: SuppressionConfig,
    /// Who runs it, for the advice of its errors.
    pub(crate) run_by: RunBy,
    /// The part of the scenes this run collects.
    pub(crate) shard: Shard,
    /// Start the store over.
    pub(crate) force: bool,
}

/// What a finished collection reports.
#[derive(Debug, serde::Serialize)]
struct CollectResults {
    store: PathBuf,
    shard: String,
    scenes: usize,
    trials: usize,
    successes: usize,
    success_rate: f64,
    by_policy: std::collections::BTreeMap<String, (usize, usize)>,
    wall_seconds: f64,
}

/// The model, when the policy needs one.
struct Policies {
    model: Option<ModelPolicy>,
}

/// Runs the command.
pub(crate) fn run(context: &Context, config: CollectConfig) -> anyhow::Result<()> {
    let start = Instant::now();
    let split = context.split()?;
    let names = split.train.clone();
    if config.clutter > names.len() {
        bail!(
            "--clutter {} asks for more objects than the {} training objects of the split; give at most {}",
            config.clutter,
            names.len(),
            names.len()
        );
    }
    // Test objects are never loaded: a trial can only ever show training objects.
    let models = context.objects.load_all(&names)?;
    let uses_model = matches!(config.policy, CollectPolicy::Model | CollectPolicy::Mix);
    let policies = || -> anyhow::Result<Policies> {
        Ok(Policies {
            model: match uses_model {
                true => Some(ModelPolicy::new(
                    AffordanceModel::load(&config.checkpoint, config.precision)?,
                    config.model,
                )?),
                false => None,
            },
        })
    };
    // A missing or wrong checkpoint is reported before anything starts; each thread then
    // loads its own copy.
    policies()?;
    let settings = settings(context, &config, &names, uses_model)?;
    let store = TrialStore::new(&config.out);
    check_output_dir(store.dir(), "the trial store")?;
    let _writer = StoreLock::acquire(store.dir(), "collect")?;
    prepare(context, &store, &config, settings)?;

    let mine: Vec<u64> = (0..config.scenes)
        .filter(|&s| config.shard.holds(s))
        .collect();
    let todo = unfinished(context, &store, &mine)?;
    let done = (mine.len() - todo.len()) as u64;
    let bar = context.progress_bar("scenes", mine.len() as u64, done);
    let (workers, network_threads) = workers::plan(context.threads, todo.len());
    crate::model::use_threads(network_threads);
    let mut finished = 0;
    workers::run_in_order(
        &todo,
        workers,
        || {
            crate::model::use_threads(network_threads);
            policies()
        },
        |policies, &scene| {
            let complete = collect_scene(&store, &config, policies, &models, scene, &bar)?;
            Ok(complete.then_some(()))
        },
        |()| {
            finished += 1;
            bar.inc(1);
        },
    )?;
    let interrupted = interrupt::requested().filter(|_| finished < todo.len());
    bar.finish_and_clear();
    if let Some(interrupted) = interrupted {
        context.stopped(&format!(
            "{interrupted}: {} keeps every finished attempt; rerun the same command to continue (unfinished scenes are redone from their seeds)",
            store.dir().display()
        ));
        return Err(interrupted.into());
    }
    finish(context, &store, &config, &mine, start)
}

/// The scenes of `mine` still to collect, their unfinished folders removed (they are redone
/// from their seeds); says how many a resumed run finds done.
fn unfinished(context: &Context, store: &TrialStore, mine: &[u64]) -> anyhow::Result<Vec<u64>> {
    let mut todo = Vec::new();
    for &scene in mine {
        match store.load_scene(scene)? {
            Some(record) if record.complete => continue,
            Some(_) => store.remove_scene(scene)?,
            None if store.scene_dir(scene).exists() => store.remove_scene(scene)?,
            None => {}
        }
        todo.push(scene);
    }
    let done = mine.len() - todo.len();
    if done > 0 {
        context.note(&format!(
            "resuming: {} of {} already in {}",
            done,
            counted(mine.len(), "scene"),
            store.dir().display()
        ));
    }
    Ok(todo)
}

/// Everything that decides a store's bytes: a run resumes a store, and stores merge, only when
/// these are equal.
fn settings(
    context: &Context,
    config: &CollectConfig,
    names: &[String],
    uses_model: bool,
) -> anyhow::Result<serde_json::Value> {
    let checkpoint = match uses_model {
        true => Some(serde_json::json!({
            "sha256": file_sha256(&config.checkpoint)?,
            "precision": config.precision.name(),
        })),
        false => None,
    };
    Ok(serde_json::json!({
        "seed": config.seed,
        "scenes": config.scenes,
        "clutter": config.clutter,
        "max_attempts": config.max_attempts,
        "policy": config.policy.name(),
        "explore": config.explore,
        "temperature": config.temperature,
        "oracle_share": config.oracle_share,
        "checkpoint": checkpoint,
        "model_policy": config.model,
        "suppression": config.suppression,
        "objects": names,
        "objects_dir": context.objects.location(),
        "version": env!("CARGO_PKG_VERSION"),
    }))
}

/// Starts the store, or checks that the one there continues with these settings.
fn prepare(
    context: &Context,
    store: &TrialStore,
    config: &CollectConfig,
    settings: serde_json::Value,
) -> anyhow::Result<()> {
    let shard = (!config.shard.is_whole()).then_some(config.shard);
    let manifest = Manifest {
        schema: Manifest::SCHEMA.to_owned(),
        settings,
        shard,
        missing_shards: Vec::new(),
    };
    if config.force {
        let scenes = store.scenes()?;
        for &scene in &scenes {
            store.remove_scene(scene)?;
        }
        if !scenes.is_empty() {
            context.say(&format!(
                "--force: removed {} from {}",
                counted(scenes.len(), "scene"),
                store.dir().display()
            ));
        }
    } else if let Some(existing) = store.load_manifest()? {
        if existing != manifest {
            let differ = differing_keys(&existing.settings, &manifest.settings);
            let shard_note = match existing.shard != manifest.shard {
                true => format!(
                    " (it holds shard {}, this run is {})",
                    existing.shard.unwrap_or(Shard::WHOLE),
                    config.shard
                ),
                false => String::new(),
            };
            bail!(
                "{} holds trials collected with other settings{shard_note}{}; {}",
                store.dir().display(),
                match differ.is_empty() {
                    true => String::new(),
                    false => format!(" (differing: {})", differ.join(", ")),
                },
                match config.run_by {
                    RunBy::Own =>
                        "rerun with those, pass --out another folder, or --force to start over",
                    RunBy::Improve =>
                        "rerun improve with those, or give improve another --out folder",
                }
            );
        }
        return Ok(());
    } else if !store.scenes()?.is_empty() {
        bail!(
            "{} holds scene folders but no {}; it is not a store graspmap can continue: {}",
            store.dir().display(),
            crate::data::trials::MANIFEST_FILE,
            match config.run_by {
                RunBy::Own => "pass --force to start over, or --out another folder",
                RunBy::Improve => "remove that folder, or give improve another --out folder",
            }
        );
    }
    store.save_manifest(&manifest)
}

/// The top-level keys whose values differ (or that only one side has), each once, sorted.
pub(crate) fn differing_keys(a: &serde_json::Value, b: &serde_json::Value) -> Vec<String> {
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return Vec::new();
    };
    let keys: std::collections::BTreeSet<&String> = a
        .keys()
        .chain(b.keys())
        .filter(|k| a.get(k.as_str()) != b.get(k.as_str()))
        .collect();
    keys.into_iter().cloned().collect()
}

/// The drop seed of scene `scene` of the run seeded `seed`: its own ChaCha stream, so scenes
/// never share a drop with an evaluation's seeds.
pub(crate) fn scene_drop_seed(seed: u64, scene: u64) -> u64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(scene.wrapping_add(0x7472_6961_6c73));
    rng.random()
}

/// The training objects of a scene: `clutter` of them, drawn without replacement, in drop order.
fn scene_objects(models: &[ObjectModel], clutter: usize, drop_seed: u64) -> Vec<ObjectModel> {
    let mut rng = ChaCha8Rng::seed_from_u64(drop_seed);
    rng.set_stream(2);
    let mut picked = rand::seq::index::sample(&mut rng, models.len(), clutter).into_vec();
    picked.sort_unstable();
    picked.into_iter().map(|i| models[i].clone()).collect()
}

/// Runs one scene to its end, storing every attempt as it finishes; `false` when a signal
/// stopped it (its folder then holds whole attempts and says it is unfinished).
fn collect_scene(
    store: &TrialStore,
    config: &CollectConfig,
    policies: &Policies,
    models: &[ObjectModel],
    scene: u64,
    bar: &indicatif::ProgressBar,
) -> anyhow::Result<bool> {
    let drop_seed = scene_drop_seed(config.seed, scene);
    let dropped = scene_objects(models, config.clutter, drop_seed);
    let mut cell = Workcell::new(&WorkcellConfig::default())?;
    cell.drop_objects(&dropped, drop_seed)?;
    let mut record = SceneTrials {
        scene,
        drop_seed,
        objects: dropped.iter().map(|m| m.name.clone()).collect(),
        complete: false,
        trials: Vec::new(),
    };
    let mut memory = Suppression::new(config.suppression);
    for attempt in 0..config.max_attempts {
        if interrupt::requested().is_some() {
            return Ok(false);
        }
        let in_bin = objects_in_bin(&cell);
        if in_bin.is_empty() {
            break;
        }
        let look = Look::take(&cell, in_bin, drop_seed, attempt);
        let mut rng = ChaCha8Rng::seed_from_u64(look.attempt_seed);
        rng.set_stream(7);
        let view = look.observation();
        let Some((who, decision)) = decide(config, policies, &view, &memory, &mut rng) else {
            // Nothing to try (the oracle found no grasp): the scene would only repeat itself.
            break;
        };
        let Ok(grasp) = decision.grasp else { break };
        let aimed_at = look.aimed_at(&cell, grasp);
        let outcome = cell.pick(&world_grasp(&look.camera, &look.frame, grasp));
        memory.record(grasp, outcome.success);
        bar.set_message(format!(
            "scene {scene} attempt {attempt}: {who} {}",
            outcome.reason.name()
        ));
        record.trials.push(Trial {
            attempt,
            policy: who.to_owned(),
            grasp,
            rotation: decision
                .choice
                .map_or(angle_bin(grasp.angle_deg), |c| c.bin),
            score: decision.choice.map(|c| c.score),
            success: outcome.success,
            reason: outcome.reason.name().to_owned(),
            aimed_at,
            held: outcome.object,
        });
        store.append(&record, &look.rgb, &look.frame.to_depth_image_mm())?;
    }
    record.complete = true;
    store.save_scene(&record)?;
    Ok(true)
}

/// Who chooses this attempt, and what they chose; `None` when there is nothing to try.
fn decide(
    config: &CollectConfig,
    policies: &Policies,
    view: &Observation,
    memory: &Suppression,
    rng: &mut ChaCha8Rng,
) -> Option<(&'static str, Decision)> {
    // The draws happen in a fixed order whatever the outcome, so a scene's choices depend on
    // its seed alone.
    let oracle_turn = rng.random_bool(config.oracle_share.clamp(0.0, 1.0));
    let explore_turn = rng.random_bool(config.explore.clamp(0.0, 1.0));
    let model_turn = |rng: &mut ChaCha8Rng| {
        let model = policies.model.as_ref()?;
        Some(match explore_turn {
            true => (
                "explore",
                model.explore(view, memory, config.temperature, rng),
            ),
            false => ("model", model.decide(view, memory)),
        })
    };
    match config.policy {
        CollectPolicy::Random => Some(("random", RandomPolicy.decide(view, memory))),
        CollectPolicy::Oracle => {
            let decision = OraclePolicy.decide(view, memory);
            decision.grasp.is_ok().then_some(("oracle", decision))
        }
        CollectPolicy::Model => model_turn(rng),
        CollectPolicy::Mix => {
            if oracle_turn {
                let decision = OraclePolicy.decide(view, memory);
                if decision.grasp.is_ok() {
                    return Some(("oracle", decision));
                }
            }
            model_turn(rng)
        }
    }
}

/// Prints and reports what the store holds for this run's scenes.
fn finish(
    context: &Context,
    store: &TrialStore,
    config: &CollectConfig,
    mine: &[u64],
    start: Instant,
) -> anyhow::Result<()> {
    let tally = store.tally(mine)?;
    let results = CollectResults {
        store: store.dir().to_path_buf(),
        shard: config.shard.to_string(),
        scenes: tally.scenes,
        trials: tally.trials,
        successes: tally.successes,
        success_rate: tally.successes as f64 / tally.trials.max(1) as f64,
        by_policy: tally.by_policy,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    let by_policy: Vec<String> = results
        .by_policy
        .iter()
        .map(|(who, (n, ok))| format!("{who} {ok}/{n}"))
        .collect();
    context.say(&format!(
        "collected {} in {} ({} succeeded, {:.1} %; {}) -> {} ({:.1} s)",
        counted(results.trials, "trial"),
        counted(results.scenes, "scene"),
        results.successes,
        100.0 * results.success_rate,
        by_policy.join(", "),
        store.dir().display(),
        results.wall_seconds
    ));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "collect": store.load_manifest()?.map(|m| m.settings),
            "shard": config.shard.to_string(),
            "out": config.out,
            "force": config.force,
        });
        write_report(json, "collect", config.seed, &resolved, &results)?;
    }
    Ok(())
}

/// `collect --check`: every problem of the store on stdout, then exit 2 if there was any.
pub(crate) fn check(context: &Context, dir: &std::path::Path) -> anyhow::Result<()> {
    let store = TrialStore::new(dir);
    let problems = store.check();
    for problem in &problems {
        context.say(problem);
    }
    let scenes = store.scenes().unwrap_or_default();
    // A damaged scene is a problem above; the count is of the others.
    let readable: Vec<SceneTrials> = scenes
        .iter()
        .filter_map(|&s| store.load_scene(s).ok().flatten())
        .collect();
    let trials = TrialTally::of(&readable).trials;
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({ "global": context, "check": dir });
        let results = serde_json::json!({ "store": dir, "scenes": scenes.len(), "trials": trials, "problems": problems });
        write_report(json, "collect", 0, &resolved, &results)?;
    }
    if !problems.is_empty() {
        bail!(
            "{} problem(s) in {}; remove the named scene folders and collect again (same flags) to redo them, or collect --force to start over",
            problems.len(),
            dir.display()
        );
    }
    context.say(&format!(
        "{}: {} in {}, no problems",
        dir.display(),
        counted(trials, "trial"),
        counted(scenes.len(), "scene")
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differing_keys_names_each_key_once_in_order() {
        let a = serde_json::json!({"seed": 1, "scenes": 4, "clutter": 3, "policy": "model"});
        let b = serde_json::json!({"scenes": 5, "seed": 2, "policy": "model", "explore": 0.1});
        assert_eq!(
            differing_keys(&a, &b),
            ["clutter", "explore", "scenes", "seed"]
        );
        assert!(differing_keys(&a, &a).is_empty());
        assert!(differing_keys(&a, &serde_json::json!(3)).is_empty());
    }
}
