//! Compression options, defaults and the per-clip report.

/// Default tolerance as a fraction of the skeleton's extent (its bind-pose bounding-box diagonal):
/// 0.0005, so 0.001 units on a 2-unit figure, 0.036 on a 72-unit Half-Life model.
pub const DEFAULT_RELATIVE_TOLERANCE: f32 = 0.0005;
/// Default error distance as a fraction of the skeleton's extent: 0.05 (0.1 units on a 2-unit figure).
pub const DEFAULT_RELATIVE_DISTANCE: f32 = 0.05;
/// How many of the candidate layouts (smallest estimated size first) `Fast` and `Default` refine:
/// one, its tries spread over the threads. A second one refined beside it (the default until
/// session 14) changed 6 of the corpus's 74 clips, by +0.9% to +7% (0.056% in total), for twice the
/// refinement's work; a third or fourth, less than 0.1% more (docs/performance.md, session 14).
pub(super) const DESCENDED: usize = 1;
/// Clips with more kept keys than this try only segments of 16 and 32 keys.
pub(super) const SHORT_CLIP: usize = 256;
/// Key-reduction budgets tried for each clip, as fractions of the tolerance (the rest is left to
/// quantization); the smallest result is kept. 0.3 was a fifth until session 14: with one candidate
/// refined it changed 4 of the corpus's 74 clips (-2.1% to +0.7%, -0.026% in total without it)
/// and 6 of 776 Half-Life clips (-0.003%) for 1-9% of the encoder's work; `max` still tries it.
pub(super) const KEY_BUDGETS: [f32; 3] = [0.5, 0.7, 0.85];
/// The one key-reduction budget [`Effort::Fast`] tries (of [`KEY_BUDGETS`]): one set of kept keys,
/// one first-width ladder, one layout family. Over 88 clips (the corpus, its MS3D/MDL/SMD exports
/// and 31 motion captures) it alone gives the three budgets' result on 65, 1.6% more bytes in
/// all at 0.001 @ 0.1 and 0.1% at the default tolerance, for 0.87x / 0.86x the encoder's time;
/// 0.5 alone +6.7% / +1.9% (Fox Walk past gltf2ozz's size), 0.85 alone smaller in all but slower
/// than the three (1.32x at 0.001 @ 0.1) (docs/performance.md, session 32).
pub(super) const FAST_KEY_BUDGET: f32 = 0.7;
/// The most source times x joints of a clip whose widths [`Effort::Fast`] refines (step 4's
/// one-bit tries); a larger clip keeps the widths of its first-width ladder, measured and checked
/// like every result. The refinement's work grows with the times it measures, and on long
/// captures it was two thirds of the encoder's time (cmu_01_01 exported to glTF, 27 joints x
/// 3,442 times, 0.001 @ 0.1, one thread: 330 -> 135 ms, +16% bytes, still 0.40x gltf2ozz's);
/// on a short clip it costs a few milliseconds and buys the bytes that keep `fast` below
/// gltf2ozz's size (Fox Walk, 20 x 157: 4,135 bytes refined, 4,495 not, gltf2ozz 4,341;
/// ninja.ms3d, 28 x 300: 22,192 refined, 27,455 not, gltf2ozz 24,311, so not 8,192)
/// (docs/performance.md, session 36).
pub(super) const FAST_REFINED_VOLUME: usize = 32_768;
/// Rungs of the first-width ladder (factors of 2^(1/4)) below the tolerance at which the first
/// layout's ladder starts: at half the tolerance. A uniform budget is per component, and a joint's
/// error gathers several components' and its parents', so clips with real motion pass 3 to 7 rungs
/// down (the corpus, both settings); the ladder finds the same rung from any start where passing
/// is monotone in the budget, so the start decides how many checks, not what they find. Starting
/// at the tolerance cost clips such as ninja.ms3d three passing checks (a whole pass each) where
/// one does; clips of little motion climb from here instead (docs/performance.md, session 16).
pub(super) const FIRST_RUNGS_DOWN: u32 = 4;

/// Clips with fewer source keys x joints than this are compressed on the calling thread alone:
/// handing their few milliseconds of work to the thread pool (starting it, waking its threads)
/// costs more than it saves, most of all on a loaded machine.
pub const PARALLEL_VOLUME: usize = 1024;
/// Key-reduction budgets [`Effort::Max`] tries after [`KEY_BUDGETS`].
pub(super) const MAX_EXTRA_KEY_BUDGETS: [f32; 4] = [0.15, 0.3, 0.6, 0.95];
/// Segment lengths [`Effort::Max`] tries after the default ones (every clip).
pub(super) const MAX_EXTRA_SEGMENTS: [usize; 3] = [8, 24, 48];
/// How many candidate layouts [`Effort::Max`] refines, besides the ones the default refines.
pub(super) const MAX_DESCENDED: usize = 8;

