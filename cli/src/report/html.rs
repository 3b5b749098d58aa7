//! The static HTML report of a `convert` run (`--report OUT.html`): one self-contained page (no
//! server, no network: styles, script and thumbnails inline) with a row per input, built from the same
//! per-input report `--json` prints (so converted, reused and failed inputs read alike), each row with
//! a thumbnail of its output as `preview` draws it; sortable by any column, failures first.

use super::convert::ConvertReport;
use crate::cli::UpArg;
use serde_json::Value;
use sinew_pipeline::preview::camera::Facing;
use sinew_pipeline::preview::sheet::{thumbnail, SheetOptions};
use std::fmt::Write as _;
use std::path::Path;

/// Thumbnail side, pixels.
pub const THUMB: u32 = 128;

/// `s` with `& < > " '` escaped, for HTML text and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The thumbnail of a written output as a `data:` URI: the file read back, its default body at rest
/// from the front (its own axes), textured with the PNG files its materials name beside it. `None`
/// when the file cannot be read or drawn.
pub fn thumbnail_uri(output: &Path) -> Option<String> {
    let loaded = crate::commands::export::load(output, &Default::default(), None).ok()?;
    let (axes, _) = crate::commands::preview::picture_axes(UpArg::Auto, output, &loaded.asset);
    let opts = SheetOptions {
        facing: Facing::of(axes, false),
        rest_facing: Facing::of(axes, true),
        images: loaded.decoded,
        ..SheetOptions::default()
    };
    let png = thumbnail(&loaded.asset, &opts, THUMB).ok()?;
    Some(format!(
        "data:image/png;base64,{}",
        sinew_pipeline::export::container::base64(&png)
    ))
}

/// The thumbnails of a run's outputs, in file order (`None` for inputs that wrote nothing), drawn in
/// parallel.
pub fn thumbnails(report: &ConvertReport) -> Vec<Option<String>> {
    use rayon::prelude::*;
    report
        .files
        .par_iter()
        .map(|f| {
            let wrote = matches!(f.status, "converted" | "reused");
            wrote.then(|| thumbnail_uri(Path::new(&f.output))).flatten()
        })
        .collect()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(0.0)
}

fn arr(v: &Value) -> &[Value] {
    v.as_array().map_or(&[], Vec::as_slice)
}

/// A number in at most four significant figures (`0.0123`, `1.5`, `120`).
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// One table cell: its sort key (a number or text) and its HTML.
fn cell(key: impl std::fmt::Display, html: &str) -> String {
    format!("<td data-k=\"{}\">{html}</td>", escape(&key.to_string()))
}

/// A summary line, and `details` under it: shown when short, folded (`<details>`) when longer.
fn fold(summary: &str, details: &str, items: usize) -> String {
    if items <= 3 {
        format!("<div>{summary}</div>{details}")
    } else {
        format!("<details><summary>{summary}</summary>{details}</details>")
    }
}

/// One row for an entry of `skipped[]` (a file a folder walk passed over): an orphaned companion is
/// an error (rank 0), the rest come last (rank 3).
fn skipped_row(k: &Value, index: usize) -> String {
    let reason = k["reason"].as_str().unwrap_or("");
    let rank = if reason == "orphaned-companion" { 0 } else { 3 };
    let file = k["file"].as_str().unwrap_or("");
    let mut s = format!(
        "<tr class=\"{}\" data-rank=\"{rank}\" data-i=\"{index}\">",
        if rank == 0 { "failed" } else { "skipped" }
    );
    s.push_str(&cell(index, "<span class=\"none\">no picture</span>"));
    s.push_str(&cell(
        file,
        &format!("<div class=\"in\">{}</div>", escape(file)),
    ));
    s.push_str(&cell(
        rank,
        &format!(
            "<span class=\"st skipped\">skipped: {}</span>",
            escape(reason)
        ),
    ));
    for _ in 0..8 {
        s.push_str(&cell("", ""));
    }
    let message = escape(k["message"].as_str().unwrap_or(""));
    let class = if rank == 0 { "err" } else { "none" };
    s.push_str(&cell(
        k["message"].as_str().unwrap_or(""),
        &format!("<div class=\"{class}\">{message}</div>"),
    ));
    s.push_str("</tr>\n");
    s
}

