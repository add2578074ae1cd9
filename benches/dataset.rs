//! Training-sample timings on the reference fixture: one augmented sample (affine warp, rotation
//! to its bin, Gaussian target) against an unaugmented one. Run: `cargo bench --bench dataset`.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use graspmap::data::augment::AugmentConfig;
use graspmap::data::dataset::{load_dataset, training_sample, TrialWeighting};
use graspmap::data::input::InputKind;
use graspmap::data::labels::LabelStore;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn dataset(c: &mut Criterion) {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    let items = load_dataset(&LabelStore::new(fixture), InputKind::Rgb).expect("the fixture loads");
    let item = &items[0];
    let config = AugmentConfig {
        probability: 1.0,
        ..AugmentConfig::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut group = c.benchmark_group("dataset");
    group.bench_function("training_sample_augmented", |b| {
        b.iter(|| {
            training_sample(
                black_box(item),
                TrialWeighting::default(),
                Some((&config, &mut rng)),
            )
        })
    });
    group.bench_function("training_sample_plain", |b| {
        b.iter(|| training_sample(black_box(item), TrialWeighting::default(), None))
    });
    group.finish();
}

criterion_group!(benches, dataset);
criterion_main!(benches);