/// How much searching the encoder does for a small clip (every effort keeps the tolerance).
///
/// - `Fast`: one key budget ([`FAST_KEY_BUDGET`]) where the default tries three, and its
///   candidate refined without the graded first rounds ([`super::search::THRESHOLDS`]): every
///   round at the full limit; a clip of more than [`FAST_REFINED_VOLUME`] times x joints is not
///   refined (the first-width ladder's widths).
/// - `Default`: the search of the module docs.
/// - `Max`: the default's candidates (the same ones, so never a larger result) and more key budgets
///   ([`MAX_EXTRA_KEY_BUDGETS`]) and segment lengths ([`MAX_EXTRA_SEGMENTS`]), with up to
///   [`MAX_DESCENDED`] more candidates refined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Effort {
    /// Fewest candidates.
    Fast,
    /// The default search.
    #[default]
    Default,
    /// More candidates; never larger than `Default`.
    Max,
}

/// Options of [`compress_clip`].
#[derive(Debug, Clone, PartialEq)]
pub struct CompressOptions {
    /// Largest allowed error, model units. `None`: [`DEFAULT_RELATIVE_TOLERANCE`] x the extent.
    pub tolerance: Option<f32>,
    /// Distance of the error points from their joint, model units. `None`:
    /// [`DEFAULT_RELATIVE_DISTANCE`] x the extent.
    pub error_distance: Option<f32>,
    /// Drop keys that interpolation reproduces (step 2 of the module docs).
    pub key_reduction: bool,
    /// How much the encoder searches ([`Effort`]).
    pub effort: Effort,
}

impl Default for CompressOptions {
    fn default() -> Self {
        Self {
            tolerance: None,
            error_distance: None,
            key_reduction: true,
            effort: Effort::Default,
        }
    }
}

impl CompressOptions {
    /// The peers' settings (ozz-animation, ACL): 0.001 units at 0.1 units.
    pub fn peers() -> Self {
        Self {
            tolerance: Some(0.001),
            error_distance: Some(0.1),
            key_reduction: true,
            effort: Effort::Default,
        }
    }
}

/// What compressing one clip reached.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClipCompressionReport {
    /// Clip name.
    pub clip: String,
    /// Raw size: 40 bytes (10 f32: translation 3, rotation 4, scale 3) per animated joint per source key;
    /// for a clip with no animated channel (a single pose), per joint it drives.
    pub raw_bytes: usize,
    /// Size of the plain (f32) clip record in the `.sinew` file.
    pub plain_bytes: usize,
    /// Size of the compressed clip record in the `.sinew` file (joint names excluded: string table).
    pub compressed_bytes: usize,
    /// `raw_bytes / compressed_bytes`.
    pub ratio: f32,
    /// Largest measured error over all joints and source key times, model units.
    pub max_error: f32,
    /// 99th percentile of the same errors.
    pub p99_error: f32,
    /// Tolerance used, model units.
    pub tolerance: f32,
    /// Error distance used, model units.
    pub error_distance: f32,
    /// Tracks with at least one animated channel in the source.
    pub animated_joints: usize,
    /// Source key count.
    pub samples: usize,
    /// Keys kept after key reduction.
    pub kept_keys: usize,
    /// `compressed_bytes / (animated_joints * samples)`.
    pub bytes_per_joint_sample: f32,
    /// False when the plain clip was kept (see `kept_plain_because`).
    pub compressed: bool,
    /// Why the plain clip was kept; absent when the clip was compressed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kept_plain_because: Option<KeptPlain>,
    /// With [`KeptPlain::ToleranceNotHeld`]: the smallest error any joint was allowed, the
    /// tolerance less the f32 noise of its error points (which grows with their distance from the
    /// figure's anchor, `NOISE_ULPS` in metric.rs), model units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_limit: Option<f32>,
}

/// Why [`super::compress_clip`] kept a clip plain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum KeptPlain {
    /// An encoding held the tolerance but was not smaller than the plain record.
    NotSmaller,
    /// No encoding held the tolerance at every source key time, even at the widest bit widths:
    /// the tolerance is within the f32 rounding of the figure's coordinates about its anchor or
    /// below what the interpolation between kept keys can follow.
    ToleranceNotHeld,
}
