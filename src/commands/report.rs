//! `graspmap report`: write the run's HTML page (present::report_page), and with `--serve`
//! serve it and the labels page over HTTP until Ctrl-C.

use std::net::IpAddr;
use std::path::PathBuf;

use super::Context;
use crate::data::labels::LabelStore;
use crate::data::output::{check_output_dir, check_output_file};
use crate::present::envelope::write_report;
use crate::present::report_page::{files_dir, write_report_page};
use crate::present::web::labels_page::{self, DiskLabels};
use crate::present::web::report_route::ReportRoute;
use crate::present::web::{Reply, Request, WebServer};

/// Everything one `graspmap report` run needs, resolved by the CLI.
#[derive(Debug, Clone, serde::Serialize)]
pub(crate) struct ReportConfig {
    /// Where the page goes; its files go to `<stem>_files/` beside it.
    pub(crate) out: PathBuf,
    /// `--serve`: serve the report and the labels page on this address until Ctrl-C.
    pub(crate) serve: Option<(std::net::IpAddr, u16)>,
}

/// Runs the command.
pub(crate) fn run(context: &Context, config: ReportConfig) -> anyhow::Result<()> {
    check_output_file(&config.out, "--out")?;
    check_output_dir(&files_dir(&config.out), "the report's files folder")?;
    let written = write_report_page(&context.data, &config.out)?;
    context.say(&format!(
        "wrote {} and {} files in {}",
        config.out.display(),
        written.len() - 1,
        files_dir(&config.out).display()
    ));
    if let Some(json) = &context.json {
        write_report(
            json,
            "report",
            0,
            &serde_json::json!({ "global": context, "out": config.out }),
            &serde_json::json!({ "page": config.out, "files": &written[1..] }),
        )?;
    }
    if let Some((host, port)) = config.serve {
        return serve(context, &config.out, host, port);
    }
    Ok(())
}

/// `report --serve`: the report at `/report` (and `/`), the labels page at `/labels`, until
/// Ctrl-C. Deleting a label takes the labels' writer lock for its duration.
fn serve(context: &Context, out: &std::path::Path, host: IpAddr, port: u16) -> anyhow::Result<()> {
    let server = WebServer::bind(host, port)?;
    let url = server.url();
    context.say(&format!(
        "report at {url}report, labels at {url}labels (Ctrl-C stops the server)"
    ));
    let report = ReportRoute {
        data: context.data.clone(),
        out: out.to_path_buf(),
    };
    let labels = DiskLabels {
        store: LabelStore::new(context.data.join("labels")),
    };
    let root = |request: &Request| {
        (request.path == "/").then(|| {
            report
                .answer(&Request {
                    method: request.method.clone(),
                    path: "/report".into(),
                    body: Vec::new(),
                })
                .unwrap_or_else(|| Reply::not_found("/report"))
        })
    };
    let report = |request: &Request| report.answer(request);
    let labels = |request: &Request| labels_page::answer(&labels, request);
    server.serve(&[&root, &report, &labels], &|| {
        crate::interrupt::requested().is_some()
    });
    context.say("server stopped");
    // Ctrl-C is the only way the server stops: exit as `label --web` does, 128 + the signal.
    match crate::interrupt::requested() {
        Some(interrupted) => Err(interrupted.into()),
        None => Ok(()),
    }
}
