//! Workcell timings: one top-down frame, and one complete single-object pick attempt (drop,
//! settle, image, oracle plan, pick, place). Run: `cargo bench --bench workcell`.

use std::path::Path;
use std::time::{Duration, Instant};

use graspmap::camera::Camera;
use graspmap::grasp::world_grasp;
use graspmap::objects::{ObjectLibrary, Split};
use graspmap::oracle::{self, OracleConfig};
use graspmap::render::render;
use graspmap::sim::Workcell;

fn median(mut samples: Vec<Duration>) -> Duration {
    samples.sort();
    samples[samples.len() / 2]
}

fn main() {
    let assets = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets"));
    let library = ObjectLibrary::new(assets.join("objects"));
    let split = Split::read(&assets.join("objects/split.json")).unwrap();
    let names = split.all();
    let models = library.load_all(&names).unwrap();
    let camera = Camera::top_down();

    // A full bin: all 15 objects, the worst case for the renderer.
    let mut cell = Workcell::new(assets, &Default::default()).unwrap();
    cell.drop_objects(&models, 2).unwrap();
    let scene = cell.drawables();
    let frames: Vec<Duration> = (0..200)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(render(&camera, &scene));
            start.elapsed()
        })
        .collect();
    println!(
        "render 128x128, {} drawables (15 objects + arm + totes): median {:.2} ms",
        scene.len(),
        median(frames).as_secs_f64() * 1e3
    );

    let mut attempts = Vec::new();
    let mut sim_seconds = 0.0;
    let mut successes = 0;
    for model in &models {
        for seed in 1..=3 {
            let start = Instant::now();
            let mut cell = Workcell::new(assets, &Default::default()).unwrap();
            cell.drop_objects(std::slice::from_ref(model), seed)
                .unwrap();
            let frame = cell.capture();
            if let Ok(plan) = oracle::plan(&camera, &frame, 1, &OracleConfig::default()) {
                let outcome = cell.pick(&world_grasp(&camera, &frame, plan.grasp));
                successes += usize::from(outcome.success);
            }
            attempts.push(start.elapsed());
            sim_seconds += cell.time();
        }
    }
    let n = attempts.len();
    let total: Duration = attempts.iter().sum();
    println!(
        "pick attempt (drop, settle, image, plan, pick, place), {n} attempts: median {:.0} ms, mean {:.0} ms, max {:.0} ms; {:.1} simulated s per attempt; {successes}/{n} succeeded",
        median(attempts.clone()).as_secs_f64() * 1e3,
        total.as_secs_f64() * 1e3 / n as f64,
        attempts.iter().max().unwrap().as_secs_f64() * 1e3,
        sim_seconds / n as f64,
    );
}
