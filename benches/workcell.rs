//! Workcell timings: a top-down frame, an oblique video frame, a frame with a dense mesh, and
//! one complete single-object pick attempt (drop, settle, image, oracle plan, pick, place).
//! Run: `cargo bench --bench workcell`. Criterion writes its estimates under
//! target/criterion/workcell/; facts.json beside them holds what a time alone does not say (the
//! scene's size, the simulated seconds per attempt), for scripts/benchmarks.sh.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use graspmap::assets::objects::{ObjectLibrary, ObjectModel, SplitFile};
use graspmap::grasp::world::world_grasp;
use graspmap::policy::oracle;
use graspmap::policy::verify::CheckConfig;
use graspmap::sim::Workcell;
use graspmap::vision::camera::Camera;
use graspmap::vision::render::{render, Drawable, Shape, TriMesh};
use rapier3d::math::{Pose, Vector};

const SEEDS: std::ops::RangeInclusive<u64> = 1..=3;

/// One single-object pick attempt from an empty workcell: (success, simulated seconds).
fn attempt(model: &ObjectModel, seed: u64, camera: &Camera) -> (bool, f64) {
    let mut cell = Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(std::slice::from_ref(model), seed)
        .unwrap();
    let frame = cell.capture();
    let success = match oracle::plan(camera, &frame, 1, &CheckConfig::default()) {
        Ok(plan) => cell.pick(&world_grasp(camera, &frame, plan.grasp)).success,
        Err(_) => false,
    };
    (success, cell.time())
}

/// Where criterion writes, found the way criterion finds it.
fn criterion_home() -> PathBuf {
    match (
        std::env::var_os("CRITERION_HOME"),
        std::env::var_os("CARGO_TARGET_DIR"),
    ) {
        (Some(home), _) => home.into(),
        (None, Some(target)) => PathBuf::from(target).join("criterion"),
        (None, None) => PathBuf::from("target/criterion"),
    }
}

fn workcell(c: &mut Criterion) {
    let library = ObjectLibrary::bundled();
    let split = SplitFile::Bundled.read().unwrap();
    let models = library.load_all(&split.all()).unwrap();
    let camera = Camera::top_down();

    // A full bin: all 15 objects, the worst case for the renderer.
    let mut cell = Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(&models, 2).unwrap();
    let scene = cell.drawables();
    let oblique = graspmap::sim::oblique_camera();
    let sphere = Arc::new(uv_sphere(0.08, 100, 150));
    let mut with_mesh = scene.clone();
    with_mesh.push(Drawable {
        shape: Shape::Mesh(sphere.clone()),
        pose: Pose::from_translation(Vector::new(0.5, 0.0, 0.1)),
        color: [0.5; 3],
        id: 99,
    });

    let mut group = c.benchmark_group("workcell");
    group.bench_function("top_down_frame", |b| {
        b.iter(|| render(&camera, black_box(&scene)))
    });
    group.bench_function("oblique_frame", |b| {
        b.iter(|| render(&oblique, black_box(&scene)))
    });
    group.bench_function("top_down_frame_dense_mesh", |b| {
        b.iter(|| render(&camera, black_box(&with_mesh)))
    });

    // Every object and seed in turn, so that the estimate covers them all.
    let cases: Vec<(&ObjectModel, u64)> = models
        .iter()
        .flat_map(|m| SEEDS.map(move |seed| (m, seed)))
        .collect();
    let mut next = 0;
    group.sample_size(10).sampling_mode(SamplingMode::Flat);
    group.measurement_time(Duration::from_secs(15));
    group.bench_function("pick_attempt", |b| {
        b.iter(|| {
            let (model, seed) = cases[next % cases.len()];
            next += 1;
            attempt(model, seed, &camera)
        })
    });
    group.finish();

    let outcomes: Vec<(bool, f64)> = cases.iter().map(|&(m, s)| attempt(m, s, &camera)).collect();
    let facts = serde_json::json!({
        "drawables": scene.len(),
        "oblique": format!("{}x{}", oblique.width, oblique.height),
        "mesh_triangles": sphere.triangles.len(),
        "objects": models.len(),
        "seeds": format!("{}–{}", SEEDS.start(), SEEDS.end()),
        "attempts": outcomes.len(),
        "successes": outcomes.iter().filter(|o| o.0).count(),
        "sim_s_per_attempt": outcomes.iter().map(|o| o.1).sum::<f64>() / outcomes.len() as f64,
    });
    let path = criterion_home().join("workcell").join("facts.json");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, serde_json::to_string_pretty(&facts).unwrap()).unwrap();
}

criterion_group!(benches, workcell);
criterion_main!(benches);

/// A UV sphere of `stacks` × `slices` quads, two triangles each.
fn uv_sphere(r: f32, stacks: u32, slices: u32) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..=stacks {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        for j in 0..slices {
            let phi = std::f32::consts::TAU * j as f32 / slices as f32;
            let (sin_t, cos_t) = theta.sin_cos();
            vertices.push(r * Vector::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
        }
    }
    let mut triangles = Vec::new();
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b) = (i * slices + j, i * slices + (j + 1) % slices);
            triangles.push([a, a + slices, b]);
            triangles.push([b, a + slices, b + slices]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}
