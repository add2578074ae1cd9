//! The labelling page's state: the round waiting for a click, the cursor, the last attempt and
//! its animation. The labelling loop and the server thread meet here.
//!
//! The state lives in the server, not the page, so closing the tab and opening it again
//! continues where it was.

use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

use image::RgbImage;

use super::{Reply, Request};
use crate::grasp::draw::JawPx;
use crate::grasp::{normalize_angle, PixelGrasp, BIN_DEG, FINGER_OFFSET_PX, IMAGE_SIZE};
use crate::interrupt;
use crate::vision::camera::Camera;

/// The labelling page and its script.
const LABEL_MAIN: &str = include_str!("page/label.html");
const LABEL_JS: &str = include_str!("page/label.js");

/// Physics steps between two frames of an attempt's animation: 15 frames per simulated second.
pub(crate) const FILM_EVERY_STEPS: u64 = 16;

/// The pads' width across the closing line in image pixels, at the tote floor.
pub(crate) fn pad_width_px(camera: &Camera) -> f32 {
    JawPx::at_floor(camera).map_or(4.0, |jaw| jaw.pad_width)
}

/// The most animation frames sent for one attempt; longer attempts are sampled evenly.
const MAX_ANIMATION_FRAMES: usize = 90;

/// A round shown on the page.
struct RoundView {
    id: u64,
    object: String,
    round: u32,
    png: Vec<u8>,
}

/// What the last attempt did, with its animation as one JPEG of frames stacked vertically.
pub(crate) struct AttemptView {
    pub(crate) object: String,
    pub(crate) round: u32,
    pub(crate) grasp: Option<PixelGrasp>,
    pub(crate) reason: String,
    pub(crate) detail: String,
    pub(crate) stored: bool,
    pub(crate) frames: Vec<RgbImage>,
}

struct Attempt {
    id: u64,
    view: AttemptView,
    strip: Vec<u8>,
    frame_size: (u32, u32),
    frame_count: usize,
}

#[derive(Default)]
struct State {
    round: Option<RoundView>,
    running: bool,
    centre: Option<(u32, u32)>,
    angle_deg: f32,
    confirmed: Option<PixelGrasp>,
    last: Option<Attempt>,
    done: bool,
    refill: bool,
    next_id: u64,
}

/// The shared state of one `label --web` session.
#[derive(Default)]
pub(crate) struct LabelSession {
    state: Mutex<State>,
    changed: Condvar,
    /// Pad width across the closing line, in image pixels, for the cursor drawing.
    pub(crate) pad_px: f32,
}

