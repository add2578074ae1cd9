//! The report's folder of files: every file the page shows is copied or drawn into it, through
//! the one atomic writer, and linked from the page by a relative URL.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use crate::data::atomic::{save_image_atomic, write_atomic};

/// `report.html` → `report_files/` beside it.
pub(crate) fn files_dir(out_html: &Path) -> PathBuf {
    let stem = out_html
        .file_stem()
        .map_or_else(|| "report".into(), |s| s.to_string_lossy().into_owned());
    out_html.with_file_name(format!("{stem}_files"))
}

/// The files written for one page.
pub(crate) struct Files {
    html: PathBuf,
    dir: PathBuf,
    /// The folder's name as the page links it.
    link_root: String,
    /// The run's data directory, which the page's commands name.
    data: PathBuf,
    written: Vec<PathBuf>,
}

impl Files {
    pub(crate) fn new(out_html: &Path, data: &Path) -> Self {
        let dir = files_dir(out_html);
        let link_root = dir
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        Self {
            html: out_html.to_path_buf(),
            dir,
            link_root,
            data: data.to_path_buf(),
            written: Vec::new(),
        }
    }

    /// A command for the page to suggest, naming the run's data directory (html::command).
    pub(crate) fn command(&self, rest: &str) -> String {
        super::html::command(&self.data, rest)
    }

    /// Where a suggested `--record` writes its video: `DATA/demo/<name>`, as `./demo.sh` does,
    /// as one shell word.
    pub(crate) fn video_path(&self, name: &str) -> String {
        let path = self.data.join("demo").join(name);
        crate::named::shell_word(&path.display().to_string())
    }

    /// The relative URL of `name` (a `/`-separated path inside the folder), percent-encoded.
    fn link(&self, name: &str) -> String {
        let mut url = String::new();
        for segment in std::iter::once(self.link_root.as_str()).chain(name.split('/')) {
            if !url.is_empty() {
                url.push('/');
            }
            for b in segment.bytes() {
                if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
                    url.push(char::from(b));
                } else {
                    url.push_str(&format!("%{b:02X}"));
                }
            }
        }
        url
    }

    /// Copies `source` into the folder as `name`; returns its link. A file that two parts of
    /// the page show is copied once.
    pub(crate) fn copy(&mut self, source: &Path, name: &str) -> anyhow::Result<String> {
        if self.written.contains(&self.dir.join(name)) {
            return Ok(self.link(name));
        }
        let bytes =
            std::fs::read(source).with_context(|| format!("reading {}", source.display()))?;
        let target = self.dir.join(name);
        write_atomic(&target, &bytes)?;
        self.written.push(target);
        Ok(self.link(name))
    }

    /// Saves an image into the folder as `name` (its extension picks the format); returns its link.
    pub(crate) fn image(&mut self, image: &image::RgbImage, name: &str) -> anyhow::Result<String> {
        let target = self.dir.join(name);
        save_image_atomic(image, &target)?;
        self.written.push(target);
        Ok(self.link(name))
    }

    /// Writes the page, then deletes what an earlier report left in the folder and this one did
    /// not write, so that the pair holds exactly this report. Returns the page, then its files.
    pub(crate) fn finish(self, html: &str) -> anyhow::Result<Vec<PathBuf>> {
        write_atomic(&self.html, html.as_bytes())?;
        let keep: BTreeSet<&PathBuf> = self.written.iter().collect();
        remove_others(&self.dir, &keep)?;
        Ok(std::iter::once(self.html.clone())
            .chain(self.written.iter().cloned())
            .collect())
    }
}

/// Deletes every file under `dir` that is not in `keep`, and the folders left empty.
fn remove_others(dir: &Path, keep: &BTreeSet<&PathBuf>) -> anyhow::Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries {
        let path = entry
            .with_context(|| format!("listing {}", dir.display()))?
            .path();
        if path.is_dir() {
            remove_others(&path, keep)?;
            // Only succeeds when nothing of this report is inside.
            let _ = std::fs::remove_dir(&path);
        } else if !keep.contains(&path) {
            std::fs::remove_file(&path)
                .with_context(|| format!("removing the stale {}", path.display()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_are_relative_and_encoded_and_stale_files_go() {
        let dir = tempfile::tempdir().unwrap();
        let html = dir.path().join("run 1.html");
        std::fs::create_dir_all(dir.path().join("run 1_files/old")).unwrap();
        std::fs::write(dir.path().join("run 1_files/old/stale.png"), b"x").unwrap();
        let source = dir.path().join("a.txt");
        std::fs::write(&source, b"hello").unwrap();
        let mut files = Files::new(&html, dir.path());
        assert_eq!(
            files.copy(&source, "sub/a b.txt").unwrap(),
            "run%201_files/sub/a%20b.txt"
        );
        let written = files.finish("<p>page</p>").unwrap();
        assert_eq!(written[0], html);
        assert_eq!(std::fs::read(&written[1]).unwrap(), b"hello");
        assert!(!dir.path().join("run 1_files/old").exists());
    }
}
