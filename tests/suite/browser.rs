//! The labelling page in a real browser: headless Chromium driven through WebDriver labels a
//! whole small dataset with mouse and keyboard events only, then the dataset is checked and
//! trained on.
//!
//! Needs Debian's `chromium` and `chromium-driver`; `./test.sh` installs them when it can, and
//! without them this test fails with the command that installs them.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::actions::{
    InputSource, KeyAction, KeyActions, MouseActions, PointerAction, MOUSE_BUTTON_LEFT,
};
use fantoccini::{Client, ClientBuilder, Locator};

use super::web::{oracle_click, round_seed, WebLabeller, BIN};

/// The five training objects of the bundled split.
const TRAIN: [&str; 5] = [
    "YcbHammer",
    "YcbMediumClamp",
    "YcbMustardBottle",
    "YcbPowerDrill",
    "YcbTomatoSoupCan",
];

/// The page shows the camera image at this scale (640 px for 128).
const SCALE: f64 = 5.0;

fn find_program(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
}

/// chromedriver on a free port, killed when dropped.
pub(crate) struct Driver {
    child: Child,
    port: u16,
}

impl Driver {
    pub(crate) fn start() -> Self {
        let install = "install them with: sudo apt-get install -y chromium chromium-driver (./test.sh does this when run as root)";
        let driver = find_program("chromedriver")
            .unwrap_or_else(|| panic!("chromedriver is not installed; {install}"));
        assert!(
            find_program("chromium").is_some(),
            "chromium is not installed; {install}"
        );
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let child = Command::new(driver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "chromedriver did not start"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
        Driver { child, port }
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A headless Chromium session. Chromium runs as root in CI, hence `--no-sandbox`; the
/// background-networking flags keep it from calling out of this closed machine.
pub(crate) async fn browser(driver: &Driver, profile: &Path) -> Client {
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        serde_json::json!({
            "binary": find_program("chromium").unwrap(),
            "args": [
                "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run", "--window-size=1280,1000",
                format!("--user-data-dir={}", profile.display()),
            ],
        }),
    );
    caps.insert(
        "goog:loggingPrefs".into(),
        serde_json::json!({ "browser": "ALL" }),
    );
    ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(&format!("http://127.0.0.1:{}", driver.port))
        .await
        .expect("connecting to chromedriver")
}

async fn text(client: &Client, css: &str) -> String {
    client
        .find(Locator::Css(css))
        .await
        .unwrap()
        .text()
        .await
        .unwrap()
}

async fn attr(client: &Client, css: &str, name: &str) -> Option<String> {
    client
        .find(Locator::Css(css))
        .await
        .unwrap()
        .attr(name)
        .await
        .unwrap()
}

/// Waits until `ready` holds, polling the page.
async fn wait_until<F, Fut>(what: &str, limit: Duration, mut ready: F)
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = bool>,
{
    let start = Instant::now();
    while !ready().await {
        assert!(start.elapsed() < limit, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

async fn press(client: &Client, key: char) {
    let keys = KeyActions::new("keyboard".into())
        .then(KeyAction::Down { value: key })
        .then(KeyAction::Up { value: key });
    client.perform_actions(keys).await.unwrap();
}

/// Clicks image pixel (u, v) on the canvas, which is 640 × 640 CSS pixels.
async fn click_pixel(client: &Client, u: u32, v: u32) {
    let canvas = client.find(Locator::Css("#view")).await.unwrap();
    let half = 64.0 * SCALE;
    let mouse = MouseActions::new("mouse".into())
        .then(PointerAction::MoveToElement {
            element: canvas,
            duration: None,
            x: (f64::from(u) * SCALE + 2.0 - half).round(),
            y: (f64::from(v) * SCALE + 2.0 - half).round(),
        })
        .then(PointerAction::Down {
            button: MOUSE_BUTTON_LEFT,
        })
        .then(PointerAction::Up {
            button: MOUSE_BUTTON_LEFT,
        });
    client.perform_actions(mouse).await.unwrap();
}

/// What one round in the browser took, for BENCHMARKS.md.
#[derive(serde::Serialize)]
struct RoundTiming {
    object: String,
    round: u64,
    reason: String,
    confirm_to_outcome_s: f64,
}

/// Labels one round through the page: reads the object and round off the page, clicks the
/// oracle's pixel, turns with D, confirms with Enter and waits for the outcome.
async fn label_round(client: &Client, web: &WebLabeller) -> RoundTiming {
    let object = text(client, "#object").await;
    let round: u64 = text(client, "#round")
        .await
        .trim_start_matches("round ")
        .parse()
        .unwrap();
    let grasp = oracle_click(&object, round_seed(&web.train, &object, round));
    let before = attr(client, "#outcome", "data-id").await;
    click_pixel(client, grasp.u, grasp.v).await;
    let centre = format!("({}, {})", grasp.u, grasp.v);
    wait_until("the centre to show", Duration::from_secs(5), || async {
        text(client, "#centre").await == centre
    })
    .await;
    let steps = (grasp.angle_deg / 22.5).round() as usize;
    for _ in 0..steps {
        press(client, 'd').await;
    }
    let angle = format!("{:.1}", grasp.angle_deg);
    wait_until("the angle to turn", Duration::from_secs(5), || async {
        text(client, "#angle").await == angle
    })
    .await;
    if !Path::new(&shot_path()).exists() {
        // The page as a person sees it mid-round: the gripper on the object, turned.
        std::fs::write(shot_path(), client.screenshot().await.unwrap()).unwrap();
    }
    let confirmed = Instant::now();
    press(client, '\u{e007}').await;
    wait_until("the outcome", Duration::from_secs(30), || async {
        attr(client, "#outcome", "data-id").await != before
    })
    .await;
    let seconds = confirmed.elapsed().as_secs_f64();
    let reason = attr(client, "#outcome", "data-reason")
        .await
        .unwrap_or_default();
    let shown = text(client, "#outcome").await;
    assert!(
        shown.contains(&object) && shown.contains(&format!("round {round}")),
        "{shown}"
    );
    if reason == "success" {
        assert!(shown.contains("stored"), "{shown}");
    } else {
        assert!(shown.contains(&reason), "{shown}");
    }
    RoundTiming {
        object,
        round,
        reason,
        confirm_to_outcome_s: seconds,
    }
}

fn shot_path() -> PathBuf {
    out_dir().join("label-round.png")
}

pub(crate) fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/browser");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[tokio::test(flavor = "current_thread")]
async fn a_person_labels_a_small_dataset_in_the_browser_with_mouse_and_keys_only() {
    let driver = Driver::start();
    let _ = std::fs::remove_file(shot_path());
    let profile = tempfile::tempdir().unwrap();
    let client = browser(&driver, profile.path()).await;
    let mut web = WebLabeller::start(&TRAIN, &["--per-object", "2"]);

    let started = Instant::now();
    client
        .goto(&format!("http://{}/", web.address))
        .await
        .unwrap();
    let load_ms = client
        .execute(
            "const n = performance.getEntriesByType('navigation')[0]; return n.loadEventEnd - n.startTime;",
            vec![],
        )
        .await
        .unwrap();
    let mut timings = Vec::new();
    loop {
        wait_until("a round or the end", Duration::from_secs(60), || async {
            matches!(
                attr(&client, "body", "data-phase").await.as_deref(),
                Some("waiting" | "done")
            )
        })
        .await;
        if attr(&client, "body", "data-phase").await.as_deref() == Some("done") {
            break;
        }
        timings.push(label_round(&client, &web).await);
        assert!(timings.len() < 40, "too many rounds");
    }
    let status = text(&client, "#status").await;
    assert!(status.contains("Every object has its labels"), "{status}");
    assert_eq!(text(&client, "#overall").await, "10 / 10");
    let shot = client.screenshot().await.unwrap();
    std::fs::write(out_dir().join("label-page.png"), shot).unwrap();

    let labels = web.store().load().unwrap();
    for object in TRAIN {
        assert_eq!(labels.of(object).len(), 2, "{object}");
    }
    let successes = timings.iter().filter(|t| t.reason == "success").count();
    assert_eq!(successes, 10);
    let slowest = timings
        .iter()
        .map(|t| t.confirm_to_outcome_s)
        .fold(0.0, f64::max);
    let summary = serde_json::json!({
        "first_load_ms": load_ms,
        "rounds": timings,
        "slowest_confirm_to_outcome_s": slowest,
        "wall_s": started.elapsed().as_secs_f64(),
    });
    std::fs::write(
        out_dir().join("label-timings.json"),
        serde_json::to_vec_pretty(&summary).unwrap(),
    )
    .unwrap();

    // The dataset passes --check and trains.
    let (data, split) = (web.data(), web.dir.path().join("split.json"));
    let run = |args: &[&str]| {
        let mut command = Command::new(BIN);
        command.arg("--data").arg(&data);
        // Only label and eval read the split; the other commands refuse the flag.
        if matches!(args.first(), Some(&"label" | &"eval")) {
            command.arg("--split").arg(&split);
        }
        command.args(args).output().unwrap()
    };
    let check = run(&["label", "--check"]);
    assert!(check.status.success(), "{check:?}");
    // Training waits for the labeller: the page's server holds the labels' lock until Ctrl-C.
    let refused = run(&["train", "--epochs", "1"]);
    assert_eq!(refused.status.code(), Some(2), "{refused:?}");
    // Every label is in, so the stopped labeller reports success. The page leaves first: its
    // polling of a stopped server would log errors the report check then reads.
    client.goto("about:blank").await.unwrap();
    assert_eq!(web.stop().status.code(), Some(0));
    let train = run(&["train", "--epochs", "1"]);
    assert!(train.status.success(), "{train:?}");
    assert!(web.data().join("affordance/best.safetensors").exists());

    // The run's report opens offline, with every image and the video in place.
    let video = web.data().join("episode.mp4");
    let eval = run(&[
        "eval",
        "--task",
        "train",
        "--record",
        video.to_str().unwrap(),
    ]);
    assert!(eval.status.success(), "{eval:?}");
    let report = run(&["report"]);
    assert!(report.status.success(), "{report:?}");
    check_report(&client, &web.data().join("report.html")).await;
    client.close().await.unwrap();
}

/// The browser's console, through chromedriver's log endpoint (W3C WebDriver has none).
#[derive(Debug)]
struct BrowserLog;

impl fantoccini::wd::WebDriverCompatibleCommand for BrowserLog {
    fn endpoint(
        &self,
        base: &url::Url,
        session: Option<&str>,
    ) -> Result<url::Url, url::ParseError> {
        base.join(&format!("session/{}/se/log", session.unwrap_or_default()))
    }

    fn method_and_body(&self, _: &url::Url) -> (http::Method, Option<String>) {
        (http::Method::POST, Some(r#"{"type": "browser"}"#.into()))
    }
}

/// Loads report.html from disk and fails on any console error, any image that did not load,
/// or a video the browser cannot play.
async fn check_report(client: &Client, page: &Path) {
    // Only this page's messages count: the log hands each entry out once.
    client.issue_cmd(BrowserLog).await.unwrap();
    client
        .goto(&format!("file://{}", page.display()))
        .await
        .unwrap();
    let broken = client
        .execute(
            "return Array.from(document.images).filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src);",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(broken, serde_json::json!([]), "images that did not load");
    let images = client
        .execute("return document.images.length;", vec![])
        .await
        .unwrap();
    assert!(images.as_u64().unwrap() >= 5, "{images}");
    let video = client
        .execute_async(
            r#"const done = arguments[arguments.length - 1];
               const v = document.querySelector("video");
               if (!v) { done({ missing: true }); return; }
               const report = () => done({ duration: v.duration, width: v.videoWidth, error: v.error && v.error.code });
               if (v.readyState >= 1) { report(); return; }
               v.addEventListener("loadedmetadata", report);
               v.addEventListener("error", report);
               v.load();"#,
            vec![],
        )
        .await
        .unwrap();
    assert!(
        video["duration"].as_f64().unwrap_or(0.0) > 0.5 && video["width"].as_u64().unwrap_or(0) > 0,
        "the episode video does not play in Chromium: {video}"
    );
    std::fs::write(
        out_dir().join("report.png"),
        client.screenshot().await.unwrap(),
    )
    .unwrap();
    let log = client.issue_cmd(BrowserLog).await.unwrap();
    let errors: Vec<&serde_json::Value> = log
        .as_array()
        .map(|entries| entries.iter().filter(|e| e["level"] == "SEVERE").collect())
        .unwrap_or_default();
    assert!(
        errors.is_empty(),
        "console errors on the report: {errors:?}"
    );
}
