//! Times the clip encoder alone, per clip: what docs/performance.md compares with ACL's
//! `acl_compressor` compression time (issues 17 and 29).
//!
//! `cargo run --release -p sinew-pipeline --example compress_time -- RUNS FILE...` (corpus-relative
//! paths or paths on disk). Every clip of each file is compressed RUNS times at the peers' settings
//! (0.001 units at 0.1 units) inside a rayon pool of one thread (`SINEW_THREADS=N` for N); prints per
//! clip the median and fastest time in milliseconds, the joints x keys, the compressed bytes and the
//! max error (`SINEW_CLIP=NAME`: only the clips of that name). `SINEW_EFFORT=fast|max` picks another
//! effort, `SINEW_SETTING=default` the default (relative) tolerance. Like the `sinew` binary, it
//! starts with [`sinew_pipeline::warm_heap`] and warms each pool thread's heap
//! ([`sinew_pipeline::warm_thread_heap`]) unless `SINEW_NO_WARM_HEAP` is set. The time is the
//! encoder's on the pool thread that runs it (as `convert --timings` reports it and ACL its
//! compression time); `SINEW_TIME_HANDOFF=1` times the hand-off to the pool and back too, as this
//! example did until session 19.

#![allow(clippy::unwrap_used)]

use sinew_pipeline::compile::compile;
use sinew_pipeline::compress::{compress_clip, CompressOptions, Effort};
use std::time::Instant;

fn main() {
    // The process the `sinew` binary runs the encoder in.
    if sinew_pipeline::heap_warming() {
        sinew_pipeline::warm_heap();
    }
    let mut args = std::env::args().skip(1);
    let runs: usize = args.next().and_then(|r| r.parse().ok()).unwrap_or(5).max(1);
    let files: Vec<String> = args.collect();
    let threads = std::env::var("SINEW_THREADS")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(1);
    let pool = sinew_pipeline::warmed_pool_builder()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut options = if std::env::var("SINEW_SETTING").as_deref() == Ok("default") {
        CompressOptions::default()
    } else {
        CompressOptions::peers()
    };
    options.effort = match std::env::var("SINEW_EFFORT").as_deref() {
        Ok("fast") => Effort::Fast,
        Ok("max") => Effort::Max,
        _ => Effort::Default,
    };
    // The encoder's time on the pool thread that runs it, as `convert --timings` reports a clip's
    // and ACL reports its compression time; `SINEW_TIME_HANDOFF` adds the hand-off from this thread
    // to the pool and back (how sessions 10 to 19 measured: a pool thread that has gone to sleep
    // can take milliseconds to start on a shared machine, which `convert` pays once per process).
    let with_handoff = std::env::var_os("SINEW_TIME_HANDOFF").is_some();
    // SINEW_CLIP: only the clips of that name (to profile one clip of a file).
    let only = std::env::var("SINEW_CLIP").ok();
    println!("| file | clip | joints x keys | bytes | median ms | fastest ms | max error |");
    println!("|---|---|---|---:|---:|---:|---:|");
    for file in files {
        let path = sinew_testdata::corpus_file(&file)
            .filter(|p| p.exists())
            .unwrap_or_else(|| std::path::PathBuf::from(&file));
        let scene = match sinew_import::import_path(&path, &Default::default()) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{file}: {e}");
                continue;
            }
        };
        let asset = compile(&scene).unwrap();
        for clip in asset
            .clips
            .iter()
            .filter(|c| only.as_ref().is_none_or(|n| c.name() == n))
        {
            let mut times = Vec::with_capacity(runs);
            let mut report = None;
            for _ in 0..runs {
                let outer = Instant::now();
                let ((_, r), inner) = pool.install(|| {
                    let start = Instant::now();
                    let out = compress_clip(clip, asset.skeleton.as_ref(), &options);
                    (out, start.elapsed())
                });
                let took = if with_handoff { outer.elapsed() } else { inner };
                times.push(took.as_secs_f64() * 1000.0);
                report = Some(r);
            }
            times.sort_by(f64::total_cmp);
            let r = report.unwrap();
            println!(
                "| {file} | {} | {} x {} | {} | {:.2} | {:.2} | {:.6} |",
                r.clip,
                r.animated_joints,
                r.samples,
                r.compressed_bytes,
                times[times.len() / 2],
                times[0],
                r.max_error
            );
        }
    }
}
