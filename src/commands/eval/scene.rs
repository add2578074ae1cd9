//! One evaluation job on a worker: a train/test attempt on a fresh drop, or a whole empty_bin
//! scene, each attempt looked at, decided, drawn, pushed or picked, and recorded.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use super::{single_object_seed, Evaluation, Setup, Worker, EPISODE_EVERY_STEPS};
use crate::assets::objects::ObjectModel;
use crate::commands::attempt::{objects_in_bin, Look};
use crate::data::atomic::save_image_atomic;
use crate::grasp::draw::draw_grasp;
use crate::grasp::world::{world_grasp, WorldPush};
use crate::interrupt;
use crate::named::Named;
use crate::policy::heights::HeightMap;
use crate::policy::push::plan_push;
use crate::policy::suppression::Suppression;
use crate::present::eval_report::{AttemptRecord, AttemptTiming, BinOutcome, PushRecord, SceneRun};
use crate::sim::pick::{PickOutcome, PickReason};
use crate::sim::{ObjectLocation, Workcell};
use rapier3d::math::Vector;

impl Evaluation<'_> {
    /// train/test: attempt `a` of object `i`, alone in a fresh drop.
    pub(super) fn single_object(
        &self,
        worker: &mut Worker,
        model: &ObjectModel,
        i: usize,
        seed: u64,
        a: u32,
    ) -> anyhow::Result<AttemptRecord> {
        let started = Instant::now();
        let drop_seed = single_object_seed(seed, i, a)?;
        let mut cell = self.workcell()?;
        cell.drop_objects(std::slice::from_ref(model), drop_seed)?;
        let drop_seconds = started.elapsed().as_secs_f64();
        // Suppression remembers actions within a scene; each attempt here is a new one.
        let memory = Suppression::new(self.suppression);
        let vis = self.vis_path(seed, &format!("{}_{a}.png", model.name));
        let mut record = self.attempt(worker, &mut cell, &memory, drop_seed, a, vis)?;
        record.object = Some(model.name.clone());
        record.timing.sim += drop_seconds;
        record.timing.wall = started.elapsed().as_secs_f64();
        self.bar.inc(1);
        self.bar.set_message(format!(
            "{} {}",
            model.name,
            if record.success {
                "success"
            } else {
                record.reason.name()
            }
        ));
        Ok(record)
    }

    /// empty_bin and scenes: every object in bin 1 at once, picked until the bin is empty,
    /// attempts run out or the give-up rule ends it. With the lines it printed, or keeps to
    /// print when the scenes before it have printed theirs.
    pub(super) fn empty_bin(
        &self,
        worker: &mut Worker,
        setup: Setup<'_>,
        seed: u64,
    ) -> anyhow::Result<Option<(SceneRun, Vec<String>)>> {
        let started = Instant::now();
        let mut cell = self.workcell()?;
        let scene = match setup {
            Setup::Drop(models) => {
                cell.drop_objects(models, seed)?;
                None
            }
            Setup::Arrange(arranged) => {
                arranged.place(&mut cell, seed)?;
                Some(arranged.scene.name.clone())
            }
        };
        let mut setup_seconds = started.elapsed().as_secs_f64();
        let total = cell.objects().len();
        let mut memory = Suppression::new(self.suppression);
        let mut attempts: Vec<AttemptRecord> = Vec::new();
        let mut gave_up = false;
        let mut lines = Vec::new();
        let mut say = |line: String| match self.live_lines {
            true => self.bar.suspend(|| self.context.note(&line)),
            false => lines.push(line),
        };
        for a in 0..self.max_attempts {
            if count(&cell, ObjectLocation::Bin1) == 0 {
                self.bar.inc(u64::from(self.max_attempts - a));
                break;
            }
            let attempt_start = Instant::now();
            let file = match &scene {
                Some(name) => format!("{name}_seed{seed}_attempt{a:02}.png"),
                None => format!("seed{seed}_attempt{a:02}.png"),
            };
            let vis = self.vis_path(seed, &file);
            let mut record = self.attempt(worker, &mut cell, &memory, seed, a, vis)?;
            if let Some(grasp) = record.grasp {
                memory.record(grasp, record.success);
            }
            let moved = count(&cell, ObjectLocation::Bin2);
            record.moved = Some(moved);
            record.timing.wall = attempt_start.elapsed().as_secs_f64() + setup_seconds;
            record.timing.sim += setup_seconds;
            setup_seconds = 0.0;
            say(moved_line(&record, moved, total));
            self.bar.inc(1);
            attempts.push(record);
            if interrupt::requested().is_some() {
                return Ok(None);
            }
            let failing = attempts
                .iter()
                .rev()
                .take_while(|r| r.failed_action())
                .count();
            if self.give_up_after > 0 && failing >= self.give_up_after as usize {
                gave_up = true;
                self.bar.inc(u64::from(self.max_attempts - a - 1));
                say(format!("gave up after {failing} failed attempts in a row."));
                break;
            }
        }
        let bin = bin_outcome(&cell, gave_up);
        say(format!("{} objects left in the bin.", bin.left));
        let run = SceneRun {
            scene,
            seed,
            attempts,
            bin: Some(bin),
        };
        Ok(Some((run, lines)))
    }

    /// A fresh workcell, watching its invariants when the soak asks for it.
    fn workcell(&self) -> anyhow::Result<Workcell> {
        let mut cell = Workcell::new(&self.workcell)?;
        if self.check_invariants {
            cell.watch_invariants();
        }
        Ok(cell)
    }

    /// Where a visualisation goes, for the policies that draw one.
    fn vis_path(&self, seed: u64, file: &str) -> PathBuf {
        if self.per_seed_vis {
            self.vis_dir.join(format!("seed{seed}")).join(file)
        } else {
            self.vis_dir.join(file)
        }
    }

    /// Looks, decides, writes the visualisation and picks.
    fn attempt(
        &self,
        worker: &mut Worker,
        cell: &mut Workcell,
        memory: &Suppression,
        drop_seed: u64,
        attempt: u32,
        vis: PathBuf,
    ) -> anyhow::Result<AttemptRecord> {
        let in_bin = objects_in_bin(cell);
        let render_start = Instant::now();
        let look = Look::take(cell, in_bin, drop_seed, attempt);
        let render = render_start.elapsed().as_secs_f64();
        let (camera, frame, rgb) = (&look.camera, &look.frame, &look.rgb);
        let decision = worker.policy.decide(&look.observation(), memory);
        let vis_written = match &decision.vis {
            Some(image) => {
                save_image_atomic(image, &vis)?;
                Some(vis)
            }
            None => None,
        };
        let aimed_at = (decision.grasp.as_ref().ok()).and_then(|&g| look.aimed_at(cell, g));
        if let Some(video) = &worker.recording {
            let mut view = rgb.clone();
            if let Ok(g) = &decision.grasp {
                draw_grasp(&mut view, g);
            }
            video.inset(view);
            cell.record_into(EPISODE_EVERY_STEPS, video.footage());
        }
        let sim_start = Instant::now();
        let push = match (&decision.grasp, decision.verified) {
            (Ok(g), Some(false)) if self.push_unverified => {
                plan_push(&HeightMap::new(camera, frame), frame, *g)
            }
            _ => None,
        };
        let mut push_record = None;
        let outcome = match (&decision.grasp, push) {
            (_, Some(push)) => {
                let (outcome, record) = push_and_record(cell, &push);
                push_record = Some(record);
                outcome
            }
            (Ok(g), None) => cell.pick(&world_grasp(camera, frame, *g)),
            (Err(why), None) => PickOutcome::failure(PickReason::Ungraspable, why.to_string()),
        };
        let sim = sim_start.elapsed().as_secs_f64();
        cell.take_recording();
        let record = AttemptRecord {
            drop_seed,
            attempt,
            object: None,
            grasp: decision.grasp.as_ref().ok().copied(),
            choice: decision.choice,
            verified: decision.verified,
            success: outcome.success,
            reason: outcome.reason,
            detail: outcome.detail,
            aimed_at,
            held: outcome.object,
            placed: outcome.placed,
            moved: None,
            vis: vis_written,
            push: push_record,
            violations: cell.take_violations(),
            timing: AttemptTiming {
                wall: 0.0,
                sim,
                render,
                network: decision.network_seconds,
            },
        };
        for violation in &record.violations {
            let line = format!("invariant broken: seed {drop_seed} attempt {attempt}: {violation}");
            self.bar.suspend(|| eprintln!("{line}"));
        }
        Ok(record)
    }
}

