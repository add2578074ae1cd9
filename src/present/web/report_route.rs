//! The run report over HTTP: `/report` writes the page afresh (so it shows the run as it is now)
//! and serves it; the files it links relatively are served from the folder beside it.

use std::path::{Path, PathBuf};

use super::{Reply, Request};
use crate::data::output::Kind;
use crate::present::report_page::{files_dir, write_report_page};

/// Serves the report of the run under `data` (written to `out` and its `_files` folder).
pub(crate) struct ReportRoute {
    pub(crate) data: PathBuf,
    pub(crate) out: PathBuf,
}

impl ReportRoute {
    /// The report's routes: `/report`, and `/<stem>_files/…` for what it shows.
    pub(crate) fn answer(&self, request: &Request) -> Option<Reply> {
        let folder = files_dir(&self.out);
        let link_root = folder.file_name()?.to_string_lossy().into_owned();
        let path = request.path.as_str();
        let file = path
            .strip_prefix('/')
            .and_then(|p| p.strip_prefix(link_root.as_str()))
            .and_then(|p| p.strip_prefix('/'));
        if path != "/report" && file.is_none() {
            return None;
        }
        if request.method != "GET" {
            return Some(Reply::error(
                405,
                &format!("{path} does not take {}", request.method),
            ));
        }
        Some(match file {
            None => self.page(),
            Some(relative) => serve_file(&folder, relative),
        })
    }

    fn page(&self) -> Reply {
        // The page may be one the user wrote there: it is theirs, and the route never asked.
        if self.out.exists() && !Kind::ReportPage.holds(&self.out) {
            return Reply::error(
                409,
                &format!(
                    "{} exists and is not a page graspmap report wrote; move it away, or write the report over it with graspmap --data {} report --force",
                    self.out.display(),
                    self.data.display()
                ),
            );
        }
        match write_report_page(&self.data, &self.out).and_then(|_| {
            std::fs::read(&self.out).map_err(|e| anyhow::anyhow!("{}: {e}", self.out.display()))
        }) {
            Ok(html) => Reply::bytes("text/html; charset=utf-8", html),
            Err(e) => Reply::error(500, &format!("writing the report: {e:#}")),
        }
    }
}

/// A file inside `folder`, named by plain path segments only (no `..`, no hidden files).
fn serve_file(folder: &Path, relative: &str) -> Reply {
    let safe = !relative.is_empty()
        && relative.split('/').all(|segment| {
            !segment.is_empty()
                && !segment.starts_with('.')
                && segment
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c))
        });
    if !safe {
        return Reply::error(404, &format!("'{relative}' is not a file of the report"));
    }
    let path = folder.join(relative);
    match std::fs::read(&path) {
        Ok(bytes) => Reply::bytes(content_type(&path), bytes),
        Err(_) => Reply::error(404, &format!("the report has no file '{relative}'")),
    }
}

fn content_type(path: &Path) -> &'static str {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("png") => "image/png",
        Some("jpg" | "jpeg") => "image/jpeg",
        Some("gif") => "image/gif",
        Some("mp4") => "video/mp4",
        Some("svg") => "image/svg+xml",
        Some("css") => "text/css; charset=utf-8",
        Some("json") => "application/json",
        Some("csv") => "text/csv; charset=utf-8",
        Some("html" | "htm") => "text/html; charset=utf-8",
        _ => "application/octet-stream",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_plain_files_of_the_folder_are_served() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.png"), b"png").unwrap();
        std::fs::create_dir(dir.path().join("vis")).unwrap();
        std::fs::write(dir.path().join("vis/b.jpg"), b"jpg").unwrap();
        assert_eq!(serve_file(dir.path(), "a.png").status, 200);
        assert_eq!(serve_file(dir.path(), "a.png").content_type, "image/png");
        assert_eq!(serve_file(dir.path(), "vis/b.jpg").status, 200);
        for bad in [
            "../a.png",
            "vis/../a.png",
            ".hidden",
            "",
            "vis//b.jpg",
            "a%2e.png",
            "nope.png",
        ] {
            assert_eq!(serve_file(dir.path(), bad).status, 404, "{bad}");
        }
    }
}
