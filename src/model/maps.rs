//! The network's answer for one observation: [`BINS`] rotated affordance maps, and the argmax and
//! ranked actions rotated back into the original image (docs/evaluation.md). Their picture is
//! [`super::picture`]'s.
//!
//! Map `b` scores the observation rotated by −b · 22.5° (the same rotation as training, in
//! [`crate::data::augment`]), so a peak there is a horizontal grasp in the rotated image and a grasp at
//! angle b · 22.5° in the original. Everything here is pure: maps in, choices out.

use crate::grasp::rotate::{rotate_point, unrotate};
use crate::grasp::{angle_bin, bin_angle, PixelGrasp, BINS};

/// The network's scores for one observation: [`BINS`] maps of `size` × `size`, each in the frame
/// of the observation rotated by −bin · 22.5°, values in [0, 1].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AffordanceMaps {
    size: u32,
    values: Vec<f32>,
}

impl AffordanceMaps {
    /// Wraps bin-major, row-major scores; `values.len()` must be `BINS · size²`.
    pub(crate) fn new(size: u32, values: Vec<f32>) -> Self {
        assert_eq!(
            values.len(),
            BINS * (size * size) as usize,
            "{BINS} maps of {size}×{size} expected"
        );
        Self { size, values }
    }

    /// Score at (column `u`, row `v`) of map `bin`.
    pub(crate) fn get(&self, bin: usize, u: u32, v: u32) -> f32 {
        self.values[self.index(bin, u, v)]
    }

    /// One map, row-major.
    pub(crate) fn map(&self, bin: usize) -> &[f32] {
        let plane = (self.size * self.size) as usize;
        &self.values[bin * plane..(bin + 1) * plane]
    }

    /// Side of each map in pixels.
    pub(crate) fn size(&self) -> u32 {
        self.size
    }

    /// Subtracts a Gaussian of height `peak` and `sigma_px` around `centre` (a point in map
    /// `bin`'s frame), out to 3σ, and clips to [0, 1]: failure suppression's lowering of one map.
    pub(crate) fn lower_around(&mut self, bin: usize, centre: [f32; 2], sigma_px: f32, peak: f32) {
        let two_var = 2.0 * sigma_px * sigma_px;
        let reach = (3.0 * sigma_px).ceil() as i64;
        let [cx, cy] = centre;
        let (iu, iv) = (cx.floor() as i64, cy.floor() as i64);
        let last = i64::from(self.size) - 1;
        for v in (iv - reach).max(0)..=(iv + reach).min(last) {
            for u in (iu - reach).max(0)..=(iu + reach).min(last) {
                let du = u as f32 + 0.5 - cx;
                let dv = v as f32 + 0.5 - cy;
                let i = self.index(bin, u as u32, v as u32);
                let lowered = self.values[i] - peak * (-(du * du + dv * dv) / two_var).exp();
                self.values[i] = lowered.clamp(0.0, 1.0);
            }
        }
    }

    /// Zeroes the scores of actions that are not allowed (`allowed` in the same layout).
    pub(crate) fn restrict(&mut self, allowed: &[bool]) {
        assert_eq!(allowed.len(), self.values.len(), "one flag per score");
        for (value, &ok) in self.values.iter_mut().zip(allowed) {
            if !ok {
                *value = 0.0;
            }
        }
    }

    /// The action of an original-image grasp: its angle's bin, its centre in that bin's map and
    /// the score there (0 where the rotation leaves the map).
    pub(crate) fn choice_of(&self, grasp: PixelGrasp) -> Choice {
        let (bin, [x, y]) = self.map_position(grasp);
        let clip = |c: f32| (c.floor().max(0.0) as u32).min(self.size - 1);
        Choice {
            bin,
            rotated: [clip(x), clip(y)],
            grasp,
            score: self.score_at(grasp),
        }
    }

    /// The score of an original-image grasp: its angle's map at its centre carried into that
    /// map's frame; 0 where the rotation leaves the map.
    pub(crate) fn score_at(&self, grasp: PixelGrasp) -> f32 {
        let (bin, [x, y]) = self.map_position(grasp);
        let inside = |c: f32| (0.0..self.size as f32).contains(&c);
        if inside(x) && inside(y) {
            self.get(bin, x as u32, y as u32)
        } else {
            0.0
        }
    }

    /// The bin of a grasp's angle and its centre carried into that bin's map frame.
    fn map_position(&self, grasp: PixelGrasp) -> (usize, [f32; 2]) {
        let bin = angle_bin(grasp.angle_deg);
        let centre = [grasp.u as f32 + 0.5, grasp.v as f32 + 0.5];
        (bin, rotate_point(centre, -bin_angle(bin), self.size))
    }

    fn index(&self, bin: usize, u: u32, v: u32) -> usize {
        (bin * self.size as usize + v as usize) * self.size as usize + u as usize
    }