/// empty_bin's line after an attempt: the objects moved so far, and where a carried object
/// came to rest when that was not bin 2 (what a user would otherwise see as an object that
/// vanished).
fn moved_line(record: &AttemptRecord, moved: usize, total: usize) -> String {
    let mut line = format!("{moved}/{total} objects moved");
    if let (Some(held), Some(placed)) = (&record.held, record.placed) {
        let rests = match placed {
            ObjectLocation::Bin1 => Some("back in bin 1"),
            ObjectLocation::Lost => Some("outside both bins"),
            ObjectLocation::Bin2 => None,
        };
        if let Some(rests) = rests {
            line += &format!(" ({held} was carried but came to rest {rests})");
        }
    }
    line
}

/// An object counts as moved by a push when its centre shifted more than this (m): less is
/// the settling of a pile that the stroke only brushed.
const PUSH_MOVED: f32 = 0.005;

/// Executes a push, and records where it went and what it moved.
fn push_and_record(cell: &mut Workcell, push: &WorldPush) -> (PickOutcome, PushRecord) {
    let before = positions(cell);
    let pushed = cell.push(push);
    let record = PushRecord {
        start: [push.start.x, push.start.y],
        end: [push.end.x, push.end.y],
        moved: moved_by_push(cell, &before),
    };
    let detail = format!("{}; {}", pushed.detail, record.describe());
    (PickOutcome::failure(PickReason::Pushed, detail), record)
}

