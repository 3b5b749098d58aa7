//! Local joint transforms as scale, rotation and translation (SQT).

use glam::{Affine3A, Mat4, Quat, Vec3};

/// A joint's local transform: scale first, then rotation, then translation.
///
/// Non-uniform scale is allowed. Blending interpolates the three parts separately (never matrices).
///
/// `#[repr(C)]`: translation at byte 0, rotation at 16, scale at 32, 48 bytes in all (the four bytes
/// after each `Vec3` are padding). The runtime writes blended transforms with one 16-byte store per
/// part (`Transform::store`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Transform {
    /// Translation, in the parent's space.
    pub translation: Vec3,
    /// Rotation, a unit quaternion.
    pub rotation: Quat,
    /// Scale along the joint's own axes.
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

// The layout `Transform::store` writes: a 16-byte store at each part's offset stays inside the
// transform and covers one part and the padding after it.
const _: () = {
    assert!(std::mem::size_of::<Transform>() == 48);
    assert!(std::mem::offset_of!(Transform, translation) == 0);
    assert!(std::mem::offset_of!(Transform, rotation) == 16);
    assert!(std::mem::offset_of!(Transform, scale) == 32);
};

impl Transform {
    /// Sets the transform to translation `t.xyz`, rotation `r` and scale `s.xyz` (the `w` lanes of
    /// `t` and `s` are ignored): the same values as assigning the three fields, written as three
    /// 16-byte stores on x86_64 instead of the five or six a `Vec3` field takes.
    #[inline(always)]
    pub(crate) fn store(&mut self, t: glam::Vec4, r: glam::Vec4, s: glam::Vec4) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, _mm_storeu_ps};
            let p = (self as *mut Transform).cast::<f32>();
            let (t, r, s): (__m128, __m128, __m128) = (t.into(), r.into(), s.into());
            // SAFETY: `p` comes from `&mut self`, so it may write all 48 bytes of the transform;
            // by the layout asserted above, the stores cover bytes 0..16 (translation and padding),
            // 16..32 (rotation) and 32..48 (scale and padding); padding may hold any bytes. SSE is
            // part of x86_64, and unaligned stores need no alignment.
            #[allow(unsafe_code)]
            unsafe {
                _mm_storeu_ps(p, t);
                _mm_storeu_ps(p.add(4), r);
                _mm_storeu_ps(p.add(8), s);
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            *self = Transform {
                translation: t.truncate(),
                rotation: Quat::from_vec4(r),
                scale: s.truncate(),
            };
        }
    }

    /// The identity transform.
    pub const IDENTITY: Self = Self {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// Builds a transform from its three parts.
    pub fn new(translation: Vec3, rotation: Quat, scale: Vec3) -> Self {
        Self {
            translation,
            rotation,
            scale,
        }
    }

    /// A pure translation.
    pub fn from_translation(translation: Vec3) -> Self {
        Self {
            translation,
            ..Self::IDENTITY
        }
    }

    /// A pure rotation.
    pub fn from_rotation(rotation: Quat) -> Self {
        Self {
            rotation,
            ..Self::IDENTITY
        }
    }

    /// The column-major 4x4 matrix `T * R * S`.
    pub fn to_mat4(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// The affine matrix `T * R * S`.
    #[inline]
    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }
}

/// Every float of `t` (translation, rotation, scale), as bits: what the crate's tests compare.
#[cfg(test)]
pub(crate) fn transform_bits(t: &[Transform]) -> Vec<u32> {
    t.iter()
        .flat_map(|t| {
            let mut v = t.translation.to_array().to_vec();
            v.extend(t.rotation.to_array());
            v.extend(t.scale.to_array());
            v
        })
        .map(f32::to_bits)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_applies_scale_then_rotation_then_translation() {
        let t = Transform::new(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            Vec3::new(2.0, 1.0, 1.0),
        );
        // (1,0,0) scaled to (2,0,0), rotated 90 degrees about z to (0,2,0), moved to (1,4,3).
        let p = t.to_mat4().transform_point3(Vec3::X);
        assert!((p - Vec3::new(1.0, 4.0, 3.0)).length() < 1e-6, "{p}");
        let a = t.to_affine().transform_point3(Vec3::X);
        assert!((a - p).length() < 1e-6);
    }
}
