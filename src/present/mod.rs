//! Presentation: what people look at and what other tools read. The HTML run report, the
//! labelling page and its HTTP server, episode videos, the versioned JSON envelope of every
//! `--json` report, and the evaluation report's schema, which `eval` writes and `report` reads.

pub(crate) mod envelope;
pub(crate) mod eval_lines;
pub(crate) mod eval_report;
pub(crate) mod improve_summary;
pub(crate) mod kept_reports;
pub(crate) mod report_page;
pub(crate) mod video;
pub(crate) mod web;