/// One row of the table for one entry of `files[]`.
fn row(f: &Value, thumb: Option<&str>, index: usize) -> String {
    let status = f["status"].as_str().unwrap_or("failed");
    let failed = status == "failed";
    let meshes = arr(&f["meshes"]);
    let clips = arr(&f["clips"]);
    let triangles: u64 = meshes
        .iter()
        .map(|m| m["triangles"].as_u64().unwrap_or(0))
        .sum();
    // LODs: per level, triangles over all meshes and the largest relative error.
    let levels = meshes
        .iter()
        .map(|m| arr(&m["lods"]).len())
        .max()
        .unwrap_or(0);
    let mut lods = String::new();
    for level in 0..levels {
        let tris: u64 = meshes
            .iter()
            .filter_map(|m| arr(&m["lods"]).get(level))
            .map(|l| l["triangles"].as_u64().unwrap_or(0))
            .sum();
        let err = meshes
            .iter()
            .filter_map(|m| arr(&m["lods"]).get(level))
            .map(|l| num(&l["error_relative"]))
            .fold(0.0, f64::max);
        let _ = write!(
            lods,
            "<div>LOD{}: {} tris, err {}%</div>",
            level + 1,
            tris,
            short(err * 100.0)
        );
    }
    let stored = |k: &Value| {
        let field = if k["compressed"].as_bool() == Some(false) {
            "plain_bytes"
        } else {
            "compressed_bytes"
        };
        k[field].as_u64().unwrap_or(0)
    };
    let clip_bytes: u64 = clips.iter().map(|c| stored(&c["compression"])).sum();
    let mut clip_list = String::new();
    for c in clips {
        let name = escape(c["name"].as_str().unwrap_or(""));
        let k = &c["compression"];
        let detail = if k.is_null() {
            format!("{} s, plain f32", short(num(&c["duration"])))
        } else {
            format!(
                "{} s, {} B, max err {}",
                short(num(&c["duration"])),
                stored(k),
                short(num(&k["max_error"]))
            )
        };
        let _ = write!(clip_list, "<div>{name}: {detail}</div>");
    }
    let max_err = clips
        .iter()
        .map(|c| num(&c["compression"]["max_error"]))
        .fold(0.0, f64::max);
    let textures = arr(&f["textures"]).len();
    let diags: Vec<&Value> = arr(&f["diagnostics"])
        .iter()
        .filter(|d| d["level"] == "warning" || d["level"] == "error")
        .collect();
    let warnings = f["warnings"].as_u64().unwrap_or(diags.len() as u64);
    let mut warning_list = String::new();
    for d in &diags {
        let _ = write!(
            warning_list,
            "<div class=\"w\">[{}] {}</div>",
            escape(d["code"].as_str().unwrap_or("")),
            escape(d["message"].as_str().unwrap_or(""))
        );
    }
    let error = f["error"].as_str().unwrap_or("");
    let image = match thumb {
        Some(uri) => format!(
            "<img src=\"{uri}\" width=\"{THUMB}\" height=\"{THUMB}\" alt=\"{}\">",
            escape(f["input"].as_str().unwrap_or(""))
        ),
        None => "<span class=\"none\">no picture</span>".to_string(),
    };
    // Failures sort first by default: rank 0 failed, 1 with warnings, 2 clean.
    let rank = if failed {
        0
    } else if warnings > 0 {
        1
    } else {
        2
    };
    let mut s = format!(
        "<tr class=\"{}\" data-rank=\"{rank}\" data-i=\"{index}\">",
        if failed { "failed" } else { "ok" }
    );
    s.push_str(&cell(index, &image));
    let input = escape(f["input"].as_str().unwrap_or(""));
    let output = escape(f["output"].as_str().unwrap_or(""));
    s.push_str(&cell(
        f["input"].as_str().unwrap_or(""),
        &format!("<div class=\"in\">{input}</div><div class=\"out\">{output}</div>"),
    ));
    s.push_str(&cell(
        rank,
        &format!("<span class=\"st {status}\">{status}</span>"),
    ));
    if f["joints"].is_null() {
        // Nothing was made (a failure before any output): no figures, blank cells.
        for _ in 0..8 {
            s.push_str(&cell("", ""));
        }
    } else {
        s.push_str(&cell(num(&f["joints"]), &short(num(&f["joints"]))));
        s.push_str(&cell(meshes.len(), &meshes.len().to_string()));
        s.push_str(&cell(triangles, &triangles.to_string()));
        s.push_str(&cell(levels, &lods));
        s.push_str(&cell(
            clips.len(),
            &fold(
                &format!("{} clips, {clip_bytes} B", clips.len()),
                &clip_list,
                clips.len(),
            ),
        ));
        s.push_str(&cell(max_err, &short(max_err)));
        s.push_str(&cell(textures, &textures.to_string()));
        s.push_str(&cell(
            warnings,
            &fold(&warnings.to_string(), &warning_list, diags.len()),
        ));
    }
    s.push_str(&cell(
        error,
        &format!("<div class=\"err\">{}</div>", escape(error)),
    ));
    s.push_str("</tr>\n");
    s
}

