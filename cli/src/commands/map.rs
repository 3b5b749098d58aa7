//! `sinew map RIG MOTION`: how a motion's joints bind to a rig's joints, as a table (stderr) or JSON
//! ([`crate::report::MappingReport`]), optionally saved as a mapping file for `convert --map`.

use super::preview::up_axis;
use crate::cli::MapArgs;
use crate::output::{write_atomic, Ctx};
use crate::report::MappingReport;
use crate::steps::{self, MappingFile};
use crate::Status;
use anyhow::{bail, Context};
use sinew_pipeline::preview::mapping::{mapping_picture, Side};
use std::fmt::Write as _;

/// Runs `sinew map`.
pub fn run(args: &MapArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    if let Some(w) = &args.write {
        crate::output::check_output_path(w)?;
    }
    if let Some(p) = &args.png {
        super::preview::check_png_output(p)?;
    }
    let map = args.map.as_deref().map(MappingFile::read).transpose()?;
    let rig_label = args.rig.display().to_string();
    let motion_label = args.motion.display().to_string();
    let rig_scene = crate::input::import(&args.rig, &args.import)?;
    let motion_scene = crate::input::import(&args.motion, &args.import)?;
    let Some(rig_skel) = &rig_scene.skeleton else {
        bail!("{rig_label}: has no skeleton to map joints onto");
    };
    let rig = steps::rig_joint_set(rig_skel, &rig_label);
    let motion = steps::motion_joint_set(&motion_scene, &motion_label);
    if motion.names().is_empty() {
        bail!("{motion_label}: has no joints (no skeleton and no animated joints)");
    }
    let mapping = steps::make_mapping(&rig, &motion, map.as_ref())?;
    if let Some(w) = &args.write {
        write_atomic(
            w,
            sinew_pipeline::mapping::write_mapping(&mapping).as_bytes(),
        )?;
    }
    let picture = match &args.png {
        Some(p) => {
            let rig_side = Side {
                skeleton: Some(rig_skel),
                names: &[],
                up: up_axis(args.up, &args.rig, !rig_scene.game.is_empty()),
            };
            let motion_side = Side {
                skeleton: motion_scene.skeleton.as_ref(),
                names: motion.names(),
                up: up_axis(args.up, &args.motion, !motion_scene.game.is_empty()),
            };
            let (png, r) = mapping_picture(&rig_side, &motion_side, &mapping)
                .map_err(anyhow::Error::msg)
                .with_context(|| p.display().to_string())?;
            write_atomic(p, &png)?;
            Some(r)
        }
        None => None,
    };
    let mut report = steps::mapping_report(&mapping);
    report.picture = picture;
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        eprint!("{}", human(&report));
        if let Some(w) = &args.write {
            eprintln!("mapping written to {}", w.display());
        }
        if let Some(p) = &args.png {
            eprintln!("picture written to {}", p.display());
        }
    }
    Ok(Status::Success)
}

/// The human-readable table (written to stderr).
pub fn human(r: &MappingReport) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "rig {} ({}) <- motion {} ({}): {} of {} rig joints bound",
        r.rig,
        r.rig_family,
        r.motion,
        r.motion_family,
        r.bound,
        r.entries.len()
    );
    let w_rig = r
        .entries
        .iter()
        .map(|e| e.rig.chars().count())
        .max()
        .unwrap_or(0)
        .max("rig joint".len());
    let w_mot = r
        .entries
        .iter()
        .filter_map(|e| e.motion.as_ref().map(|m| m.chars().count()))
        .max()
        .unwrap_or(0)
        .max("motion joint".len());
    let _ = writeln!(
        o,
        "  {:w_rig$}  {:w_mot$}  method",
        "rig joint", "motion joint"
    );
    for e in &r.entries {
        let method = match (e.method, &e.slot, e.score) {
            (None, _, _) => "-".to_string(),
            (Some(m), Some(slot), _) => format!("{m} ({slot})"),
            (Some(m), None, Some(score)) => format!("{m} {score:.2}"),
            (Some(m), None, None) => m.to_string(),
        };
        let _ = writeln!(
            o,
            "  {:w_rig$}  {:w_mot$}  {method}",
            e.rig,
            e.motion.as_deref().unwrap_or("-")
        );
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    let _ = writeln!(
        o,
        "unmatched rig joints ({}): {}",
        r.unmatched_rig.len(),
        list(&r.unmatched_rig)
    );
    let _ = writeln!(
        o,
        "unmatched motion joints ({}): {}",
        r.unmatched_motion.len(),
        list(&r.unmatched_motion)
    );
    let _ = writeln!(o, "warnings: {}", r.warnings.len());
    for w in &r.warnings {
        let _ = writeln!(o, "  [{}] {}", w.code, w.message);
    }
    o
}
