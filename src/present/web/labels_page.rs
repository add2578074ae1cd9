//! The labels page: every stored label image with its grasp drawn, filterable by object, and
//! the delete that renumbers an object's labels (the reference's way to relabel).

use super::{Reply, Request};
use crate::data::labels::{Label, LabelStore, Labels};
use crate::data::progress::Progress;
use crate::grasp::draw::draw_grasp;
use crate::grasp::PixelGrasp;

const LABELS_MAIN: &str = include_str!("page/labels.html");
const LABELS_JS: &str = include_str!("page/labels.js");

/// How the labels page reaches the dataset: through the running labeller's copy, or on disk.
pub(crate) trait LabelsAccess: Sync {
    /// The store on disk.
    fn store(&self) -> &LabelStore;
    /// The labels and progress as they are now.
    fn snapshot(&self) -> anyhow::Result<(Labels, Option<Progress>)>;
    /// Deletes `object`'s label k; the reply says why it cannot.
    fn delete(&self, object: &str, k: usize) -> Result<(), Reply>;
}

/// The page's routes.
pub(crate) fn answer(access: &dyn LabelsAccess, request: &Request) -> Option<Reply> {
    let method = request.method.as_str();
    let path = request.path.as_str();
    let reply = match (method, path) {
        ("GET", "/labels") => Reply::text(
            "text/html; charset=utf-8",
            &super::framed_page("labels", "/labels", LABELS_MAIN),
        ),
        ("GET", "/labels.js") => Reply::text("text/javascript; charset=utf-8", LABELS_JS),
        ("GET", "/api/labels") => list(access),
        (_, "/labels" | "/labels.js" | "/api/labels") => {
            Reply::error(405, &format!("{path} does not take {method}"))
        }
        _ => {
            let rest = path.strip_prefix("/api/labels/")?;
            match label_address(rest) {
                Err(message) => Reply::error(404, &message),
                Ok((object, k, png)) => match (method, png) {
                    ("GET", true) => image(access, &object, k),
                    ("DELETE", false) => match access.delete(&object, k) {
                        Ok(()) => list(access),
                        Err(reply) => reply,
                    },
                    _ => Reply::error(
                        405,
                        &format!("{path}: GET …/<k>.png shows a label, DELETE …/<k> deletes it"),
                    ),
                },
            }
        }
    };
    Some(reply)
}

/// `<Object>/<k>` or `<Object>/<k>.png`: (object, k, is the image).
fn label_address(rest: &str) -> Result<(String, usize, bool), String> {
    let bad = || format!("'/api/labels/{rest}' is not /api/labels/<Object>/<k>[.png]");
    let (object, k) = rest.split_once('/').ok_or_else(bad)?;
    let (k, png) = match k.strip_suffix(".png") {
        Some(k) => (k, true),
        None => (k, false),
    };
    let valid_name = !object.is_empty()
        && object
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let k: usize = k.parse().ok().filter(|&k| k >= 1).ok_or_else(bad)?;
    if !valid_name {
        return Err(bad());
    }
    Ok((object.to_owned(), k, png))
}

fn list(access: &dyn LabelsAccess) -> Reply {
    let (labels, progress) = match access.snapshot() {
        Ok(snapshot) => snapshot,
        Err(e) => return Reply::error(500, &format!("{e:#}")),
    };
    let objects: Vec<serde_json::Value> = labels
        .iter()
        .map(|(object, list)| {
            let sources = progress.as_ref().map(|p| p.sources_of(object).to_vec());
            let entries: Vec<serde_json::Value> = list
                .iter()
                .enumerate()
                .map(|(i, label)| {
                    serde_json::json!({
                        "k": i + 1,
                        "x": label.x,
                        "y": label.y,
                        "angle": label.angle,
                        "source": sources.as_ref().and_then(|s| s.get(i)),
                    })
                })
                .collect();
            serde_json::json!({ "object": object, "labels": entries })
        })
        .collect();
    Reply::json(&serde_json::json!({
        "labels_dir": access.store().dir(),
        "total": labels.len(),
        "objects": objects,
    }))
}

/// The label's image, 4× with its grasp drawn.
fn image(access: &dyn LabelsAccess, object: &str, k: usize) -> Reply {
    let labels = match access.snapshot() {
        Ok((labels, _)) => labels,
        Err(e) => return Reply::error(500, &format!("{e:#}")),
    };
    let Some(label) = labels.of(object).get(k - 1).copied() else {
        return Reply::error(404, &format!("{object} has no label {k}"));
    };
    match render_label(access.store(), object, k, label) {
        Ok(png) => Reply::bytes("image/png", png),
        Err(e) => Reply::error(500, &format!("{e:#}")),
    }
}

/// Draws a stored label's grasp on its image, scaled up pixel-exactly.
pub(crate) fn render_label(
    store: &LabelStore,
    object: &str,
    k: usize,
    label: Label,
) -> anyhow::Result<Vec<u8>> {
    let path = store.image_path(object, k);
    let mut rgb = image::open(&path)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?
        .to_rgb8();
    draw_grasp(&mut rgb, &PixelGrasp::from(label));
    let (w, h) = rgb.dimensions();
    let big = image::imageops::resize(&rgb, w * 4, h * 4, image::imageops::FilterType::Nearest);
    let mut png = std::io::Cursor::new(Vec::new());
    big.write_to(&mut png, image::ImageFormat::Png)?;
    Ok(png.into_inner())
}

/// The labels on disk, for `report --serve`: a delete takes the store's writer lock for its
/// duration, so it never races a running `graspmap label`.
pub(crate) struct DiskLabels {
    pub(crate) store: LabelStore,
}

impl LabelsAccess for DiskLabels {
    fn store(&self) -> &LabelStore {
        &self.store
    }

    fn snapshot(&self) -> anyhow::Result<(Labels, Option<Progress>)> {
        Ok((self.store.load()?, self.store.load_progress()?))
    }

    fn delete(&self, object: &str, k: usize) -> Result<(), Reply> {
        let _writer = crate::data::lock::StoreLock::acquire(self.store.dir(), "label")
            .map_err(|e| Reply::error(409, &e.to_string()))?;
        let fail = |e: anyhow::Error| Reply::error(500, &format!("{e:#}"));
        let mut labels = self.store.load().map_err(fail)?;
        // A dataset without progress.json (e.g. the reference tool's) stays without one.
        let mut progress = self.store.load_progress().map_err(fail)?;
        self.store
            .delete_label(&mut labels, progress.as_mut(), object, k)
            .map_err(|e| Reply::error(404, &format!("{e:#}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_addresses_are_parsed_strictly() {
        assert_eq!(
            label_address("YcbHammer/3.png"),
            Ok(("YcbHammer".into(), 3, true))
        );
        assert_eq!(
            label_address("YcbHammer/12"),
            Ok(("YcbHammer".into(), 12, false))
        );
        for bad in [
            "YcbHammer",
            "YcbHammer/0",
            "YcbHammer/x.png",
            "../x/1",
            "/1",
            "a b/1",
        ] {
            assert!(label_address(bad).is_err(), "{bad}");
        }
    }
}
