//! Which objects a labelling round drops with `label --clutter K` (docs/data.md, "Clutter rounds").
//!
//! Pure: a function of the round's object, the training set's size, K and the round's seed, so
//! that a round replays exactly (resume, `--backfill-depth`) and tests can rebuild its scene.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Stream of the round seed's generator that picks the companions; the drop poses use stream 0,
/// random policies 1 and the scripted clicker's noise 2.
const CLUTTER_STREAM: u64 = 3;

/// The training-object indices that round `round_seed` of object `j` drops, in drop order: `j`
/// and `clutter − 1` others drawn without replacement from the other `n_train − 1`, shuffled
/// together with the round seed. With `clutter` 1 it is `[j]`, the reference protocol's round,
/// and no random draw happens, so those rounds are the same as before clutter existed.
///
/// Panics unless 1 ≤ `clutter` ≤ `n_train` and `j` < `n_train` (the CLI checks both).
pub fn round_objects(j: usize, n_train: usize, clutter: usize, round_seed: u64) -> Vec<usize> {
    assert!(j < n_train, "object {j} of {n_train}");
    assert!(
        (1..=n_train).contains(&clutter),
        "--clutter {clutter} with {n_train} training objects"
    );
    if clutter == 1 {
        return vec![j];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(round_seed);
    rng.set_stream(CLUTTER_STREAM);
    let mut others: Vec<usize> = (0..n_train).filter(|&i| i != j).collect();
    others.shuffle(&mut rng);
    others.truncate(clutter - 1);
    others.push(j);
    others.shuffle(&mut rng);
    others
}

/// The camera mask id of the round's object: the simulator numbers objects 1, 2, … in drop order.
pub fn round_object_id(order: &[usize], j: usize) -> u16 {
    let at = order
        .iter()
        .position(|&i| i == j)
        .expect("the round's object is in its drop order");
    at as u16 + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clutter_rounds_are_seeded_and_hold_the_round_object_once() {
        assert_eq!(
            round_objects(2, 5, 1, 7),
            vec![2],
            "K = 1 is the reference round"
        );
        let mut orders = std::collections::BTreeSet::new();
        for seed in 0..200u64 {
            let order = round_objects(3, 5, 3, seed);
            assert_eq!(order, round_objects(3, 5, 3, seed), "same seed, same round");
            assert_eq!(order.len(), 3);
            assert_eq!(order.iter().filter(|&&i| i == 3).count(), 1, "{order:?}");
            let mut unique = order.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), 3, "distinct objects {order:?}");
            assert!(order.iter().all(|&i| i < 5));
            assert_eq!(order[round_object_id(&order, 3) as usize - 1], 3);
            orders.insert(order);
        }
        // 4·3 companion pairs × 3 positions × 2 orders of the companions = 24 possible drops.
        assert!(orders.len() > 20, "only {} distinct drops", orders.len());
        assert_eq!(
            round_objects(0, 5, 5, 11).len(),
            5,
            "K = n drops every object"
        );
    }
}