    /// The best (bin, row, column), first in that order on ties (like argmax over the flattened
    /// batch), turned into a grasp in the original image.
    pub(crate) fn choose(&self) -> Choice {
        let (best, score) =
            self.values
                .iter()
                .copied()
                .enumerate()
                .fold((0, f32::NEG_INFINITY), |best, (i, s)| {
                    if s > best.1 {
                        (i, s)
                    } else {
                        best
                    }
                });
        self.choice_at(best, score)
    }

    /// The `count` best actions with a positive score, best first, ties in the order
    /// [`AffordanceMaps::choose`] breaks them.
    pub(crate) fn ranked(&self, count: usize) -> Vec<Choice> {
        let by_score =
            |a: &usize, b: &usize| self.values[*b].total_cmp(&self.values[*a]).then(a.cmp(b));
        let mut order: Vec<usize> = (0..self.values.len())
            .filter(|&i| self.values[i] > 0.0)
            .collect();
        if order.len() > count {
            order.select_nth_unstable_by(count, by_score);
            order.truncate(count);
        }
        order.sort_unstable_by(by_score);
        order
            .into_iter()
            .map(|i| self.choice_at(i, self.values[i]))
            .collect()
    }

    /// An action drawn with probability proportional to its score raised to 1/`temperature`:
    /// exploration that stays on what the network finds graspable (the empty floor scores near
    /// 0) while trying what its argmax would not. Falls back to the argmax when every score is 0.
    pub(crate) fn sample(&self, temperature: f32, rng: &mut impl rand::Rng) -> Choice {
        let power = 1.0 / temperature.max(1e-3);
        let weights = self
            .values
            .iter()
            .map(|&s| f64::from(s.max(0.0)).powf(f64::from(power)));
        match rand::distr::weighted::WeightedIndex::new(weights) {
            Ok(index) => {
                let i = rng.sample(&index);
                self.choice_at(i, self.values[i])
            }
            Err(_) => self.choose(),
        }
    }

    /// The action at a flat index into `values`.
    fn choice_at(&self, index: usize, score: f32) -> Choice {
        let plane = (self.size * self.size) as usize;
        let bin = index / plane;
        let (v, u) = (
            (index % plane) as u32 / self.size,
            (index % plane) as u32 % self.size,
        );
        Choice {
            bin,
            rotated: [u, v],
            grasp: unrotate(bin, u, v, self.size),
            score: score.max(0.0),
        }
    }
}

