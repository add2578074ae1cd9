//! Workcell timings: a top-down frame, an oblique video frame, a frame with a dense mesh, and
//! one complete single-object pick attempt (drop, settle, image, oracle plan, pick, place).
//! Run: `cargo bench --bench workcell`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use graspmap::assets::objects::{ObjectLibrary, SplitFile};
use graspmap::grasp::world::world_grasp;
use graspmap::policy::oracle;
use graspmap::policy::verify::CheckConfig;
use graspmap::sim::Workcell;
use graspmap::vision::camera::Camera;
use graspmap::vision::render::{render, Drawable, Shape, TriMesh};
use rapier3d::math::{Pose, Vector};

fn median(mut samples: Vec<Duration>) -> Duration {
    samples.sort();
    samples[samples.len() / 2]
}

/// The median wall time of `runs` calls of `work`.
fn median_of<T>(runs: usize, mut work: impl FnMut() -> T) -> Duration {
    median(
        (0..runs)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(work());
                start.elapsed()
            })
            .collect(),
    )
}

fn main() {
    let library = ObjectLibrary::bundled();
    let split = SplitFile::Bundled.read().unwrap();
    let names = split.all();
    let models = library.load_all(&names).unwrap();
    let camera = Camera::top_down();

    // A full bin: all 15 objects, the worst case for the renderer.
    let mut cell = Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(&models, 2).unwrap();
    let scene = cell.drawables();
    let frames = median_of(200, || render(&camera, &scene));
    println!(
        "render 128x128, {} drawables (15 objects + arm + totes): median {:.2} ms",
        scene.len(),
        frames.as_secs_f64() * 1e3
    );

    let oblique = graspmap::sim::oblique_camera();
    let video = median_of(20, || render(&oblique, &scene));
    println!(
        "render {}x{} oblique video frame, same scene: median {:.2} ms",
        oblique.width,
        oblique.height,
        video.as_secs_f64() * 1e3
    );
    let sphere = Arc::new(uv_sphere(0.08, 100, 150));
    let mut with_mesh = scene.clone();
    with_mesh.push(Drawable {
        shape: Shape::Mesh(sphere.clone()),
        pose: Pose::from_translation(Vector::new(0.5, 0.0, 0.1)),
        color: [0.5; 3],
        id: 99,
    });
    let meshed = median_of(50, || render(&camera, &with_mesh));
    println!(
        "render 128x128, same scene + a {}-triangle mesh: median {:.2} ms",
        sphere.triangles.len(),
        meshed.as_secs_f64() * 1e3
    );

    let mut attempts = Vec::new();
    let mut sim_seconds = 0.0;
    let mut successes = 0;
    for model in &models {
        for seed in 1..=3 {
            let start = Instant::now();
            let mut cell = Workcell::new(&Default::default()).unwrap();
            cell.drop_objects(std::slice::from_ref(model), seed)
                .unwrap();
            let frame = cell.capture();
            if let Ok(plan) = oracle::plan(&camera, &frame, 1, &CheckConfig::default()) {
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
