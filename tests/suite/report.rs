//! `graspmap report` on a small real run: the page and its folder, every relative link resolving,
//! each kept eval report named, missing parts named with their command, and clear errors.

use std::path::Path;

use crate::common::{assert_ok, assert_user_error, kept_report};
use crate::eval::{read_json, Setup};

/// Every `href="…"` and `src="…"` value of the page.
fn links(html: &str) -> Vec<String> {
    let mut found = Vec::new();
    for attribute in ["href=\"", "src=\""] {
        let mut rest = html;
        while let Some(at) = rest.find(attribute) {
            rest = &rest[at + attribute.len()..];
            let end = rest.find('"').unwrap();
            found.push(rest[..end].to_owned());
            rest = &rest[end..];
        }
    }
    found
}

/// The file a relative URL of the page names (percent-decoded).
fn target(page_dir: &Path, url: &str) -> std::path::PathBuf {
    let bytes = url.as_bytes();
    let mut decoded = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap();
            decoded.push(u8::from_str_radix(hex, 16).unwrap());
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    page_dir.join(String::from_utf8(decoded).unwrap())
}

/// Labels (the reference fixture), one epoch of training, the model and the random baseline on
/// the train task, and one recorded oracle attempt of empty_bin; with the reports they kept.
fn small_run() -> (Setup, Vec<std::path::PathBuf>) {
    let setup = Setup::new();
    let labels = setup.path("labels");
    std::fs::create_dir_all(&labels).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    for entry in std::fs::read_dir(fixture).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    let video = setup.path("episode.mp4");
    let mut kept = Vec::new();
    for args in [
        &[
            "train",
            "--epochs",
            "1",
            "--batch-size",
            "2",
            "--precision",
            "fp32",
            // Over the set-up's untrained checkpoint.
            "--force",
        ][..],
        &["eval", "--task", "train"][..],
        &["eval", "--task", "train", "--policy", "random"][..],
    ] {
        let out = setup.run(args);
        assert_ok(&out);
        if args[0] == "eval" {
            kept.push(kept_report(&out));
        }
    }
    let out = setup.oracle_empty_bin(1, &["--record", video.to_str().unwrap()]);
    assert_ok(&out);
    kept.push(kept_report(&out));
    (setup, kept)
}

/// The file name of a path.
fn name_of(path: &Path) -> String {
    path.file_name().unwrap().to_string_lossy().into_owned()
}

#[test]
fn the_report_of_a_small_run_links_only_files_it_wrote_and_names_every_eval() {
    let (setup, kept_paths) = small_run();
    // eval keeps its reports under DATA/reports even without --json: one per task, policy and
    // settings (this set-up's own split makes them other settings than the defaults).
    assert!(
        kept_paths
            .iter()
            .all(|p| p.starts_with(setup.path("reports")) && p.is_file()),
        "{kept_paths:?}"
    );
    let kept = read_json(&kept_paths[0]);
    assert!(name_of(&kept_paths[0]).starts_with("eval_train_model_"));
    assert_eq!(kept["schema"], "graspmap.eval/2");
    assert!(kept["results"]["vis_dir"]
        .as_str()
        .unwrap()
        .ends_with("eval_pick_training_vis"));
    let listing = setup.path("written.json");
    let out = setup.run(&["report", "--json", listing.to_str().unwrap()]);
    assert_ok(&out);
    let page = setup.path("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    let files = read_json(&listing)["results"]["files"]
        .as_array()
        .unwrap()
        .clone();
    assert!(files.len() >= 8, "{files:?}");
    for file in &files {
        let file = Path::new(file.as_str().unwrap());
        assert!(
            file.starts_with(setup.path("report_files")) && file.is_file(),
            "{file:?}"
        );
    }
    let urls = links(&html);
    assert!(urls.len() >= 8, "{urls:?}");
    for url in &urls {
        assert!(
            !url.contains("://") && !url.starts_with('/'),
            "not relative: {url}"
        );
        assert!(url.starts_with("report_files/"), "{url}");
        assert!(target(setup.dir.path(), url).is_file(), "broken link {url}");
    }
    for path in &kept_paths {
        let name = name_of(path);
        assert!(html.contains(&name), "{name} not named");
    }
    assert!(html.contains("<video controls") && html.contains("episode.mp4"));
    assert!(html.contains("4 labels of 2 objects"), "label summary");
    assert!(html.contains("Trained 1 epoch."), "training summary");
    // What is missing is named with the command that makes it.
    assert!(html.contains("No test evaluation yet: run <code>graspmap eval --task test</code>"));
    assert!(html.contains("graspmap eval --task train --policy oracle"));
    assert!(
        !html.contains("<script") && !html.contains("http"),
        "not self-contained"
    );
    // The same run gives the same page.
    assert_ok(&setup.run(&["report"]));
    assert_eq!(std::fs::read_to_string(&page).unwrap(), html);

    // A corrupt report is one line naming it; a bad --out names the value and the fix.
    let corrupt = setup.path("reports/eval_test_model.json");
    std::fs::write(&corrupt, b"{\"schema\": ").unwrap();
    assert_user_error(
        &setup.run(&["report"]),
        &["eval_test_model.json", "not a graspmap eval report"],
    );
    std::fs::remove_file(&corrupt).unwrap();
    assert_user_error(
        &setup.run(&["report", "--out", "report.txt"]),
        &["report.txt", ".html"],
    );
    // A probe with other settings keeps its own report, and the page lists it apart from the
    // runs it cannot be compared with, naming its settings.
    let before = std::fs::read(&kept_paths[1]).unwrap();
    let out = setup.run(&[
        "eval", "--task", "train", "--policy", "random", "--seeds", "7",
    ]);
    assert_ok(&out);
    let probe = kept_report(&out);
    assert_ne!(probe, kept_paths[1]);
    assert_eq!(std::fs::read(&kept_paths[1]).unwrap(), before, "replaced");
    assert_ok(&setup.run(&["report"]));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains(&name_of(&probe)) && html.contains(&name_of(&kept_paths[1])));
    assert!(
        html.contains("Runs with seed 7,"),
        "the probe's settings are named"
    );
    assert!(html.contains("listed apart, not compared"));
    assert!(html.contains("graspmap eval --task train --policy model --seeds 7"));
    let dir = setup.path("pages.html");
    std::fs::create_dir_all(&dir).unwrap();
    assert_user_error(
        &setup.run(&["report", "--out", dir.to_str().unwrap()]),
        &["pages.html", "is a directory"],
    );
}