/// A chosen action.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Choice {
    /// Angle bin (the map it came from).
    pub(crate) bin: usize,
    /// Pixel [column, row] in the rotated map.
    pub(crate) rotated: [u32; 2],
    /// The grasp in the original image: the map pixel rotated back (or, when `eval`'s centring
    /// moved it, the executed grasp, and `bin`, `rotated` and `score` are its own).
    pub(crate) grasp: PixelGrasp,
    /// Affordance at the chosen pixel (after any suppression).
    pub(crate) score: f32,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use image::RgbImage;

    pub(crate) const SIZE: u32 = 128;

    pub(crate) fn empty_maps() -> AffordanceMaps {
        AffordanceMaps::new(SIZE, vec![0.0; BINS * (SIZE * SIZE) as usize])
    }

    #[test]
    fn a_peak_in_each_rotation_comes_back_at_its_original_pixel_and_angle() {
        // Put a grasp at a known original pixel, carry it into bin k's frame the way the dataset
        // does (continuous centre rotated by −k·22.5°, the pixel holding it), plant the peak
        // there, and expect prediction to return the original pixel within 1 px and angle k·22.5°.
        for &(x, y) in &[(64u32, 64u32), (30, 90), (100, 20), (10, 10), (120, 70)] {
            for bin in 0..BINS {
                let [rx, ry] =
                    rotate_point([x as f32 + 0.5, y as f32 + 0.5], -bin_angle(bin), SIZE);
                if !(0.0..SIZE as f32).contains(&rx) || !(0.0..SIZE as f32).contains(&ry) {
                    continue; // rotated out of the image: the network cannot score it there
                }
                let mut maps = empty_maps();
                let i = maps.index(bin, rx as u32, ry as u32);
                maps.values[i] = 0.9;
                let choice = maps.choose();
                assert_eq!(choice.bin, bin);
                assert_eq!(choice.rotated, [rx as u32, ry as u32]);
                assert_eq!(choice.grasp.angle_deg, bin as f32 * 22.5);
                let du = choice.grasp.u as i64 - x as i64;
                let dv = choice.grasp.v as i64 - y as i64;
                assert!(
                    du.abs() <= 1 && dv.abs() <= 1,
                    "bin {bin}: ({x}, {y}) came back as ({}, {})",
                    choice.grasp.u,
                    choice.grasp.v
                );
                assert!((choice.score - 0.9).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn the_round_trip_matches_the_training_rotation_of_a_labelled_grasp() {
        // make_sample puts the target peak where prediction must look; unrotating it must give
        // the label back.
        let image = RgbImage::new(SIZE, SIZE);
        for bin in 0..BINS {
            let label = PixelGrasp {
                u: 40 + bin as u32 * 5,
                v: 70,
                angle_deg: bin_angle(bin),
            };
            let sample = crate::data::dataset::make_sample(
                &crate::data::input::NetInput::rgb(image.clone()),
                crate::grasp::fingers(label),
            );
            let (pu, pv) = sample.center_pixel(SIZE).expect("inside");
            let back = unrotate(sample.bin, pu, pv, SIZE);
            assert!(
                (back.u as i64 - label.u as i64).abs() <= 1,
                "{back:?} vs {label:?}"
            );
            assert!(
                (back.v as i64 - label.v as i64).abs() <= 1,
                "{back:?} vs {label:?}"
            );
            assert_eq!(back.angle_deg, label.angle_deg);
        }
    }

    #[test]
    fn score_at_reads_a_grasp_from_its_angle_map() {
        for bin in 0..BINS {
            let grasp = PixelGrasp {
                u: 50,
                v: 70,
                angle_deg: bin_angle(bin),
            };
            let [rx, ry] = rotate_point([50.5, 70.5], -bin_angle(bin), SIZE);
            let mut maps = empty_maps();
            let i = maps.index(bin, rx as u32, ry as u32);
            maps.values[i] = 0.7;
            assert_eq!(maps.score_at(grasp), 0.7, "bin {bin}");
            let other = PixelGrasp {
                angle_deg: bin_angle((bin + 1) % BINS),
                ..grasp
            };
            assert_eq!(maps.score_at(other), 0.0, "bin {bin}");
        }
    }

    #[test]
    fn choice_of_a_grasp_is_the_action_that_unrotates_to_it() {
        let mut maps = empty_maps();
        let i = maps.index(6, 30, 90);
        maps.values[i] = 0.8;
        let peak = maps.choose();
        let back = maps.choice_of(peak.grasp);
        assert_eq!((back.bin, back.grasp), (peak.bin, peak.grasp));
        assert!(back.rotated[0].abs_diff(30) <= 1 && back.rotated[1].abs_diff(90) <= 1);
        assert_eq!(back.score, maps.get(6, back.rotated[0], back.rotated[1]));
    }

    #[test]
    fn corner_pixels_are_clipped_into_the_image() {
        for bin in 0..BINS {
            for (u, v) in [(0, 0), (127, 0), (0, 127), (127, 127)] {
                let g = unrotate(bin, u, v, SIZE);
                assert!(g.u < SIZE && g.v < SIZE);
            }
        }
    }

    #[test]
    fn ties_go_to_the_first_bin_row_and_column() {
        let mut maps = empty_maps();
        for (bin, u, v) in [(3, 5, 9), (3, 6, 8), (5, 1, 1)] {
            let i = maps.index(bin, u, v);
            maps.values[i] = 1.0;
        }
        let choice = maps.choose();
        assert_eq!((choice.bin, choice.rotated), (3, [6, 8]));
    }

    /// Maps of one static scene with three bumps of different heights, drawn where each rotated
    /// frame sees them (so every bin agrees on where the bumps are in the original image).
    pub(crate) fn bumpy_maps() -> AffordanceMaps {
        let mut maps = empty_maps();
        for bin in 0..BINS {
            for v in 0..SIZE {
                for u in 0..SIZE {
                    let [x, y] =
                        rotate_point([u as f32 + 0.5, v as f32 + 0.5], bin_angle(bin), SIZE);
                    let bump = |cx: f32, cy: f32, h: f32| {
                        h * (-((x - cx - 0.5).powi(2) + (y - cy - 0.5).powi(2)) / 50.0).exp()
                    };
                    let i = maps.index(bin, u, v);
                    let tilt = bin as f32 * 0.01;
                    maps.values[i] = bump(40.0, 60.0, 0.9 - tilt)
                        .max(bump(80.0, 70.0, 0.8 - tilt))
                        .max(bump(64.0, 30.0, 0.7 - tilt));
                }
            }
        }
        maps
    }

    #[test]
    fn ranked_lists_the_best_positive_actions_first_starting_with_the_argmax() {
        let maps = bumpy_maps();
        let ranked = maps.ranked(50);
        assert_eq!(ranked.len(), 50);
        assert_eq!(ranked[0], maps.choose());
        assert!(ranked.windows(2).all(|w| w[0].score >= w[1].score));
        for c in &ranked {
            assert_eq!(maps.get(c.bin, c.rotated[0], c.rotated[1]), c.score);
            assert_eq!(maps.choice_of(c.grasp).bin, c.bin);
        }
        // Only positive scores are actions worth trying.
        let mut sparse = empty_maps();
        for (bin, u, v, value) in [(2, 10, 20, 0.3), (5, 100, 7, 0.9), (7, 64, 64, 0.3)] {
            let i = sparse.index(bin, u, v);
            sparse.values[i] = value;
        }
        let order: Vec<(usize, [u32; 2])> = sparse
            .ranked(10)
            .iter()
            .map(|c| (c.bin, c.rotated))
            .collect();
        assert_eq!(order, [(5, [100, 7]), (2, [10, 20]), (7, [64, 64])]);
    }
}
