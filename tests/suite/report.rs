//! `graspmap report` on a small real run: the page and its folder, every relative link resolving,
//! each kept eval report named, missing parts named with their command, and clear errors; and the
//! page in headless Chromium at 1280 × 800: the results on the first screen, and affordance
//! pictures whose heat stands out.

use std::path::Path;

use fantoccini::Client;

use crate::browser::{browser, out_dir, Driver};
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
    // What is missing is named with the command that makes it, naming the data directory.
    let data = setup.dir.path().display();
    assert!(html.contains(&format!(
        "No test evaluation yet: run <code>graspmap --data {data} eval --task test</code>"
    )));
    assert!(html.contains(&format!(
        "graspmap --data {data} eval --task train --policy oracle"
    )));
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
    assert!(html.contains(&format!(
        "graspmap --data {data} eval --task train --policy model --seeds 7"
    )));
    let dir = setup.path("pages.html");
    std::fs::create_dir_all(&dir).unwrap();
    assert_user_error(
        &setup.run(&["report", "--out", dir.to_str().unwrap()]),
        &["pages.html", "is a directory"],
    );
    // Last, as they add runs: every command the page suggests runs as printed.
    assert_ok(&setup.run(&["report"]));
    let html = std::fs::read_to_string(&page).unwrap();
    runs_as_printed(&suggested_commands(&html));
}

/// Every `<code>graspmap …</code>` of a page, unescaped, each once.
fn suggested_commands(html: &str) -> Vec<String> {
    let mut found: Vec<String> = Vec::new();
    for part in html.split("<code>").skip(1) {
        let code = part.split("</code>").next().unwrap();
        let text = code
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&#39;", "'")
            .replace("&amp;", "&");
        if text.starts_with("graspmap ") && !found.contains(&text) {
            found.push(text);
        }
    }
    found
}

/// Runs each command as printed. A command that ends within a few seconds must succeed; one
/// still working then is past every check of its flags, files and seeds (those take well
/// under a second), and is stopped with Ctrl-C, which it must take as an interruption.
fn runs_as_printed(commands: &[String]) {
    assert!(commands.len() >= 5, "{commands:?}");
    for command in commands {
        let words = crate::common::shell_words(command);
        assert_eq!(words[0], "graspmap", "{command}");
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_graspmap"))
            .args(&words[1..])
            .env_remove("GRASPMAP_LOG")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let start = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() && start.elapsed().as_secs() < 5 {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let stopped = child.try_wait().unwrap().is_none();
        if stopped {
            crate::common::send_signal(&child, libc::SIGINT);
        }
        let out = child.wait_with_output().unwrap();
        // Stopped just as it finished, it ends with 0.
        let fine: &[i32] = if stopped { &[130, 0] } else { &[0] };
        assert!(
            out.status.code().is_some_and(|c| fine.contains(&c)),
            "`{command}` ended with {:?}: {}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The pictures' left panel, the best of the 8 angles at twice the camera's 128 px, below the
/// caption box in its corner (model::picture's layout).
const SUMMARY_PANEL: (u32, u32, u32, u32) = (0, 20, 256, 256);

/// The lowest heat contrast a picture must reach somewhere on the page. The overlay draws heat
/// as colour over a grey image, so a pixel's heat is its chroma (largest channel minus
/// smallest); the contrast is the mean of the 1 % most coloured pixels less the median. The old
/// rendering (raw scores in viridis, a dark purple square with a peak of a few pixels) scores
/// about 21 on this run's pictures and 20 on a 30-epoch model's, the overlay on a fixed linear
/// 0–1 scale 38–48, and the overlay on the picture's own square-root scale 74–95.
const MIN_HEAT_CONTRAST: f64 = 60.0;

/// The heat contrast of the summary panel of an affordance picture (see [`MIN_HEAT_CONTRAST`]).
fn heat_contrast(png: &Path) -> f64 {
    let image = image::open(png).unwrap().into_rgb8();
    let (x0, y0, x1, y1) = SUMMARY_PANEL;
    assert!(
        image.width() >= x1 && image.height() >= y1,
        "{png:?}: too small"
    );
    let mut heat: Vec<u8> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .map(|(x, y)| {
            let p = image.get_pixel(x, y).0;
            p.iter().max().unwrap() - p.iter().min().unwrap()
        })
        .collect();
    heat.sort_unstable();
    let top = heat.len() / 100;
    let mean_top = heat[heat.len() - top..]
        .iter()
        .map(|&h| f64::from(h))
        .sum::<f64>()
        / top as f64;
    mean_top - f64::from(heat[heat.len() / 2])
}

/// Runs `script` on the page and returns its value.
async fn js(client: &Client, script: &str) -> serde_json::Value {
    client.execute(script, vec![]).await.unwrap()
}

#[tokio::test(flavor = "current_thread")]
async fn the_first_screen_shows_the_results_and_the_pictures_show_the_heat() {
    let (setup, _) = small_run();
    assert_ok(&setup.run(&["report"]));
    let page = setup.path("report.html");
    let driver = Driver::start();
    let profile = tempfile::tempdir().unwrap();
    let client = browser(&driver, profile.path()).await;
    client.set_window_size(1280, 800).await.unwrap();
    client
        .goto(&format!("file://{}", page.display()))
        .await
        .unwrap();
    let view = js(&client, "return [innerWidth, innerHeight];").await;
    assert_eq!(view[0], 1280, "{view}");
    // The results table ends within the first 800 px, its three task rows in it, and the
    // episode video starts there too.
    let table = js(
        &client,
        r#"const t = document.querySelector("table.results");
           if (!t) return null;
           const rows = Array.from(t.querySelectorAll("tr > th:first-child")).map(th => th.textContent);
           return { bottom: t.getBoundingClientRect().bottom, rows };"#,
    )
    .await;
    assert!(table.is_object(), "no results table");
    let bottom = table["bottom"].as_f64().unwrap();
    assert!(
        bottom <= 800.0,
        "the results table ends at {bottom} px: {table}"
    );
    let rows = table["rows"].to_string();
    for task in ["train", "test", "empty_bin"] {
        assert!(rows.contains(task), "no {task} row: {rows}");
    }
    let video_top = js(
        &client,
        r#"const v = document.querySelector("video"); return v && v.getBoundingClientRect().top;"#,
    )
    .await;
    assert!(
        video_top.as_f64().is_some_and(|top| top < 800.0),
        "the episode video is not on the first screen: {video_top}"
    );
    std::fs::write(
        out_dir().join("report-first-screen.png"),
        client.screenshot().await.unwrap(),
    )
    .unwrap();
    // Every affordance picture loaded; at least one has heat that stands out.
    let pictures = js(
        &client,
        r#"return Array.from(document.querySelectorAll("img.affordance"))
                 .map(i => [i.getAttribute("src"), i.complete && i.naturalWidth > 0]);"#,
    )
    .await;
    let pictures = pictures.as_array().unwrap().clone();
    assert!(!pictures.is_empty(), "no affordance picture on the page");
    let mut contrasts = Vec::new();
    for picture in &pictures {
        let url = picture[0].as_str().unwrap();
        assert_eq!(picture[1], true, "{url} did not load");
        contrasts.push(heat_contrast(&target(setup.dir.path(), url)));
    }
    let best = contrasts.iter().copied().fold(f64::MIN, f64::max);
    assert!(
        best >= MIN_HEAT_CONTRAST,
        "no picture's heat stands out: contrasts {contrasts:?}"
    );
    client.close().await.unwrap();
}
