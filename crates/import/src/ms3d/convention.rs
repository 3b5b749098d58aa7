//! Milkshape conventions that both the mesh builder and the animation builder apply: the Euler angle
//! order of joints and keys, and the shape of a vertex's joint influences.

use sinew_core::glam::{EulerRot, Quat};

/// The rotation of Milkshape Euler angles (x, y, z): `Rz * Ry * Rx` acting on column vectors.
pub fn euler_to_quat(angles: [f32; 3]) -> Quat {
    Quat::from_euler(EulerRot::ZYX, angles[2], angles[1], angles[0])
}

/// Up to four (skeleton joint, weight) pairs per file vertex, weights summing to 1.
pub(crate) type Influences = ([u16; 4], [f32; 4]);