const STYLE: &str = "body{font:13px/1.4 sans-serif;margin:16px;color:#222;background:#fafaf7}\
h1{font-size:18px}table{border-collapse:collapse;width:100%}\
th,td{border-bottom:1px solid #ddd;padding:4px 6px;vertical-align:top;text-align:left}\
th{background:#ecece8;cursor:pointer;position:sticky;top:0}th:hover{background:#ddd}\
tr.failed{background:#fde8e8}.st{font-weight:bold}.st.failed{color:#b00}.st.converted{color:#060}\
.st.reused{color:#046}.out{color:#666;font-size:11px}.err{color:#b00}.w{color:#850;font-size:11px}\
.none{color:#999}tr.skipped{color:#777}.st.skipped{color:#777}summary{cursor:pointer}img{display:block;border:1px solid #ccc;background:#fff}";

/// Sorting: a click on a header sorts by that column's keys (numbers as numbers), again to reverse;
/// ties keep the current order.
const SCRIPT: &str = "(function(){var t=document.getElementById('files');var b=t.tBodies[0];\
var dir={};Array.prototype.forEach.call(t.tHead.rows[0].cells,function(th,c){\
th.addEventListener('click',function(){var d=dir[c]=-(dir[c]||-1);\
var rows=Array.prototype.slice.call(b.rows);rows.sort(function(x,y){\
var a=x.cells[c].getAttribute('data-k'),z=y.cells[c].getAttribute('data-k');\
var na=parseFloat(a),nz=parseFloat(z);var r=(!isNaN(na)&&!isNaN(nz))?na-nz:a.localeCompare(z);\
return d*r;});rows.forEach(function(r){b.appendChild(r);});});});})();";

