//! An object's true size: the smallest box around its collision geometry in any orientation.
//!
//! The axis-aligned box of a model file is not the object's size when the model lies rotated
//! in its own frame (several of the public YCB meshes do), so sizes are compared this way: the
//! box's sides sorted, narrowest first, which is what a parallel jaw must span.

use rapier3d::math::Vector;

use crate::assets::urdf::{Collision, CollisionShape};

/// Points sampled around a round shape's circumference.
const ROUND_SAMPLES: usize = 64;

type Mat3 = [[f64; 3]; 3];

/// The sides of the smallest box around `collisions`, in metres, sorted ascending.
///
/// A local search over rotations from many starts (the identity, each piece's own axes, and a
/// coarse grid of orientations), each refined by halving steps about the box's three axes. It
/// finds the optimum of every shape the models use to well under a millimetre.
pub(crate) fn true_size(collisions: &[Collision]) -> [f64; 3] {
    let points: Vec<[f64; 3]> = collisions.iter().flat_map(surface_points).collect();
    let mut starts: Vec<Mat3> = vec![IDENTITY];
    starts.extend(collisions.iter().map(|c| {
        let r = c.pose.rotation;
        let columns = [r * Vector::X, r * Vector::Y, r * Vector::Z];
        std::array::from_fn(|i| std::array::from_fn(|j| f64::from(columns[i][j])))
    }));
    for yaw in (0..180).step_by(30) {
        for pitch in (0..180).step_by(45) {
            let (yaw, pitch) = (f64::from(yaw).to_radians(), f64::from(pitch).to_radians());
            starts.push(mul(&about(2, yaw), &about(0, pitch)));
        }
    }
    let best = starts
        .iter()
        .map(|start| descend(&points, *start))
        .min_by(|a, b| volume(a).total_cmp(&volume(b)))
        .unwrap_or([0.0; 3]);
    let mut sides = best;
    sides.sort_by(f64::total_cmp);
    sides
}

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn volume(sides: &[f64; 3]) -> f64 {
    sides[0] * sides[1] * sides[2]
}

/// The box's sides after a greedy descent from `rotation`: try ± the step about each axis,
/// keep any turn that shrinks the box, and halve the step when none does.
fn descend(points: &[[f64; 3]], mut rotation: Mat3) -> [f64; 3] {
    let mut sides = extents(points, &rotation);
    let mut step = 10f64.to_radians();
    while step > 0.05f64.to_radians() {
        let mut improved = false;
        for axis in 0..3 {
            for sign in [1.0, -1.0] {
                let turned = mul(&about(axis, sign * step), &rotation);
                let turned_sides = extents(points, &turned);
                if volume(&turned_sides) < volume(&sides) - 1e-15 {
                    (rotation, sides, improved) = (turned, turned_sides, true);
                }
            }
        }
        if !improved {
            step /= 2.0;
        }
    }
    sides
}