impl LabelSession {
    /// A session whose cursor draws pads `pad_px` wide.
    pub(crate) fn new(pad_px: f32) -> Self {
        LabelSession {
            pad_px,
            ..Default::default()
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Shows a round and waits for the person's confirmed grasp; a signal ends the wait.
    pub(crate) fn await_click(
        &self,
        object: &str,
        round: u32,
        image: &RgbImage,
    ) -> anyhow::Result<PixelGrasp> {
        let mut png = std::io::Cursor::new(Vec::new());
        image.write_to(&mut png, image::ImageFormat::Png)?;
        let mut state = self.lock();
        state.next_id += 1;
        state.round = Some(RoundView {
            id: state.next_id,
            object: object.to_owned(),
            round,
            png: png.into_inner(),
        });
        state.running = false;
        state.done = false;
        state.centre = None;
        state.angle_deg = 0.0;
        state.confirmed = None;
        self.changed.notify_all();
        loop {
            if let Some(grasp) = state.confirmed.take() {
                return Ok(grasp);
            }
            if let Some(interrupted) = interrupt::requested() {
                return Err(interrupted.into());
            }
            state = self
                .changed
                .wait_timeout(state, Duration::from_millis(100))
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .0;
        }
    }

    /// Publishes an attempt's outcome; the page shows it and its animation.
    pub(crate) fn finish_attempt(&self, view: AttemptView) -> anyhow::Result<()> {
        let step = view.frames.len().div_ceil(MAX_ANIMATION_FRAMES).max(1);
        let frames: Vec<&RgbImage> = view.frames.iter().step_by(step).collect();
        let frame_size = frames.first().map_or((0, 0), |f| f.dimensions());
        let mut strip = RgbImage::new(frame_size.0, frame_size.1 * frames.len() as u32);
        for (i, frame) in frames.iter().enumerate() {
            image::imageops::replace(&mut strip, *frame, 0, i64::from(frame_size.1) * i as i64);
        }
        let mut jpeg = std::io::Cursor::new(Vec::new());
        if !frames.is_empty() {
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 85)
                .encode_image(&strip)?;
        }
        let frame_count = frames.len();
        let mut state = self.lock();
        state.next_id += 1;
        state.last = Some(Attempt {
            id: state.next_id,
            view: AttemptView {
                frames: Vec::new(),
                ..view
            },
            strip: jpeg.into_inner(),
            frame_size,
            frame_count,
        });
        state.running = false;
        // That round is over: nothing on the page may click or confirm it any more.
        state.round = None;
        self.changed.notify_all();
        Ok(())
    }

    /// Every object has its labels: the page says so.
    pub(crate) fn set_done(&self) {
        let mut state = self.lock();
        state.done = true;
        state.round = None;
        self.changed.notify_all();
    }

    /// A label was deleted: the labelling loop has a round to run again.
    pub(crate) fn request_refill(&self) {
        self.lock().refill = true;
        self.changed.notify_all();
    }

    /// Waits until a deleted label asks for more rounds (true) or a signal arrives (false).
    pub(crate) fn wait_for_refill(&self) -> bool {
        let mut state = self.lock();
        loop {
            if std::mem::take(&mut state.refill) {
                return true;
            }
            if interrupt::requested().is_some() {
                return false;
            }
            state = self
                .changed
                .wait_timeout(state, Duration::from_millis(100))
                .unwrap_or_else(|poisoned| poisoned.into_inner())
                .0;
        }
    }

    /// The page's routes; `dataset` describes the labels so far (counts per object).
    pub(crate) fn answer(
        &self,
        request: &Request,
        dataset: &dyn Fn() -> serde_json::Value,
    ) -> Option<Reply> {
        let reply = match (request.method.as_str(), request.path.as_str()) {
            ("GET", "/") => Reply::text(
                "text/html; charset=utf-8",
                &super::framed_page("label", "/", LABEL_MAIN),
            ),
            ("GET", "/label.js") => Reply::text("text/javascript; charset=utf-8", LABEL_JS),
            ("GET", "/api/state") => Reply::json(&self.state_json(dataset())),
            ("GET", "/api/round.png") => match &self.lock().round {
                Some(round) => Reply::bytes("image/png", round.png.clone()),
                None => Reply::error(404, "no round is waiting for a click"),
            },
            ("GET", "/api/attempt.jpg") => match &self.lock().last {
                Some(last) if !last.strip.is_empty() => {
                    Reply::bytes("image/jpeg", last.strip.clone())
                }
                _ => Reply::error(404, "no attempt has been filmed yet"),
            },
            ("POST", "/api/click") => self.click(request).unwrap_or_else(|e| e),
            ("POST", "/api/rotate") => self.rotate(request).unwrap_or_else(|e| e),
            ("POST", "/api/confirm") => self.confirm(request).unwrap_or_else(|e| e),
            (_, "/" | "/label.js" | "/api/state" | "/api/round.png" | "/api/attempt.jpg")
            | (_, "/api/click" | "/api/rotate" | "/api/confirm") => Reply::error(
                405,
                &format!("{} does not take {}", request.path, request.method),
            ),
            _ => return None,
        };
        Some(reply)
    }

    fn state_json(&self, dataset: serde_json::Value) -> serde_json::Value {
        let state = self.lock();
        let round = state
            .round
            .as_ref()
            .map(|r| serde_json::json!({ "id": r.id, "object": r.object, "round": r.round }));
        let last = state.last.as_ref().map(|a| {
            serde_json::json!({
                "id": a.id,
                "object": a.view.object,
                "round": a.view.round,
                "grasp": a.view.grasp,
                "reason": a.view.reason,
                "detail": a.view.detail,
                "stored": a.view.stored,
                "frames": a.frame_count,
                "frame_width": a.frame_size.0,
                "frame_height": a.frame_size.1,
            })
        });
        serde_json::json!({
            "phase": if state.done { "done" } else if state.running { "running" }
                     else if state.round.is_some() { "waiting" } else { "preparing" },
            "round": round,
            "cursor": {
                "centre": state.centre.map(|(x, y)| [x, y]),
                "angle": state.angle_deg,
            },
            "last": last,
            "dataset": dataset,
            "image_size": IMAGE_SIZE,
            "angle_step": BIN_DEG,
            "finger_offset_px": FINGER_OFFSET_PX,
            "pad_px": self.pad_px,
        })
    }

    fn click(&self, request: &Request) -> Result<Reply, Reply> {
        let body = request.json()?;
        let coordinate = |key: &str| {
            body.get(key)
                .and_then(|v| v.as_u64())
                .filter(|&v| v < u64::from(IMAGE_SIZE))
                .map(|v| v as u32)
                .ok_or_else(|| {
                    Reply::error(
                        400,
                        &format!(
                            "\"{key}\" = {} must be an integer pixel in 0..={}",
                            body.get(key).map_or("missing".into(), |v| v.to_string()),
                            IMAGE_SIZE - 1
                        ),
                    )
                })
        };
        let (x, y) = (coordinate("x")?, coordinate("y")?);
        let mut state = self.lock();
        state.centre = Some((x, y));
        Ok(Reply::json(
            &serde_json::json!({ "centre": [x, y], "angle": state.angle_deg }),
        ))
    }

    fn rotate(&self, request: &Request) -> Result<Reply, Reply> {
        let body = request.json()?;
        let steps = body
            .get("steps")
            .and_then(|v| v.as_i64())
            .filter(|s| (-8..=8).contains(s))
            .ok_or_else(|| {
                Reply::error(400, "\"steps\" must be an integer in -8..=8 (22.5° each)")
            })?;
        let mut state = self.lock();
        state.angle_deg = normalize_angle(state.angle_deg + steps as f32 * BIN_DEG);
        Ok(Reply::json(
            &serde_json::json!({ "angle": state.angle_deg }),
        ))
    }

    fn confirm(&self, request: &Request) -> Result<Reply, Reply> {
        let body = request.json()?;
        let mut state = self.lock();
        if state.running || state.confirmed.is_some() {
            return Err(Reply::error(
                409,
                "an attempt is running; wait for its outcome",
            ));
        }
        let Some(round) = &state.round else {
            return Err(Reply::error(
                409,
                if state.done {
                    "every object has its labels; nothing to confirm"
                } else {
                    "the next round is being prepared; wait for its image"
                },
            ));
        };
        let Some(round_id) = body.get("round_id") else {
            return Err(Reply::error(
                400,
                &format!(
                    "the confirm body needs \"round_id\" (the round on show is {})",
                    round.id
                ),
            ));
        };
        if round_id.as_u64() != Some(round.id) {
            return Err(Reply::error(
                409,
                &format!(
                    "round_id {} is not the round on show ({}); reload the page",
                    body.get("round_id")
                        .map_or("missing".into(), |v| v.to_string()),
                    round.id
                ),
            ));
        }
        let Some((u, v)) = state.centre else {
            return Err(Reply::error(400, "click a grasp centre first"));
        };
        let grasp = PixelGrasp {
            u,
            v,
            angle_deg: state.angle_deg,
        };
        state.confirmed = Some(grasp);
        state.running = true;
        self.changed.notify_all();
        Ok(Reply::json(&serde_json::json!({ "confirmed": grasp })))
    }
}
