//! sinew-core is the runtime a game links: skeletons, clip sampling, blending, local-to-model transforms,
//! skinning, and the `.sinew` reader and writer.
//!
//! It does no file-system I/O and depends on nothing else of sinew's: bytes in, plain data out. The
//! offline tools (importers, pipeline, command line) are built on top of it, and the baker calls the same
//! skinning functions as a game, so a baked cache can be checked bit for bit against the runtime.
//!
//! The pieces, in the order a frame uses them:
//! - [`Skeleton`]: joint names, parents (parents before children), bind pose, inverse bind matrices.
//! - [`Clip`]: immutable key data shared by all characters; [`ClipBinding`] maps its tracks to joints by
//!   name once; [`Sampler`] keeps a cursor per playing clip.
//! - blending of weighted, masked and additive layers, and an animator holding per-character state;
//!   [`PoseBlocks`] keeps a pose four joints per block for callers that sample and blend step by step
//!   without transposing poses (the animator's own layout);
//! - local-to-model transforms, the skinning palette, and linear blend skinning of a [`Mesh`].

pub mod animator;
pub mod blend;
pub mod clip;
pub mod compressed;
mod cpu;
mod rotation;
mod skin_avx;
pub use cpu::set_baseline_only;
pub mod format;
pub mod mesh;
pub mod pose_blocks;
pub mod skeleton;
pub mod skinning;
mod soa;
pub mod transform;

pub use animator::{Animator, AnimatorError, ClipId};
pub use blend::{apply_additive, BlendBuffers, BlendError, Layer};
pub use clip::{
    Channel, ChannelEncoding, Clip, ClipBinding, ClipError, Curve, Sampler, Track, TrackCurves,
};
pub use mesh::{
    projected_pixels, select_lod, Lod, Mesh, Submesh, DEFAULT_PIXEL_ERROR, MAX_INFLUENCES,
};
pub use pose_blocks::PoseBlocks;
pub use skeleton::{JointDesc, JointIndex, Skeleton, SkeletonError};
pub use skinning::{
    local_to_model, local_to_model_and_palette, skin, skin_lod, skin_with, skinning_palette,
    NormalTransform, SkinError,
};
pub use transform::Transform;

pub use glam;