/// The extent of `points` along each row of `rotation`.
fn extents(points: &[[f64; 3]], rotation: &Mat3) -> [f64; 3] {
    std::array::from_fn(|i| {
        let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            let d = rotation[i][0] * p[0] + rotation[i][1] * p[1] + rotation[i][2] * p[2];
            (lo.min(d), hi.max(d))
        });
        hi - lo
    })
}

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// A rotation by `angle` about coordinate axis `axis` (0 = x, 1 = y, 2 = z).
fn about(axis: usize, angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

/// Points on a piece's surface in the object frame, enough to bound it: a box's corners, two
/// rings for a cylinder, rings and poles for spheres and capsules, a hull's own points.
fn surface_points(collision: &Collision) -> Vec<[f64; 3]> {
    let ring = |r: f32, y: f32| {
        (0..ROUND_SAMPLES).map(move |i| {
            let a = i as f32 * std::f32::consts::TAU / ROUND_SAMPLES as f32;
            Vector::new(r * a.cos(), y, r * a.sin())
        })
    };
    // A sphere (capsule when `half` > 0) along y: latitude rings every 1/16 of a turn.
    let round = |r: f32, half: f32| {
        let mut points = vec![
            Vector::new(0.0, r + half, 0.0),
            Vector::new(0.0, -r - half, 0.0),
        ];
        for band in 0..8 {
            let polar = band as f32 * std::f32::consts::FRAC_PI_2 / 8.0;
            let (ring_r, ring_y) = (r * polar.cos(), r * polar.sin());
            points.extend(ring(ring_r, half + ring_y));
            points.extend(ring(ring_r, -half - ring_y));
        }
        points
    };
    let local: Vec<Vector> = match &collision.shape {
        CollisionShape::Cuboid { half_extents: h } => (0..8)
            .map(|corner| {
                let sign = |bit: i32| if corner & bit == 0 { -1.0 } else { 1.0 };
                Vector::new(sign(1) * h.x, sign(2) * h.y, sign(4) * h.z)
            })
            .collect(),
        CollisionShape::Sphere { radius } => round(*radius, 0.0),
        CollisionShape::Capsule {
            radius,
            half_height,
        } => round(*radius, *half_height),
        CollisionShape::Cylinder {
            radius,
            half_height,
        } => ring(*radius, *half_height)
            .chain(ring(*radius, -*half_height))
            .collect(),
        CollisionShape::ConvexHull { points } => points.clone(),
    };
    local
        .into_iter()
        .map(|p| {
            let q = collision.pose.transform_point(p);
            [f64::from(q.x), f64::from(q.y), f64::from(q.z)]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::objects::ObjectLibrary;
    use rapier3d::math::{Pose, Rotation};

    /// The reference's table: assets/ycb-meshes/SIZES.md, the one source of the true sizes.
    const SIZES_MD: &str = include_str!("../../assets/ycb-meshes/SIZES.md");

    struct Reference {
        name: String,
        size_mm: [f64; 3],
        mass: f32,
        friction: f32,
    }

    fn reference_table() -> Vec<Reference> {
        SIZES_MD
            .lines()
            .filter(|line| line.starts_with("| Ycb"))
            .map(|line| {
                let cells: Vec<&str> = line.split('|').map(str::trim).collect();
                let size: Vec<f64> = cells[4]
                    .split('×')
                    .map(|s| s.trim().parse().unwrap())
                    .collect();
                Reference {
                    name: cells[1].to_owned(),
                    size_mm: [size[0], size[1], size[2]],
                    mass: cells[6].parse().unwrap(),
                    friction: cells[7].parse().unwrap(),
                }
            })
            .collect()
    }

    fn size_mm(library: &ObjectLibrary, name: &str) -> [f64; 3] {
        let model = library.load(name).unwrap();
        true_size(&model.collisions).map(|s| s * 1000.0)
    }

    #[test]
    fn a_rotated_box_measures_its_own_sides() {
        let rotation = Rotation::from_rotation_z(0.5) * Rotation::from_rotation_x(0.3);
        let box_piece = Collision {
            shape: CollisionShape::Cuboid {
                half_extents: Vector::new(0.014, 0.036, 0.0435),
            },
            pose: Pose::from_parts(Vector::new(0.1, 0.0, 0.0), rotation),
        };
        let sides = true_size(&[box_piece]).map(|s| s * 1000.0);
        for (got, want) in sides.iter().zip([28.0, 72.0, 87.0]) {
            assert!((got - want).abs() < 0.1, "{sides:?}");
        }
    }

    #[test]
    fn the_bundled_models_have_the_reference_objects_sizes_masses_and_friction() {
        let table = reference_table();
        assert_eq!(table.len(), 15);
        let bundled = ObjectLibrary::bundled();
        let mut problems = Vec::new();
        for reference in &table {
            let model = bundled.load(&reference.name).unwrap();
            let sides = size_mm(&bundled, &reference.name);
            for (got, want) in sides.iter().zip(reference.size_mm) {
                if (got - want).abs() > (0.1 * want).max(5.0) {
                    problems.push(format!(
                        "{} size {sides:.0?} mm, reference {:?}",
                        reference.name, reference.size_mm
                    ));
                    break;
                }
            }
            if model.mass != reference.mass || model.friction != reference.friction {
                problems.push(format!(
                    "{}: mass {} kg, μ {}; reference {} kg, μ {}",
                    reference.name, model.mass, model.friction, reference.mass, reference.friction
                ));
            }
        }
        assert!(problems.is_empty(), "{}", problems.join("\n"));
    }

    /// The same measurement on the reference's own meshes gives the table's figures, so the
    /// check above measures what the table means. Within 3 mm: for the near-round strawberry
    /// the smallest box by volume (42 × 44 × 44) differs from the table's (41 × 44 × 47).
    #[test]
    fn the_reference_meshes_measure_as_the_table_says() {
        let meshes = ObjectLibrary::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/ycb-meshes"));
        for reference in reference_table() {
            let sides = size_mm(&meshes, &reference.name);
            for (got, want) in sides.iter().zip(reference.size_mm) {
                assert!(
                    (got - want).abs() <= 3.0,
                    "{}: {sides:.1?} against {:?}",
                    reference.name,
                    reference.size_mm
                );
            }
        }
    }
}
