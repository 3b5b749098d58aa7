//! Which meshes make the model a person sees: the default body (submodel 0 of every body group, and
//! every mesh no group names), a body number counted as Half-Life model viewers count it, or a list of
//! meshes by index or name. `bake`, `preview` and `export` pose and draw these meshes.
//!
//! # Body numbers
//!
//! A Half-Life model's body groups (the file's game data, in order) each offer some choices; body
//! number `n` picks choice `(n / base_g) % choices_g` of group `g`, where `base_g` is the product of the
//! choice counts of the groups before it (studiomdl's `base` of each body part, what the engine's
//! `pev->body` and the model viewers' "Body" number mean). Body 0 is the default body. A file
//! without body groups has one body, 0: all its meshes.

use sinew_core::format::Asset;

/// How the meshes of a model are chosen.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum BodyChoice {
    /// The default body.
    #[default]
    Default,
    /// A body number (see the module docs).
    Number(u64),
    /// These meshes, each a mesh index or a mesh name.
    Meshes(Vec<String>),
}

impl BodyChoice {
    /// `--body N` or `--mesh LIST` as the command line gives them (at most one of the two).
    pub fn from_args(body: Option<u64>, meshes: Option<&str>) -> BodyChoice {
        match (body, meshes) {
            (Some(n), _) => BodyChoice::Number(n),
            (None, Some(list)) => BodyChoice::Meshes(
                list.split(',')
                    .map(|s| s.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .collect(),
            ),
            (None, None) => BodyChoice::Default,
        }
    }
}

/// Why no meshes could be chosen.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BodyError {
    /// The body number is not below the number of bodies.
    #[error("body {number} does not exist; the file has {count} bodies (0 to {})", count - 1)]
    NoSuchBody {
        /// Requested number.
        number: u64,
        /// Bodies the file has.
        count: u64,
    },
    /// A mesh index or name is not in the file.
    #[error("no mesh {given:?}; the file has: {}", list(available))]
    UnknownMesh {
        /// As given.
        given: String,
        /// Mesh names, in order.
        available: Vec<String>,
    },
    /// An empty list of meshes.
    #[error("no meshes were named")]
    Empty,
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "(no meshes)".into()
    } else {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| format!("{i} {n:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// How many bodies the file has: the product of its body groups' choice counts (1 without groups;
/// saturating at `u64::MAX`).
pub fn body_count(asset: &Asset) -> u64 {
    asset
        .game
        .body_groups
        .iter()
        .fold(1u64, |n, g| n.saturating_mul(g.meshes.len().max(1) as u64))
}

/// Indices of the meshes no body group names (part of every body).
fn ungrouped(asset: &Asset) -> Vec<usize> {
    asset
        .meshes
        .iter()
        .enumerate()
        .filter(|(_, m)| {
            !asset
                .game
                .body_groups
                .iter()
                .any(|g| g.meshes.contains(&m.name))
        })
        .map(|(i, _)| i)
        .collect()
}

/// The meshes of body `number`, in file order.
fn body(asset: &Asset, number: u64) -> Result<Vec<usize>, BodyError> {
    let count = body_count(asset);
    if number >= count {
        return Err(BodyError::NoSuchBody { number, count });
    }
    let mut chosen = ungrouped(asset);
    let mut base = 1u64;
    for g in &asset.game.body_groups {
        let n = g.meshes.len().max(1) as u64;
        let pick = ((number / base) % n) as usize;
        base = base.saturating_mul(n);
        if let Some(name) = g.meshes.get(pick).filter(|s| !s.is_empty()) {
            if let Some(i) = asset.meshes.iter().position(|m| m.name == *name) {
                chosen.push(i);
            }
        }
    }
    chosen.sort_unstable();
    chosen.dedup();
    Ok(chosen)
}

/// The meshes `choice` names, as mesh indices: in file order for a body, in the order given for a
/// list (repeats dropped).
pub fn select(asset: &Asset, choice: &BodyChoice) -> Result<Vec<usize>, BodyError> {
    match choice {
        BodyChoice::Default => body(asset, 0),
        BodyChoice::Number(n) => body(asset, *n),
        BodyChoice::Meshes(names) => {
            if names.is_empty() {
                return Err(BodyError::Empty);
            }
            let mut out = Vec::new();
            for given in names {
                let found = match given.parse::<usize>() {
                    Ok(i) if i < asset.meshes.len() => Some(i),
                    _ => asset.meshes.iter().position(|m| m.name == *given),
                };
                let i = found.ok_or_else(|| BodyError::UnknownMesh {
                    given: given.clone(),
                    available: asset.meshes.iter().map(|m| m.name.clone()).collect(),
                })?;
                if !out.contains(&i) {
                    out.push(i);
                }
            }
            Ok(out)
        }
    }
}

/// A copy of `asset` holding only `meshes` (in that order, with their LOD figures and source-vertex
/// maps); everything else is kept.
pub fn only(asset: &Asset, meshes: &[usize]) -> Asset {
    let pick = |m: usize| asset.meshes.get(m).cloned();
    Asset {
        meshes: meshes.iter().filter_map(|&m| pick(m)).collect(),
        lod_info: meshes
            .iter()
            .filter(|&&m| m < asset.meshes.len())
            .map(|&m| asset.lod_info.get(m).cloned().unwrap_or_default())
            .collect(),
        source_vertex: meshes
            .iter()
            .filter(|&&m| m < asset.meshes.len())
            .map(|&m| asset.source_vertex.get(m).cloned().flatten())
            .collect(),
        ..asset.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::format::game::BodyGroup;
    use sinew_core::{Lod, Mesh};

    /// The scientist's layout: a body, four heads, a needle that is blank by default.
    fn scientist() -> Asset {
        let names = [
            "studio/body",
            "heads/nerd",
            "heads/einstein",
            "heads/luther",
            "heads/slick",
            "needle/needle",
            "prop",
        ];
        let mut a = Asset {
            meshes: names
                .iter()
                .map(|n| Mesh {
                    name: n.to_string(),
                    lods: vec![Lod::default()],
                })
                .collect(),
            ..Default::default()
        };
        let group = |name: &str, meshes: &[&str]| BodyGroup {
            name: name.into(),
            meshes: meshes.iter().map(|s| s.to_string()).collect(),
        };
        a.game.body_groups = vec![
            group("studio", &["studio/body"]),
            group(
                "heads",
                &[
                    "heads/nerd",
                    "heads/einstein",
                    "heads/luther",
                    "heads/slick",
                ],
            ),
            group("needle", &["", "needle/needle"]),
        ];
        a
    }

    #[test]
    fn body_numbers_count_as_the_model_viewer_does() {
        let a = scientist();
        assert_eq!(body_count(&a), 8);
        // Body 0: the body, the first head, no needle; the ungrouped prop always.
        assert_eq!(select(&a, &BodyChoice::Default).unwrap(), [0, 1, 6]);
        assert_eq!(select(&a, &BodyChoice::Number(0)).unwrap(), [0, 1, 6]);
        // Heads count first (studio has one choice): 1 = einstein, 3 = slick, 4 = nerd + needle.
        assert_eq!(select(&a, &BodyChoice::Number(1)).unwrap(), [0, 2, 6]);
        assert_eq!(select(&a, &BodyChoice::Number(3)).unwrap(), [0, 4, 6]);
        assert_eq!(select(&a, &BodyChoice::Number(4)).unwrap(), [0, 1, 5, 6]);
        assert_eq!(select(&a, &BodyChoice::Number(7)).unwrap(), [0, 4, 5, 6]);
        let e = select(&a, &BodyChoice::Number(8)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "body 8 does not exist; the file has 8 bodies (0 to 7)"
        );
    }

    #[test]
    fn mesh_lists_take_indices_and_names_in_the_order_given() {
        let a = scientist();
        let c = BodyChoice::from_args(None, Some("heads/luther, 0,3"));
        assert_eq!(select(&a, &c).unwrap(), [3, 0]);
        let e = select(&a, &BodyChoice::from_args(None, Some("9"))).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("no mesh \"9\"; the file has: 0 \"studio/body\""));
        assert_eq!(
            select(&a, &BodyChoice::from_args(None, Some(","))),
            Err(BodyError::Empty)
        );
    }

    #[test]
    fn only_keeps_the_chosen_meshes_in_order() {
        let a = scientist();
        let b = only(&a, &[3, 0, 99]);
        let names: Vec<&str> = b.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["heads/luther", "studio/body"]);
        assert_eq!(b.game, a.game);
    }

    #[test]
    fn a_file_without_body_groups_has_one_body_of_every_mesh() {
        let mut a = scientist();
        a.game.body_groups.clear();
        assert_eq!(body_count(&a), 1);
        assert_eq!(
            select(&a, &BodyChoice::Default).unwrap(),
            [0, 1, 2, 3, 4, 5, 6]
        );
        assert!(select(&a, &BodyChoice::Number(1)).is_err());
    }
}
