//! How `graspmap label` shares out its rounds: waves of the rounds each object still needs, played on the workers and stored in object and round order.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use anyhow::bail;

use super::{lock, round_line, rounds, ObjectJob, ObjectSummary, RoundDone, Shared, Tried};
use crate::assets::objects::ObjectModel;
use crate::grasp::PixelGrasp;
use crate::interrupt;
use crate::sim::pick::PickReason;
use crate::vision::render::Frame;

/// One round to play: training object `j`'s round `round`.
struct RoundJob {
    j: usize,
    round: u32,
}

/// A round played in the simulator, waiting to be stored in its turn.
struct Played {
    j: usize,
    round: u32,
    frame: Frame,
    click: Result<PixelGrasp, String>,
    tried: Tried,
}

impl ObjectJob<'_> {
    /// Labels every object on `workers` threads. The rounds, not the objects, are shared out: a
    /// run of five objects on two cores would otherwise leave one core idle for the fifth. Each
    /// wave plays, for every object still short, just the rounds that its missing labels need at
    /// the least (a round stores at most one label), so no round is played that one object at a
    /// time would not have played too; the rounds are stored in object and round order, so the
    /// files do not depend on which worker finishes first. One worker (a person clicking) takes
    /// the objects one after another, as before.
    pub(super) fn label_all(
        &self,
        objects: &[String],
        models: &[ObjectModel],
        shared: &Mutex<Shared>,
        workers: usize,
    ) -> anyhow::Result<Vec<ObjectSummary>> {
        let mut summaries: Vec<ObjectSummary> = objects
            .iter()
            .map(|object| ObjectSummary {
                object: object.clone(),
                ..Default::default()
            })
            .collect();
        let groups: Vec<Vec<usize>> = match workers {
            1 => (0..objects.len()).map(|j| vec![j]).collect(),
            _ => vec![(0..objects.len()).collect()],
        };
        for group in groups {
            loop {
                let wave = self.next_wave(&group, objects, shared)?;
                if wave.is_empty() || interrupt::requested().is_some() {
                    break;
                }
                self.play_wave(&wave, objects, models, shared, workers, &mut summaries)?;
            }
        }
        let state = lock(shared);
        for summary in &mut summaries {
            summary.rounds = state.progress.rounds_of(&summary.object);
            summary.labels = state.labels.of(&summary.object).len();
        }
        Ok(summaries)
    }

    /// The rounds that the objects of `group` still short of labels need at the least, or the
    /// error of one that has used up `--max-rounds`.
    fn next_wave(
        &self,
        group: &[usize],
        objects: &[String],
        shared: &Mutex<Shared>,
    ) -> anyhow::Result<Vec<RoundJob>> {
        let args = self.args;
        let state = lock(shared);
        let mut wave = Vec::new();
        for &j in group {
            let object = &objects[j];
            let have = state.labels.of(object).len();
            let round = state.progress.rounds_of(object);
            if have >= args.per_object as usize {
                continue;
            }
            if round >= args.max_rounds {
                bail!(
                    "{object}: only {have} of {} labels after {round} rounds (--max-rounds {}); raise --max-rounds or check the clicks",
                    args.per_object,
                    args.max_rounds
                );
            }
            let missing = args.per_object - have as u32;
            let last = round.saturating_add(missing).min(args.max_rounds);
            wave.extend((round..last).map(|round| RoundJob { j, round }));
        }
        Ok(wave)
    }

    /// Plays a wave's rounds on `workers` threads and stores each in wave order.
    fn play_wave(
        &self,
        wave: &[RoundJob],
        objects: &[String],
        models: &[ObjectModel],
        shared: &Mutex<Shared>,
        workers: usize,
        summaries: &mut [ObjectSummary],
    ) -> anyhow::Result<()> {
        if workers == 1 {
            // By hand, a round is stored (and the page told) before the next one is shown.
            for job in wave {
                let Some(played) = self.play(job, &objects[job.j], models)? else {
                    break;
                };
                self.store_round(played, objects, shared, summaries)?;
            }
            return Ok(());
        }
        // A round that cannot be stored stops the wave: the rounds after it are not played.
        let unstored = AtomicBool::new(false);
        let mut stored = Ok(());
        crate::commands::workers::run_in_order(
            wave,
            workers,
            || Ok(()),
            |(), job| match unstored.load(Ordering::SeqCst) {
                true => Ok(None),
                false => self.play(job, &objects[job.j], models),
            },
            |played| {
                if stored.is_ok() {
                    stored = self.store_round(played, objects, shared, summaries);
                    unstored.store(stored.is_err(), Ordering::SeqCst);
                }
            },
        )?;
        stored
    }

    /// Plays one round: its scene, the click and the pick. `None` when a signal asked to stop:
    /// the object resumes on the next run, from the rounds saved so far.
    fn play(
        &self,
        job: &RoundJob,
        object: &str,
        models: &[ObjectModel],
    ) -> anyhow::Result<Option<Played>> {
        if interrupt::requested().is_some() {
            return Ok(None);
        }
        let RoundJob { j, round } = *job;
        let round_seed = rounds::round_seed(self.args.seed, j, round)?;
        self.bar.set_message(format!("{object} round {round}"));
        let (mut cell, id) = rounds::round_scene(models, j, self.args.clutter, round_seed)?;
        let frame = cell.capture();
        let camera = *cell.camera();
        let click = self
            .clicker
            .click(object, id, round, round_seed, &camera, &frame)?;
        let tried = self.try_click(&mut cell, &frame, &click);
        Ok(Some(Played {
            j,
            round,
            frame,
            click,
            tried,
        }))
    }

    /// Stores a played round and says how it went when it failed (or always, by hand).
    fn store_round(
        &self,
        played: Played,
        objects: &[String],
        shared: &Mutex<Shared>,
        summaries: &mut [ObjectSummary],
    ) -> anyhow::Result<()> {
        let object = &objects[played.j];
        let (reason, detail) = (played.tried.0, played.tried.1.clone());
        let line = round_line(object, played.round, &played.click, reason, &detail);
        let done = RoundDone {
            object,
            rounds: played.round + 1,
            frame: &played.frame,
            click: &played.click,
            tried: played.tried,
        };
        self.record_round(shared, done, &mut summaries[played.j])?;
        if self.verbose_rounds || reason != PickReason::Success {
            self.bar.suspend(|| self.context.say(&line));
        }
        Ok(())
    }
}
