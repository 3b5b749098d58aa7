//! `convert --report OUT/index.html` opened in a real browser: headless Chromium loads the page from
//! disk (no server) inside a test page that reads it once loaded, and the test checks that every
//! thumbnail decoded, that sorting by a column works, and that the page logged nothing to the console
//! (no error, no warning). Without Chromium the test says so and skips, except under CI (`CI` set),
//! where it fails: `.ci/run` installs Chromium when it is missing.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::sinew;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The Chromium binary: `SINEW_CHROMIUM`, else the first of `chromium`, `chromium-browser`,
/// `google-chrome` on PATH.
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SINEW_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Runs headless Chromium on `url` with a fresh profile in `profile`, printing the DOM after load;
/// returns (stdout, stderr). Killed after 90 s.
fn dump_dom(browser: &Path, profile: &Path, url: &str) -> (String, String) {
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--allow-file-access-from-files",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=10000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(90) {
            child.kill().unwrap();
            panic!("chromium did not finish in 90 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The test page: loads the report in an iframe, then writes what it found as JSON into `#out`:
/// the images and how many decoded, the `triangles` column's keys as shown, after one click on its
/// header and after a second click, and the rows' statuses.
const PROBE: &str = r#"<!doctype html><html><body><iframe id="f" src="index.html"></iframe>
<pre id="out">pending</pre><script>
document.getElementById('f').addEventListener('load', function () {
  var d = document.getElementById('f').contentDocument;
  var imgs = Array.prototype.slice.call(d.images);
  var heads = Array.prototype.slice.call(d.querySelectorAll('#files thead th'));
  var col = heads.findIndex(function (h) { return h.textContent === 'triangles'; });
  var keys = function () {
    return Array.prototype.map.call(d.querySelectorAll('#files tbody tr'), function (r) {
      return r.cells[col].getAttribute('data-k');
    });
  };
  var shown = keys();
  var status = Array.prototype.map.call(d.querySelectorAll('#files tbody tr'), function (r) {
    return r.cells[2].textContent;
  });
  heads[col].click();
  var up = keys();
  heads[col].click();
  var down = keys();
  document.getElementById('out').textContent = JSON.stringify({
    images: imgs.length,
    loaded: imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length,
    shown: shown, up: up, down: down, status: status
  });
});
</script></body></html>"#;

#[test]
fn the_batch_report_loads_in_chromium_with_every_picture_and_no_console_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // A folder of inputs: two fixtures, and a file that fails (a truncated MS3D).
    let src = dir.path().join("in");
    std::fs::create_dir_all(&src).unwrap();
    for f in ["biped.gltf", "prop.obj", "prop.mtl"] {
        std::fs::copy(sinew_testdata::fixtures().join(f), src.join(f)).unwrap();
    }
    let ms3d = std::fs::read(sinew_testdata::fixtures().join("ms3d/sliding_arm.ms3d")).unwrap();
    std::fs::write(src.join("broken.ms3d"), &ms3d[..ms3d.len() / 2]).unwrap();
    let report = out.join("index.html");
    let r = sinew([
        "convert".as_ref(),
        src.as_os_str(),
        "--out-dir".as_ref(),
        out.as_os_str(),
        "--report".as_ref(),
        report.as_os_str(),
        "--json".as_ref(),
        "-q".as_ref(),
    ]);
    assert_eq!(r.code, 1, "one input fails: {}", r.stderr);
    let json: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(
        (json["converted"].as_u64(), json["failed"].as_u64()),
        (Some(2), Some(1))
    );
    let html = std::fs::read_to_string(&report).unwrap();
    assert!(html.starts_with("<!doctype html>"));
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "no network"
    );
    // A row per input, and one for the MTL file the folder walk passed over (the OBJ reads it).
    assert_eq!(html.matches("<tr class=").count(), 4);
    assert!(html.contains("skipped: companion"), "the MTL's row");
    // Failures first.
    let broken = html.find("broken.ms3d").unwrap();
    assert!(broken < html.find("biped.gltf").unwrap() && broken < html.find("prop.obj").unwrap());

    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "chromium is needed under CI (.ci/run installs it)"
        );
        eprintln!(
            "chromium not found (set SINEW_CHROMIUM or install it); skipping the browser check"
        );
        return;
    };
    std::fs::write(out.join("probe.html"), PROBE).unwrap();
    let url = format!("file://{}", out.join("probe.html").display());
    let (dom, log) = dump_dom(&browser, &dir.path().join("profile"), &url);
    let found = dom
        .split("<pre id=\"out\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| panic!("no probe output in the DOM: {dom}"));
    let probe: serde_json::Value = serde_json::from_str(&found.replace("&quot;", "\""))
        .unwrap_or_else(|e| panic!("probe output {found:?}: {e}"));
    // One thumbnail per converted input, every one decoded.
    assert_eq!(probe["images"], 2, "{probe}");
    assert_eq!(probe["loaded"], 2, "{probe}");
    assert_eq!(probe["status"][0], "failed", "{probe}");
    // As written: the failure first, the passed-over MTL last.
    assert_eq!(probe["status"][3], "skipped: companion", "{probe}");
    // Sorting by triangles: ascending, then descending (keys as numbers; the failed and skipped
    // rows have none).
    let nums = |k: &str| -> Vec<f64> {
        probe[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().parse::<f64>().unwrap_or(f64::NAN))
            .filter(|x| x.is_finite())
            .collect()
    };
    let up = nums("up");
    let down = nums("down");
    assert!(
        up.windows(2).all(|w| w[0] <= w[1]) && up.len() == 2,
        "{probe}"
    );
    assert!(
        down.windows(2).all(|w| w[0] >= w[1]) && up[0] < up[1],
        "{probe}"
    );
    // Nothing on the console from the report page.
    let messages: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("CONSOLE") && l.contains("index.html"))
        .collect();
    assert!(messages.is_empty(), "console: {messages:?}");
}