/// The page for a run: `report` is the run's JSON report (`ConvertReport` serialised), `thumbs` one
/// thumbnail per `files[]` entry. Rows: failures first, then inputs with warnings, then the rest, each
/// group in input order.
pub fn page(report: &Value, thumbs: &[Option<String>], title: &str) -> String {
    let files = arr(&report["files"]);
    let mut order: Vec<usize> = (0..files.len()).collect();
    let rank = |f: &Value| match (f["status"].as_str(), f["warnings"].as_u64()) {
        (Some("failed"), _) => 0,
        (_, Some(w)) if w > 0 => 1,
        _ => 2,
    };
    order.sort_by_key(|&i| (rank(&files[i]), i));
    let mut s = String::new();
    let _ = write!(
        s,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"generator\" content=\"sinew {}\"><title>{}</title><style>{STYLE}</style></head><body>\n",
        env!("CARGO_PKG_VERSION"),
        escape(title)
    );
    let _ = writeln!(
        s,
        "<h1>{}</h1><p>{} inputs: {} converted, {} reused, {} failed; {} warnings; {} files passed \
over ({} companions without their model). Click a column to sort.</p>",
        escape(title),
        num(&report["inputs"]),
        num(&report["converted"]),
        num(&report["reused"]),
        num(&report["failed"]),
        num(&report["warnings"]),
        arr(&report["skipped"]).len(),
        num(&report["orphans"])
    );
    s.push_str("<table id=\"files\"><thead><tr>");
    for h in [
        "picture",
        "input",
        "status",
        "joints",
        "meshes",
        "triangles",
        "LODs",
        "clips",
        "max clip error",
        "textures",
        "warnings",
        "error",
    ] {
        let _ = write!(s, "<th>{h}</th>");
    }
    s.push_str("</tr></thead><tbody>\n");
    let skipped = arr(&report["skipped"]);
    for &i in order.iter().filter(|&&i| rank(&files[i]) == 0) {
        s.push_str(&row(&files[i], thumbs.get(i).and_then(|t| t.as_deref()), i));
    }
    for (k, entry) in skipped.iter().enumerate() {
        if entry["reason"] == "orphaned-companion" {
            s.push_str(&skipped_row(entry, files.len() + k));
        }
    }
    for &i in order.iter().filter(|&&i| rank(&files[i]) > 0) {
        s.push_str(&row(&files[i], thumbs.get(i).and_then(|t| t.as_deref()), i));
    }
    for (k, entry) in skipped.iter().enumerate() {
        if entry["reason"] != "orphaned-companion" {
            s.push_str(&skipped_row(entry, files.len() + k));
        }
    }
    let _ = writeln!(s, "</tbody></table><script>{SCRIPT}</script></body></html>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn rows_put_failures_first_and_escape_what_they_show() {
        let report = json!({
            "inputs": 3, "converted": 2, "reused": 0, "failed": 1, "warnings": 1,
            "files": [
                {"input": "a.mdl", "output": "out/a.sinew", "status": "converted", "warnings": 0,
                 "joints": 3, "meshes": [{"name": "m", "triangles": 10,
                   "lods": [{"triangles": 5, "error_relative": 0.01}]}],
                 "clips": [{"name": "walk", "duration": 1.0,
                   "compression": {"compressed": true, "compressed_bytes": 80, "plain_bytes": 400,
                                   "max_error": 0.002}}],
                 "textures": ["out/a_skin.png"], "diagnostics": []},
                {"input": "b<x>.mdl", "output": "out/b.sinew", "status": "failed", "warnings": 0,
                 "error": "b<x>.mdl: truncated"},
                {"input": "c.obj", "output": "out/c.sinew", "status": "converted", "warnings": 1,
                 "joints": 0, "meshes": [], "clips": [], "textures": [],
                 "diagnostics": [{"level": "warning", "code": "obj-x", "message": "odd & odd"}]}
            ],
            "skipped": [
                {"file": "notes.txt", "reason": "not-a-model", "model": null,
                 "message": "not a model"},
                {"file": "xT.mdl", "reason": "orphaned-companion", "model": null,
                 "message": "no model reads it"}
            ]
        });
        let html = page(
            &report,
            &[Some("data:image/png;base64,AAAA".into()), None, None],
            "run",
        );
        let b = html.find("b&lt;x&gt;.mdl: truncated").unwrap();
        let c = html.find("odd &amp; odd").unwrap();
        let a = html.find("a.mdl").unwrap();
        let orphan = html.find("no model reads it").unwrap();
        let other = html.find("notes.txt").unwrap();
        assert!(
            b < orphan && orphan < c && c < a && a < other,
            "failed, orphaned companions, then warned, then clean, then passed over"
        );
        assert!(html.contains("LOD1: 5 tris, err 1%"));
        assert!(html.contains("walk: 1 s, 80 B, max err 0.002"));
        assert!(html.contains("<img src=\"data:image/png;base64,AAAA\""));
        assert_eq!(html.matches("<tr class=").count(), 5);
        assert!(!html.contains("http://") && !html.contains("https://"));
    }

    #[test]
    fn short_keeps_four_figures() {
        assert_eq!(short(0.0123456), "0.01235");
        assert_eq!(short(1.5), "1.5");
        assert_eq!(short(120.0), "120");
        assert_eq!(short(0.0), "0");
    }
}
