//! Property tests: mapping arbitrary names and parents never panics and stays one-to-one.

use proptest::prelude::*;
use sinew_pipeline::mapping::{map_joints, normalise, read_mapping, write_mapping, JointSet};
use std::collections::HashSet;

fn joint_set() -> impl Strategy<Value = JointSet> {
    prop::collection::vec(
        (
            prop_oneof![
                "[A-Za-z0-9 _.:|-]{0,14}",
                "(Bip01 |mixamorig:|)(L |R |Left|Right|)(Leg|Leg1|Arm|Arm2|Spine|Shoulder|Collar|Hip|Finger0|Thumb)[0-9]?",
                any::<String>(),
            ],
            prop::option::of(0usize..40),
        ),
        0..40,
    )
    .prop_map(|v| {
        let (names, parents): (Vec<String>, Vec<Option<usize>>) = v.into_iter().unzip();
        JointSet::new(names, parents)
    })
}

proptest! {
    #[test]
    fn mapping_is_one_to_one_and_round_trips(rig in joint_set(), motion in joint_set()) {
        for n in rig.names() {
            let _ = normalise(n);
        }
        let m = map_joints(&rig, &motion);
        prop_assert_eq!(m.entries.len(), rig.names().len());
        let used: Vec<&str> = m.pairs().map(|(_, b)| b).collect();
        let distinct: HashSet<&str> = used.iter().copied().collect();
        prop_assert_eq!(used.len(), distinct.len());
        prop_assert_eq!(used.len() + m.unmatched_motion.len(), motion.names().len());
        // Deterministic.
        prop_assert_eq!(&map_joints(&rig, &motion), &m);
        // A written mapping reads back to the same pairs when names are unique.
        let unique = |s: &JointSet| s.names().iter().collect::<HashSet<_>>().len() == s.names().len();
        if unique(&rig) && unique(&motion) {
            let back = read_mapping(&write_mapping(&m), &rig, &motion).unwrap();
            prop_assert_eq!(back.pairs().collect::<Vec<_>>(), m.pairs().collect::<Vec<_>>());
        }
    }
}

#[test]
fn large_sets_finish() {
    // A 3000-joint chain of spine-like names against 3000 others: no quadratic blow-up in the
    // slot stage, fuzzy skipped above its pair limit.
    let names: Vec<String> = (0..3000).map(|i| format!("Spine{i}")).collect();
    let parents: Vec<Option<usize>> = (0usize..3000).map(|i| i.checked_sub(1)).collect();
    let rig = JointSet::new(names.clone(), parents.clone());
    let motion = JointSet::new(
        names
            .iter()
            .map(|n| format!("ns:{}", n.replace("Spine", "Chest")))
            .collect(),
        parents,
    );
    let m = map_joints(&rig, &motion);
    // All pair up through the spine slot, by order.
    assert_eq!(m.pairs().count(), 3000);
    assert_eq!(m.motion_for("Spine17"), Some("ns:Chest17"));
}
