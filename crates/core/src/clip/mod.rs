//! Clips: shared, immutable animation data, bound to skeletons by joint name and sampled with a cursor.
//!
//! # Time and samples
//!
//! A clip stores one strictly increasing array of key times (`times`, seconds, the first at or after 0),
//! shared by every animated channel, and for each key time one *frame*: the values of all animated
//! channels at that time, side by side (time-major). A channel that never changes is stored once as a
//! constant; a channel the clip does not have takes the joint's bind value.
//!
//! Sampling at time `t`:
//! - **Non-looping clip** (`looping == false`): `t` is clamped to `[0, duration]`. Before the first key
//!   the first frame holds; after the last key the last frame holds. Between keys `k` and `k+1` values
//!   are interpolated linearly (translation, scale) or by normalised lerp along the shortest path
//!   (rotation). At a key time the stored value is returned bit for bit. A clip of N frames sampled
//!   uniformly at rate `r` has keys at `0, 1/r, ..., (N-1)/r` and duration `(N-1)/r`: its last frame is
//!   its end.
//! - **Looping clip** (`looping == true`): `t` is wrapped into `[0, duration)` (negative times wrap
//!   too). Between the last key and `duration` the values run from the last frame back to the first,
//!   which is reached again at `duration`. A looping clip of N frames at rate `r` has keys at
//!   `0, ..., (N-1)/r` and duration `N/r`: frame 0 is *not* repeated at the end, and the segment after
//!   frame N-1 interpolates towards frame 0. When a source repeats frame 0 as its last frame, the
//!   wrap segment has length zero and nothing changes.
//!
//! An additive clip stores, per channel, a difference from a reference pose: a translation to add, a
//! rotation to apply before the base rotation (`delta * base`), and a scale factor. Missing channels of an
//! additive clip are the identity difference.

mod binding;
mod data;
mod key_cache;
mod sampler;
#[cfg(test)]
mod tests;
mod times;
#[cfg(test)]
mod times_tests;

pub use crate::rotation::{nlerp, normalize_rotation};
pub use binding::ClipBinding;
pub use data::{Channel, ChannelEncoding, Clip, ClipError, Curve, Track, TrackCurves};
pub use sampler::Sampler;
pub use times::union_of_times;
