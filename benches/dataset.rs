//! Training-sample timings on the reference fixture: one augmented sample (affine warp, rotation
//! to its bin, Gaussian target) against an unaugmented one. Run: `cargo bench --bench dataset`.

use std::path::Path;
use std::time::Instant;

use graspmap::data::augment::AugmentConfig;
use graspmap::data::dataset::{load_dataset, training_sample};
use graspmap::data::input::InputKind;
use graspmap::data::labels::LabelStore;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn main() {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    let items = load_dataset(&LabelStore::new(fixture), InputKind::Rgb).expect("the fixture loads");
    let item = &items[0];
    let config = AugmentConfig {
        probability: 1.0,
        ..AugmentConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let n = 2000;
    let mut checksum = 0.0;
    let start = Instant::now();
    for _ in 0..n {
        checksum += training_sample(
            item,
            graspmap::data::dataset::TrialWeighting::default(),
            Some((&config, &mut rng)),
        )
        .target[0];
    }
    let augmented = start.elapsed() / n;
    let start = Instant::now();
    for _ in 0..n {
        checksum += training_sample(
            item,
            graspmap::data::dataset::TrialWeighting::default(),
            None,
        )
        .target[0];
    }
    let plain = start.elapsed() / n;
    println!(
        "training sample: augmented {augmented:?}, unaugmented {plain:?} (checksum {checksum})"
    );
}
