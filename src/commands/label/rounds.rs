//! One labelling round's scene: which objects it drops (`--clutter`) and with which seed, shared
//! by labelling and `--backfill-depth`, so that a replayed round is the same drop, bit for bit.

use crate::assets::objects::ObjectModel;
use crate::data::clutter::{round_object_id, round_objects};
use crate::data::seeds::{derived_seed, SeedOverflow};
use crate::sim::{Workcell, WorkcellConfig};

/// The seed of round `round` of training object `j`: base + 100·j + r (docs/data.md).
pub(super) fn round_seed(base: u64, j: usize, round: u32) -> Result<u64, SeedOverflow> {
    let offset = 100 * j as u64 + u64::from(round);
    derived_seed(
        base,
        1,
        offset,
        "seed + 100·j + r for round r of training object j",
    )
}

/// A workcell with round `seed`'s objects dropped into bin 1 (object `j` of `models` and, with
/// `clutter` K > 1, K − 1 other training objects), and the camera mask id of object `j`.
pub(super) fn round_scene(
    models: &[ObjectModel],
    j: usize,
    clutter: u32,
    seed: u64,
) -> anyhow::Result<(Workcell, u16)> {
    let order = round_objects(j, models.len(), clutter as usize, seed);
    let dropped: Vec<ObjectModel> = order.iter().map(|&i| models[i].clone()).collect();
    let mut cell = Workcell::new(&WorkcellConfig::default())?;
    cell.drop_objects(&dropped, seed)?;
    Ok((cell, round_object_id(&order, j)))
}
