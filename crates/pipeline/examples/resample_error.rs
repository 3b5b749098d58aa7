//! How far a clip resampled at a fixed rate is from its source: the error a peer that needs uniform
//! samples (ACL) starts from before it compresses anything, in sinew's metric (three points
//! `--distance` units from each joint, carried through the hierarchy, at every source key time).
//!
//! Each clip is resampled as `../shared/peers/gltf2acl.py` does (`round(duration * rate) + 1`
//! samples, sample `i` at `min(i / rate, duration)`), played back with linear interpolation (sinew's
//! sampler), and measured against the source clip.
//!
//! `cargo run --release -p sinew-pipeline --example resample_error -- FILE RATE [RATE...] [--distance D]`
//!
//! With `WORST=1` in the environment it also prints, on stderr, where the worst error is (key,
//! time, joint) and the six joints with the largest errors.

#![allow(clippy::unwrap_used)]

use sinew_core::{Clip, ClipBinding, Curve, Sampler, TrackCurves, Transform};
use sinew_pipeline::compile::compile;
use sinew_pipeline::compress::measure;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut distance = 0.1f32;
    let mut rest = Vec::new();
    let mut i = 0;
    while i < args.len() {
        if args[i] == "--distance" {
            distance = args[i + 1].parse().unwrap();
            i += 2;
        } else {
            rest.push(args[i].clone());
            i += 1;
        }
    }
    let file = &rest[0];
    let rates: Vec<f32> = rest[1..].iter().map(|r| r.parse().unwrap()).collect();
    let scene = sinew_import::import_path(std::path::Path::new(file), &Default::default()).unwrap();
    let asset = compile(&scene).unwrap();
    let skeleton = asset.skeleton.as_ref().unwrap();
    println!("| clip | source keys | rate (Hz) | samples | max error of the resampled clip |");
    println!("|---|---:|---:|---:|---:|");
    for clip in &asset.clips {
        for &rate in &rates {
            let dur = clip.duration();
            let n = if dur > 0.0 {
                (dur * rate).round() as usize + 1
            } else {
                1
            };
            let mut times: Vec<f32> = (0..n).map(|i| (i as f32 / rate).min(dur)).collect();
            times.dedup();
            let binding = ClipBinding::new(clip, skeleton);
            let mut sampler = Sampler::new();
            let mut pose = skeleton.bind_local().to_vec();
            let poses: Vec<Vec<Transform>> = times
                .iter()
                .map(|&t| {
                    sampler
                        .sample(clip, &binding, skeleton, t, &mut pose)
                        .unwrap();
                    pose.clone()
                })
                .collect();
            let tracks = clip
                .tracks()
                .iter()
                .map(|tr| {
                    let j = skeleton.find(&tr.joint).unwrap() as usize;
                    TrackCurves {
                        joint: tr.joint.clone(),
                        translation: Curve::new(
                            times.clone(),
                            poses.iter().map(|p| p[j].translation).collect(),
                        ),
                        rotation: Curve::new(
                            times.clone(),
                            poses.iter().map(|p| p[j].rotation).collect(),
                        ),
                        scale: Curve::new(
                            times.clone(),
                            poses.iter().map(|p| p[j].scale).collect(),
                        ),
                    }
                })
                .collect();
            let resampled = Clip::from_curves(
                clip.name().to_owned(),
                dur,
                rate,
                clip.looping(),
                clip.additive(),
                tracks,
            )
            .unwrap();
            let errors = measure(clip, &resampled, Some(skeleton), distance);
            let worst = errors.iter().copied().fold(0.0f32, f32::max);
            if std::env::var_os("WORST").is_some() {
                // Errors are time-major, one per joint.
                let nj = skeleton.len();
                if let Some(at) = errors.iter().position(|&e| e == worst) {
                    eprintln!(
                        "  worst at key {} ({} s), joint {}",
                        at / nj,
                        clip.times()[at / nj],
                        skeleton.names()[at % nj]
                    );
                }
                let mut per_joint = vec![0.0f32; nj];
                for (i, e) in errors.iter().enumerate() {
                    per_joint[i % nj] = per_joint[i % nj].max(*e);
                }
                let mut order: Vec<usize> = (0..nj).collect();
                order.sort_by(|a, b| per_joint[*b].total_cmp(&per_joint[*a]));
                for &j in order.iter().take(6) {
                    eprintln!("  {} {:.4}", skeleton.names()[j], per_joint[j]);
                }
            }
            println!(
                "| {} | {} | {rate} | {} | {worst:.6} |",
                clip.name(),
                clip.times().len(),
                times.len()
            );
        }
    }
}
