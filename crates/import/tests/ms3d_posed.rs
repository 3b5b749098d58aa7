//! A skinned vertex of animated_cylinder.ms3d, posed through sinew-core, against a value worked out
//! here from the raw bytes and the documented semantics (docs/formats/ms3d.md): bind local =
//! T(position) * Rz * Ry * Rx, animated local = bind local * [R(slerped key) | Hermite key position],
//! clip time 0 = frame 1, weights from boneId + vertex extra (percent at subVersion 2).
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat3, Mat4, Quat, Vec3};
use sinew_core::{Clip, ClipBinding, Sampler, Transform};
use sinew_import::{ms3d, ImportOptions};

struct Raw<'a>(&'a [u8], usize);
impl Raw<'_> {
    fn u16(&mut self) -> usize {
        self.1 += 2;
        u16::from_le_bytes([self.0[self.1 - 2], self.0[self.1 - 1]]) as usize
    }
    fn f(&mut self) -> f32 {
        self.1 += 4;
        f32::from_le_bytes(self.0[self.1 - 4..self.1].try_into().unwrap())
    }
    fn v3(&mut self) -> Vec3 {
        Vec3::new(self.f(), self.f(), self.f())
    }
    fn name(&mut self) -> String {
        let s = &self.0[self.1..self.1 + 32];
        self.1 += 32;
        String::from_utf8(s.iter().take_while(|&&c| c != 0).copied().collect()).unwrap()
    }
}

fn euler(e: Vec3) -> Mat3 {
    Mat3::from_rotation_z(e.z) * Mat3::from_rotation_y(e.y) * Mat3::from_rotation_x(e.x)
}

struct J {
    name: String,
    parent: String,
    rot: Vec3,
    pos: Vec3,
    rk: Vec<(f32, Vec3)>,
    pk: Vec<(f32, Vec3)>,
}