/// Every object's centre now.
fn positions(cell: &Workcell) -> Vec<Vector> {
    (0..cell.objects().len())
        .map(|i| cell.object_centre(i))
        .collect()
}

/// The objects a push moved more than [`PUSH_MOVED`], farthest first, with how far (mm).
fn moved_by_push(cell: &Workcell, before: &[Vector]) -> Vec<(String, f32)> {
    let mut moved: Vec<(String, f32)> = before
        .iter()
        .enumerate()
        .map(|(i, was)| {
            let shift = (cell.object_centre(i) - *was).length();
            (cell.objects()[i].model.name.clone(), shift)
        })
        .filter(|(_, shift)| *shift > PUSH_MOVED)
        .map(|(name, shift)| (name, 1000.0 * shift))
        .collect();
    moved.sort_by(|a, b| b.1.total_cmp(&a.1));
    moved
}

/// Where each object of an empty_bin scene ended up.
fn bin_outcome(cell: &Workcell, gave_up: bool) -> BinOutcome {
    // A scene may list an object twice (VPG's cases have two Block1s): the second is "#2".
    let mut locations: BTreeMap<String, ObjectLocation> = BTreeMap::new();
    for (i, o) in cell.objects().iter().enumerate() {
        let mut key = o.model.name.clone();
        let mut copy = 1;
        while locations.contains_key(&key) {
            copy += 1;
            key = format!("{}#{copy}", o.model.name);
        }
        locations.insert(key, cell.locate(i));
    }
    BinOutcome {
        moved: count(cell, ObjectLocation::Bin2),
        left: count(cell, ObjectLocation::Bin1),
        lost: count(cell, ObjectLocation::Lost),
        locations,
        gave_up,
    }
}

fn count(cell: &Workcell, place: ObjectLocation) -> usize {
    (0..cell.objects().len())
        .filter(|&i| cell.locate(i) == place)
        .count()
}
