//! Which way is up and which way a model faces, as its source format defines them: the `AXES` section
//! (format 1.6). sinew never turns a model; pictures and tools read these to show it the right way
//! round.

/// A signed coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// +X.
    PosX,
    /// -X.
    NegX,
    /// +Y.
    PosY,
    /// -Y.
    NegY,
    /// +Z.
    PosZ,
    /// -Z.
    NegZ,
}

impl Axis {
    /// Every axis, in code order.
    pub const ALL: [Axis; 6] = [
        Axis::PosX,
        Axis::NegX,
        Axis::PosY,
        Axis::NegY,
        Axis::PosZ,
        Axis::NegZ,
    ];

    /// The byte the `AXES` section stores: 0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The axis of a stored byte, or `None` for a byte above 5.
    pub fn from_code(code: u8) -> Option<Axis> {
        Axis::ALL.get(usize::from(code)).copied()
    }

    /// The unit vector, `[x, y, z]`.
    pub fn vector(self) -> [f32; 3] {
        let mut v = [0.0; 3];
        let i = (self as usize) / 2;
        v[i] = if (self as usize) % 2 == 0 { 1.0 } else { -1.0 };
        v
    }

    /// `+x`, `-y` ...: how reports and docs write an axis.
    pub fn name(self) -> &'static str {
        ["+x", "-x", "+y", "-y", "+z", "-z"][self as usize]
    }

    /// True when both lie on the same coordinate line (equal or opposite).
    pub fn parallel(self, other: Axis) -> bool {
        (self as usize) / 2 == (other as usize) / 2
    }
}

/// A model's orientation: its up axis, the way it faces as its clips play (and a game shows it), and
/// the way its bind (rest) pose faces, which differs when the source turns animations but not the
/// reference pose (Half-Life's studiomdl turns every sequence by 90 degrees about Z).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Axes {
    /// Up.
    pub up: Axis,
    /// The way the model faces in its clips.
    pub forward: Axis,
    /// The way the bind pose faces.
    pub bind_forward: Axis,
}

impl Axes {
    /// Y up, facing +Z, rest pose too (glTF's definition; the convention of MS3D, OBJ and BVH).
    pub const Y_UP: Axes = Axes {
        up: Axis::PosY,
        forward: Axis::PosZ,
        bind_forward: Axis::PosZ,
    };

    /// Checked: neither facing may be parallel to up.
    pub fn new(up: Axis, forward: Axis, bind_forward: Axis) -> Result<Axes, String> {
        if up.parallel(forward) || up.parallel(bind_forward) {
            return Err(format!(
                "up {} and facing {} / {} must be perpendicular",
                up.name(),
                forward.name(),
                bind_forward.name()
            ));
        }
        Ok(Axes {
            up,
            forward,
            bind_forward,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::format::axes::*;

    #[test]
    fn codes_round_trip_and_vectors_are_unit_axes() {
        for a in Axis::ALL {
            assert_eq!(Axis::from_code(a.code()), Some(a));
            let v = a.vector();
            assert_eq!(v.iter().map(|x| x.abs()).sum::<f32>(), 1.0);
        }
        assert_eq!(Axis::from_code(6), None);
        assert_eq!(Axis::NegY.vector(), [0.0, -1.0, 0.0]);
        assert_eq!(Axis::PosZ.name(), "+z");
    }

    #[test]
    fn facing_along_up_is_refused() {
        assert!(Axes::new(Axis::PosZ, Axis::PosX, Axis::NegY).is_ok());
        assert!(Axes::new(Axis::PosZ, Axis::NegZ, Axis::NegY).is_err());
        assert!(Axes::new(Axis::PosY, Axis::PosZ, Axis::NegY).is_err());
    }
}