/// The viewer's Hermite position at time t (tangents: looped central differences, zero for <= 2 keys).
fn hermite(k: &[(f32, Vec3)], t: f32) -> Vec3 {
    let n = k.len();
    if n == 0 {
        return Vec3::ZERO;
    }
    if t < k[0].0 {
        return k[0].1;
    }
    if t >= k[n - 1].0 {
        return k[n - 1].1;
    }
    let i = (0..n - 1).find(|&i| t >= k[i].0 && t < k[i + 1].0).unwrap();
    let tangent = |m: usize| -> (Vec3, Vec3) {
        if n <= 2 {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let (a, c) = ((m + n - 1) % n, (m + 1) % n);
        let d = k[c].1 - k[a].1;
        let (dt1, dt2) = (k[m].0 - k[a].0, k[c].0 - k[m].0);
        (d * dt1 / (dt1 + dt2), d * dt2 / (dt1 + dt2))
    };
    let s = (t - k[i].0) / (k[i + 1].0 - k[i].0);
    let (h1, h2, h3, h4) = (
        2.0 * s * s * s - 3.0 * s * s + 1.0,
        -2.0 * s * s * s + 3.0 * s * s,
        s * s * s - 2.0 * s * s + s,
        s * s * s - s * s,
    );
    k[i].1 * h1 + k[i + 1].1 * h2 + tangent(i).1 * h3 + tangent(i + 1).0 * h4
}

fn slerped(k: &[(f32, Vec3)], t: f32) -> Quat {
    let q = |e: Vec3| Quat::from_mat3(&euler(e));
    let n = k.len();
    if t < k[0].0 {
        return q(k[0].1);
    }
    if t >= k[n - 1].0 {
        return q(k[n - 1].1);
    }
    let i = (0..n - 1).find(|&i| t >= k[i].0 && t < k[i + 1].0).unwrap();
    q(k[i].1).slerp(q(k[i + 1].1), (t - k[i].0) / (k[i + 1].0 - k[i].0))
}

#[test]
fn a_posed_vertex_matches_the_hand_computation() {
    let Some(b) = sinew_testdata::read_corpus("ms3d/animated_cylinder.ms3d") else {
        return;
    };
    // --- by hand from the bytes ---
    let mut r = Raw(&b, 14);
    let nv = r.u16();
    let vstart = r.1;
    r.1 += 15 * nv;
    let nt = r.u16();
    r.1 += 70 * nt;
    let ng = r.u16();
    for _ in 0..ng {
        r.1 += 33;
        let k = r.u16();
        r.1 += 2 * k + 1;
    }
    let nm = r.u16();
    r.1 += 361 * nm;
    let fps = r.f();
    r.1 += 8;
    let nj = r.u16();
    let mut js = Vec::new();
    for _ in 0..nj {
        r.1 += 1;
        let (name, parent) = (r.name(), r.name());
        let (rot, pos) = (r.v3(), r.v3());
        let (nr, np) = (r.u16(), r.u16());
        let rk = (0..nr).map(|_| (r.f(), r.v3())).collect();
        let pk = (0..np).map(|_| (r.f(), r.v3())).collect();
        js.push(J {
            name,
            parent,
            rot,
            pos,
            rk,
            pk,
        });
    }
    // Vertex extra (subVersion 2, 10-byte records) follows the 20-byte empty comment block.
    let extra = r.1 + 20;
    assert_eq!(
        i32::from_le_bytes(b[extra..extra + 4].try_into().unwrap()),
        2
    );
    // The first vertex with a split weight: own bone, then boneIds[0] with weights[1].
    let vi = (0..nv).find(|&i| b[extra + 4 + 10 * i + 4] > 0).unwrap();
    let rec = &b[extra + 4 + 10 * vi..extra + 4 + 10 * vi + 10];
    let own = b[vstart + 15 * vi + 13] as i8 as usize;
    let other = rec[0] as i8 as usize;
    let (w_own, w_other) = (rec[3] as f32 / 100.0, rec[4] as f32 / 100.0);
    assert_eq!(rec[3] as u32 + rec[4] as u32, 100);
    let mut vr = Raw(&b, vstart + 15 * vi + 1);
    let v = vr.v3();

    let frame = 150.0;
    let t_file = frame / fps;
    let global = |j: usize, animated: bool| -> Mat4 {
        let mut m = Mat4::IDENTITY;
        let mut chain = vec![j];
        while let Some(p) = js
            .iter()
            .position(|x| x.name == js[*chain.last().unwrap()].parent)
        {
            chain.push(p);
        }
        for &c in chain.iter().rev() {
            let jj = &js[c];
            let mut local = Mat4::from_translation(jj.pos) * Mat4::from_mat3(euler(jj.rot));
            if animated {
                local *= Mat4::from_rotation_translation(
                    slerped(&jj.rk, t_file),
                    hermite(&jj.pk, t_file),
                );
            }
            m *= local;
        }
        m
    };
    let skin = |j: usize| global(j, true) * global(j, false).inverse();
    let want = skin(own).transform_point3(v) * w_own + skin(other).transform_point3(v) * w_other;

    // --- through the importer and sinew-core ---
    let s = ms3d::import(
        "animated_cylinder.ms3d",
        &b,
        &|_| unreachable!(),
        &ImportOptions::default(),
    )
    .unwrap();
    let sk = s.skeleton.as_ref().unwrap();
    let c = &s.clips[0];
    let clip = Clip::from_curves(
        &c.name,
        c.duration,
        c.sample_rate,
        false,
        false,
        c.tracks.clone(),
    )
    .unwrap();
    let binding = ClipBinding::new(&clip, sk);
    let mut locals = sk.bind_local().to_vec();
    Sampler::new()
        .sample(&clip, &binding, sk, (frame - 1.0) / fps, &mut locals)
        .unwrap();
    let mut globals: Vec<Mat4> = Vec::new();
    for (i, l) in locals.iter().enumerate() {
        let m = match sk.parents()[i] {
            Some(p) => globals[p as usize] * Transform::to_mat4(l),
            None => l.to_mat4(),
        };
        globals.push(m);
    }
    let m = &s.meshes[0];
    let k = m
        .source_vertex
        .iter()
        .position(|&sv| sv as usize == vi)
        .unwrap();
    let (jj, ww) = (m.geometry.joints[k], m.geometry.weights[k]);
    let mut got = Vec3::ZERO;
    for i in 0..4 {
        let j = jj[i] as usize;
        got +=
            (globals[j] * sk.inverse_bind()[j]).transform_point3(m.geometry.positions[k]) * ww[i];
    }
    // The vertex really moves at this frame, and both computations agree.
    assert!(
        (want - v).length() > 0.01,
        "vertex barely moves: {v} -> {want}"
    );
    assert!((got - want).length() < 1e-4, "sinew {got} vs hand {want}");
}

#[test]
fn hermite_positions_match_between_keys() {
    // ninja's first joint has more than two position keys; every frame between them is checked against the hand
    // Hermite evaluation of the raw keys.
    let Some(b) = sinew_testdata::read_corpus("ms3d/ninja.ms3d") else {
        return;
    };
    let f = ms3d::parse("ninja.ms3d", &b).unwrap();
    let j = &f.joints[0];
    let keys: Vec<(f32, Vec3)> = j
        .position_keys
        .iter()
        .map(|k| (k.time, Vec3::from_array(k.value)))
        .collect();
    assert!(keys.len() > 2);
    let s = ms3d::import(
        "ninja.ms3d",
        &b,
        &|_| unreachable!(),
        &ImportOptions::default(),
    )
    .unwrap();
    let track = s.clips[0]
        .tracks
        .iter()
        .find(|t| t.joint == j.name)
        .unwrap();
    let t0 = Vec3::from_array(j.position);
    let fps = f.animation_fps;
    let mut checked = 0;
    for frame in 2..300 {
        let t_file = frame as f32 / fps;
        let want = t0 + hermite(&keys, t_file);
        let ct = (frame as f32 - 1.0) / fps;
        let i = track
            .translation
            .times
            .iter()
            .position(|&x| (x - ct).abs() < 1e-5)
            .unwrap();
        let got = track.translation.values[i];
        assert!(
            (got - want).length() < 1e-4,
            "frame {frame}: {got} vs {want}"
        );
        checked += 1;
    }
    assert_eq!(checked, 298);
}
