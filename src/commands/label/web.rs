//! `label --web`: the labelling rounds run as always, with the clicks coming from a page in
//! the browser that the server thread serves beside them.

use std::sync::Mutex;

use super::{labels_in, lock, ObjectJob, ObjectSummary, Shared};
use crate::assets::objects::ObjectModel;
use crate::data::labels::{LabelStore, Labels};
use crate::data::progress::Progress;
use crate::interrupt;
use crate::present::web::labels_page::{self, LabelsAccess};
use crate::present::web::report_route::ReportRoute;
use crate::present::web::session::LabelSession;
use crate::present::web::{Reply, Request, WebServer};

/// The running labeller's dataset, for the labels page: deletes go through the same copy the
/// rounds append to, under the lock the command already holds.
struct SessionLabels<'a> {
    store: &'a LabelStore,
    shared: &'a Mutex<Shared>,
    session: &'a LabelSession,
}

impl LabelsAccess for SessionLabels<'_> {
    fn store(&self) -> &LabelStore {
        self.store
    }

    fn snapshot(&self) -> anyhow::Result<(Labels, Option<Progress>)> {
        let state = lock(self.shared);
        Ok((state.labels.clone(), Some(state.progress.clone())))
    }

    fn delete(&self, object: &str, k: usize) -> Result<(), Reply> {
        let mut state = lock(self.shared);
        let Shared { labels, progress } = &mut *state;
        self.store
            .delete_label(labels, Some(progress), object, k)
            .map_err(|e| Reply::error(404, &format!("{e:#}")))?;
        drop(state);
        self.session.request_refill();
        Ok(())
    }
}

impl ObjectJob<'_> {
    /// Labels every object with clicks from the page, serving it on `server` until a signal.
    /// `finished` reports the dataset each time it is complete; a deleted label starts the
    /// rounds again.
    pub(super) fn label_with_page(
        &self,
        objects: &[String],
        models: &[ObjectModel],
        shared: &Mutex<Shared>,
        (server, session): (&WebServer, &LabelSession),
        finished: &dyn Fn(&[ObjectSummary]) -> anyhow::Result<()>,
    ) -> anyhow::Result<Vec<ObjectSummary>> {
        let per_object = self.args.per_object;
        let dataset = || {
            let state = lock(shared);
            dataset_json(&state.labels, &state.progress, objects, per_object)
        };
        let access = SessionLabels {
            store: self.store,
            shared,
            session,
        };
        let page = |request: &Request| session.answer(request, &dataset);
        let labels = |request: &Request| labels_page::answer(&access, request);
        let report = ReportRoute {
            data: self.context.data.clone(),
            out: self.context.data.join("report.html"),
        };
        let report = |request: &Request| report.answer(request);
        let done = std::sync::atomic::AtomicBool::new(false);
        std::thread::scope(|scope| {
            scope.spawn(|| {
                server.serve(&[&page, &labels, &report], &|| {
                    done.load(std::sync::atomic::Ordering::SeqCst)
                })
            });
            let result = (|| loop {
                let summaries = self.label_all(objects, models, shared, 1)?;
                if interrupt::requested().is_some() {
                    return Ok(summaries);
                }
                session.set_done();
                finished(&summaries)?;
                self.context.say(&format!(
                    "every object has its labels; the page at {} keeps serving until Ctrl-C",
                    server.url()
                ));
                if !session.wait_for_refill() {
                    return Ok(summaries);
                }
            })();
            done.store(true, std::sync::atomic::Ordering::SeqCst);
            result
        })
    }
}

/// The counts the page shows: per object, the labels and rounds so far.
fn dataset_json(
    labels: &Labels,
    progress: &Progress,
    objects: &[String],
    per_object: u32,
) -> serde_json::Value {
    let per: Vec<serde_json::Value> = objects
        .iter()
        .map(|o| {
            serde_json::json!({
                "object": o,
                "labels": labels.of(o).len(),
                "rounds": progress.rounds_of(o),
            })
        })
        .collect();
    serde_json::json!({
        "per_object": per_object,
        "objects": per,
        "labelled": labels_in(labels, objects, per_object),
        "wanted": u64::from(per_object) * objects.len() as u64,
    })
}
