//! studiomdl's arithmetic, step for step in its precision: bone matrices through float degrees,
//! vertex truncation to two decimals, angle wrapping.

use std::f64::consts::PI;

/// Truncates to two decimals as studiomdl's `lookup_vertex` does (`(int)(x * 100) / 100.0`).
pub(super) fn two_decimals(x: f32) -> f32 {
    (f64::from((x * 100.0) as i32) / 100.0) as f32
}

/// Wraps an angle into [-pi, pi), in double as studiomdl does, back to float.
pub(super) fn clip_rotation(mut r: f32) -> f32 {
    let mut guard = 0;
    while f64::from(r) >= PI && guard < 64 {
        r = (f64::from(r) - PI * 2.0) as f32;
        guard += 1;
    }
    while f64::from(r) < -PI && guard < 128 {
        r = (f64::from(r) + PI * 2.0) as f32;
        guard += 1;
    }
    r
}

/// A bone's reference-pose matrices and world origin, as studiomdl keeps them.
pub(super) struct Fixup {
    pub(super) m: [[f32; 4]; 3],
    pub(super) im: [[f32; 4]; 3],
    pub(super) org: [f32; 3],
}

/// Sines and cosines of studiomdl's `AngleMatrix`: radians to float degrees and back, `sin` and `cos`
/// in double, kept as float.
pub(super) fn studio_sincos(rot: [f32; 3]) -> [(f32, f32); 3] {
    rot.map(|r| {
        let degrees = (f64::from(r) * (180.0 / PI)) as f32;
        let angle = (f64::from(degrees) * (PI * 2.0 / 360.0)) as f32;
        (f64::from(angle).sin() as f32, f64::from(angle).cos() as f32)
    })
}

/// studiomdl's `AngleMatrix` (rows; x = roll, y = pitch, z = yaw).
pub(super) fn angle_matrix(rot: [f32; 3]) -> [[f32; 4]; 3] {
    let [(sr, cr), (sp, cp), (sy, cy)] = studio_sincos(rot);
    [
        [
            cp * cy,
            sr * sp * cy + cr * -sy,
            cr * sp * cy + -sr * -sy,
            0.0,
        ],
        [
            cp * sy,
            sr * sp * sy + cr * cy,
            cr * sp * sy + -sr * cy,
            0.0,
        ],
        [-sp, sr * cp, cr * cp, 0.0],
    ]
}

/// studiomdl's `AngleIMatrix`: the transpose of [`angle_matrix`].
pub(super) fn angle_imatrix(rot: [f32; 3]) -> [[f32; 4]; 3] {
    let [(sr, cr), (sp, cp), (sy, cy)] = studio_sincos(rot);
    [
        [cp * cy, cp * sy, -sp, 0.0],
        [
            sr * sp * cy + cr * -sy,
            sr * sp * sy + cr * cy,
            sr * cp,
            0.0,
        ],
        [
            cr * sp * cy + -sr * -sy,
            cr * sp * sy + -sr * cy,
            cr * cp,
            0.0,
        ],
    ]
}

/// studiomdl's `R_ConcatTransforms`.
pub(super) fn concat(a: &[[f32; 4]; 3], b: &[[f32; 4]; 3]) -> [[f32; 4]; 3] {
    let mut out = [[0f32; 4]; 3];
    for i in 0..3 {
        for j in 0..4 {
            out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
            if j == 3 {
                out[i][j] += a[i][3];
            }
        }
    }
    out
}

/// studiomdl's `VectorTransform`.
pub(super) fn transform(v: [f32; 3], m: &[[f32; 4]; 3]) -> [f32; 3] {
    [0, 1, 2].map(|i| v[0] * m[i][0] + v[1] * m[i][1] + v[2] * m[i][2] + m[i][3])
}

pub(super) fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// studiomdl's `VectorNormalize` (length in double).
pub(super) fn normalize(v: [f32; 3]) -> [f32; 3] {
    let len = (f64::from(v[0]) * f64::from(v[0])
        + f64::from(v[1]) * f64::from(v[1])
        + f64::from(v[2]) * f64::from(v[2]))
    .sqrt();
    if len == 0.0 {
        return v;
    }
    let inv = (1.0 / len) as f32;
    v.map(|x| x * inv)
}
