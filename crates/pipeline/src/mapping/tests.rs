//! Unit tests of joint-name mapping.

use super::matching::*;
use super::names::*;

#[test]
fn normalise_folds_prefixes_sides_and_case() {
    let n = |s: &str| {
        let n = normalise(s);
        (n.side, n.key)
    };
    assert_eq!(n("Bip01 L UpperArm"), (Side::Left, "upperarm".into()));
    assert_eq!(n("Bip01_R_Forearm"), (Side::Right, "forearm".into()));
    assert_eq!(n("mixamorig:LeftForeArm"), (Side::Left, "forearm".into()));
    assert_eq!(n("Armature|DEF-thigh.L"), (Side::Left, "thigh".into()));
    assert_eq!(n("LHipJoint"), (Side::Left, "hipjoint".into()));
    assert_eq!(n("Spine1"), (Side::Centre, "spine1".into()));
    assert_eq!(n("Bip01"), (Side::Centre, "bip01".into()));
    assert_eq!(n("ValveBiped.Bip01_L_Hand"), (Side::Left, "hand".into()));
    assert_eq!(n("ns:RightHandIndex1"), (Side::Right, "handindex1".into()));
}

#[test]
fn match_method_serialises_and_displays() {
    let m = MatchMethod::Synonym { slot: Slot::Thigh };
    assert_eq!(
        serde_json::to_string(&m).unwrap(),
        r#"{"method":"synonym","slot":"thigh"}"#
    );
    assert_eq!(m.to_string(), "synonym (thigh)");
    let f = MatchMethod::Fuzzy { score: 0.5 };
    assert_eq!(
        serde_json::to_string(&f).unwrap(),
        r#"{"method":"fuzzy","score":0.5}"#
    );
    assert_eq!(f.to_string(), "fuzzy (0.50)");
    assert_eq!(
        serde_json::to_string(&MatchMethod::Exact).unwrap(),
        r#"{"method":"exact"}"#
    );
}

#[test]
fn fuzzy_score_is_one_minus_relative_distance() {
    assert_eq!(fuzzy_score("forarm", "forearm"), 1.0 - 1.0 / 7.0);
    assert_eq!(fuzzy_score("abc", "abc"), 1.0);
    assert_eq!(fuzzy_score("", ""), 0.0);
}
