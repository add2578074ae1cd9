//! `label --backfill-depth`: write the missing `<Object>_<k>_depth.png` of a dataset that graspmap
//! labelled before depth files existed, by replaying its rounds' drops (docs/data.md).
//!
//! Every round's drop is a pure function of its seed, so replaying round r of object j gives the
//! scene that round saw. Which rounds succeeded is not recorded, but a successful round's image
//! is stored: the rounds are replayed in order, and the k-th label's depth is the depth of the
//! first round after label k − 1's whose image equals `<Object>_<k>_rgb.png` byte for byte. No
//! grasp is executed, so any click source (scripted, file, a person) backfills the same way.

use anyhow::{bail, Context as _};

use super::rounds::{round_scene, round_seed};
use crate::commands::Context;
use crate::data::labels::LabelStore;
use crate::data::lock::StoreLock;
use crate::data::progress::PROGRESS_FILE;

/// Runs the backfill; returns the number of depth files written.
pub(super) fn backfill_depth(context: &Context, store: &LabelStore) -> anyhow::Result<usize> {
    let _writer = StoreLock::acquire(store.dir(), "label")?;
    let labels = store.load()?;
    let Some(progress) = store.load_progress()? else {
        bail!(
            "{}: no {PROGRESS_FILE}, so its rounds' seeds are unknown (a dataset from the reference \
             tool cannot be backfilled); relabel it with `graspmap label --force` to get depth files",
            store.dir().display()
        );
    };
    let split = context.split()?;
    let models = context.objects.load_all(&split.train)?;
    let mut written = 0;
    for (j, object) in split.train.iter().enumerate() {
        let n = labels.of(object).len();
        let missing = (1..=n).any(|k| !store.depth_path(object, k).exists());
        if !missing {
            continue;
        }
        let mut k = 1;
        for round in 0..progress.rounds_of(object) {
            if k > n {
                break;
            }
            let seed = round_seed(progress.seed, j, round)?;
            let (cell, _) = round_scene(&models, j, progress.clutter, seed)?;
            let frame = cell.capture();
            let image_path = store.image_path(object, k);
            let stored = image::open(&image_path)
                .with_context(|| format!("cannot read {}", image_path.display()))?
                .into_rgb8();
            if frame.to_rgb_image() != stored {
                continue;
            }
            let path = store.depth_path(object, k);
            if !path.exists() {
                crate::data::atomic::save_image_atomic(&frame.to_depth_image_mm(), &path)?;
                written += 1;
            }
            k += 1;
        }
        if k <= n {
            bail!(
                "{}: no round of {object} (seeds {}…, --clutter {}) reproduces this image, so its \
                 depth cannot be backfilled (was it labelled with another version of graspmap's \
                 physics?); relabel with `graspmap label --force`",
                store.image_path(object, k).display(),
                round_seed(progress.seed, j, 0)?,
                progress.clutter
            );
        }
    }
    context.say(&format!(
        "{}: wrote {written} depth images; every label now has one",
        store.dir().display()
    ));
    Ok(written)
}
