//! Runtime benchmarks: one character frame on a 40-joint Biped skeleton, skinning throughput, and a
//! memcpy for the machine's memory bandwidth. Figures are in docs/performance.md.
//!
//! Every benchmark runs twice: under `wall/` with criterion's wall-clock timer, and (on Linux) under
//! `cpu/` with the benchmark thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), which leaves out the time
//! the thread waited for a core on a busy shared machine.

#![allow(clippy::unwrap_used)] // benchmark set-up on known-good data

use criterion::measurement::Measurement;
#[cfg(target_os = "linux")]
use criterion::measurement::{ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{
    local_to_model, local_to_model_and_palette, skin, skin_with, skinning_palette, Animator,
    BlendBuffers, ClipBinding, Layer, NormalTransform, PoseBlocks, Sampler, Transform,
};
use std::hint::black_box;
use std::sync::Arc;

mod rig;
use rig::{biped, clip, skin_input, upper_body_mask, SkinInput};

fn frame<M: Measurement>(c: &mut Criterion<M>, clock: &str) {
    let skeleton = Arc::new(biped());
    let n = skeleton.len();
    let walk = Arc::new(clip("walk", &skeleton, 0.0));
    let wave = Arc::new(clip("wave", &skeleton, 1.0));
    let upper = upper_body_mask(&skeleton);
    let lower: Vec<f32> = upper.iter().map(|m| 1.0 - m).collect();

    let mut anim = Animator::new(skeleton.clone());
    let a = anim.add_clip(walk.clone());
    let b = anim.add_clip(wave.clone());
    anim.set_mask(a, Some(lower.clone())).unwrap();
    anim.set_mask(b, Some(upper.clone())).unwrap();
    anim.play(a).unwrap();
    anim.activate(b).unwrap();
    let mut locals = vec![Transform::IDENTITY; n];
    let mut models = vec![Mat4::IDENTITY; n];
    let mut palette = vec![Mat4::IDENTITY; n];

    let mut g = c.benchmark_group(format!("{clock}/frame_40_joints"));
    sinew_core::set_baseline_only(true);
    g.bench_function("animator_full_frame_baseline_sse2", |bench| {
        bench.iter(|| {
            anim.update(black_box(1.0 / 60.0));
            anim.evaluate_palette(&mut models, &mut palette).unwrap();
            black_box(&palette);
        })
    });
    sinew_core::set_baseline_only(false);
    g.bench_function("animator_full_frame", |bench| {
        bench.iter(|| {
            anim.update(black_box(1.0 / 60.0));
            anim.evaluate_palette(&mut models, &mut palette).unwrap();
            black_box(&palette);
        })
    });

    // The same frame with clips keyed as Biped and motion-capture clips usually are: rotation on
    // every joint, translation on the root only.
    let mut anim_r = Animator::new(skeleton.clone());
    let ra = anim_r.add_clip(Arc::new(rig::clip_rotations("walk", &skeleton, 0.0)));
    let rb = anim_r.add_clip(Arc::new(rig::clip_rotations("wave", &skeleton, 1.0)));
    anim_r.set_mask(ra, Some(lower.clone())).unwrap();
    anim_r.set_mask(rb, Some(upper.clone())).unwrap();
    anim_r.play(ra).unwrap();
    anim_r.activate(rb).unwrap();
    g.bench_function("animator_full_frame_root_translation", |bench| {
        bench.iter(|| {
            anim_r.update(black_box(1.0 / 60.0));
            anim_r.evaluate_palette(&mut models, &mut palette).unwrap();
            black_box(&palette);
        })
    });

    // The same work without the animator, step by step.
    let bind_a = ClipBinding::new(&walk, &skeleton);
    let bind_b = ClipBinding::new(&wave, &skeleton);
    let (mut sa, mut sb) = (Sampler::new(), Sampler::new());
    let mut pose_a = skeleton.bind_local().to_vec();
    let mut pose_b = skeleton.bind_local().to_vec();
    let mut buffers = BlendBuffers::new(n);
    let mut t = 0.0f32;
    g.bench_function("sample_two_clips", |bench| {
        bench.iter(|| {
            // Wrapped to the clips' 1 s so the time never freezes in f32 (after about 25 million
            // steps of 1/60 it would stop advancing) and every iteration samples a new time.
            t += 1.0 / 60.0;
            if t >= 1.0 {
                t -= 1.0;
            }
            sa.sample(&walk, &bind_a, &skeleton, t, &mut pose_a)
                .unwrap();
            sb.sample(&wave, &bind_b, &skeleton, t, &mut pose_b)
                .unwrap();
            black_box((&pose_a, &pose_b));
        })
    });
    g.bench_function("blend_two_masked", |bench| {
        bench.iter(|| {
            buffers
                .blend(
                    skeleton.bind_local(),
                    &[
                        Layer::new(&pose_a, bind_a.driven()).with_mask(&lower),
                        Layer::new(&pose_b, bind_b.driven()).with_mask(&upper),
                    ],
                    &[],
                    &mut locals,
                )
                .unwrap();
            black_box(&locals);
        })
    });
    // The same blend with the layers kept as blocks, as ozz's `BlendingJob` takes them (SoA in,
    // SoA out): sampled once into `PoseBlocks`, resolved into `PoseBlocks`.
    let mut blocks_a = PoseBlocks::new(n);
    let mut blocks_b = PoseBlocks::new(n);
    sa.sample_layer_blocks(&walk, &bind_a, 0.3, &mut blocks_a)
        .unwrap();
    sb.sample_layer_blocks(&wave, &bind_b, 0.3, &mut blocks_b)
        .unwrap();
    let bind_blocks = PoseBlocks::from_transforms(skeleton.bind_local());
    let mut blended = PoseBlocks::new(n);
    g.bench_function("blend_two_masked_blocks", |bench| {
        bench.iter(|| {
            buffers.reset();
            buffers
                .accumulate_blocks(black_box(&blocks_a), 1.0, Some(&lower))
                .unwrap();
            buffers
                .accumulate_blocks(black_box(&blocks_b), 1.0, Some(&upper))
                .unwrap();
            buffers.resolve_blocks(&bind_blocks, &mut blended).unwrap();
            black_box(&blended);
        })
    });
    g.bench_function("local_to_model_and_palette", |bench| {
        bench.iter(|| {
            local_to_model_and_palette(
                skeleton.parents(),
                black_box(&locals),
                skeleton.inverse_bind(),
                &mut models,
                &mut palette,
            )
            .unwrap();
            black_box(&palette);
        })
    });
    g.bench_function("local_to_model_and_palette_before", |bench| {
        bench.iter(|| {
            before::local_to_model_and_palette(
                skeleton.parents(),
                black_box(&locals),
                skeleton.inverse_bind(),
                &mut models,
                &mut palette,
            );
            black_box(&palette);
        })
    });
    g.finish();
}

const VERTICES: usize = 100_000;

fn skinning<M: Measurement>(c: &mut Criterion<M>, clock: &str) {
    let skeleton = biped();
    let n = skeleton.len();
    let walk = clip("walk", &skeleton, 0.0);
    let binding = ClipBinding::new(&walk, &skeleton);
    let mut locals = skeleton.bind_local().to_vec();
    Sampler::new()
        .sample(&walk, &binding, &skeleton, 0.37, &mut locals)
        .unwrap();
    let mut models = vec![Mat4::IDENTITY; n];
    let mut palette = vec![Mat4::IDENTITY; n];
    local_to_model(skeleton.parents(), &locals, &mut models).unwrap();
    skinning_palette(&models, skeleton.inverse_bind(), &mut palette).unwrap();

    let SkinInput {
        positions,
        normals,
        joints,
        weights,
    } = skin_input(n, VERTICES);
    let mut out_p = vec![Vec3::ZERO; VERTICES];
    let mut out_n = vec![Vec3::ZERO; VERTICES];

    let mut g = c.benchmark_group(format!("{clock}/skinning"));
    g.throughput(Throughput::Elements(VERTICES as u64));
    g.bench_function("lbs4_positions_normals_100k", |bench| {
        bench.iter(|| {
            skin(
                &palette, &positions, &normals, &joints, &weights, &mut out_p, &mut out_n,
            )
            .unwrap();
            black_box((&out_p, &out_n));
        })
    });
    // Normals through the blended matrix itself, not normalised: ozz's SkinningJob without
    // inverse-transpose matrices (its `lbs4_positions_normals_100k` row).
    g.bench_function("lbs4_positions_normals_100k_blended_matrix", |bench| {
        bench.iter(|| {
            skin_with(
                NormalTransform::BlendedMatrix,
                &palette,
                &positions,
                &normals,
                &joints,
                &weights,
                &mut out_p,
                &mut out_n,
            )
            .unwrap();
            black_box((&out_p, &out_n));
        })
    });
    sinew_core::set_baseline_only(true);
    g.bench_function("lbs4_positions_normals_100k_baseline_sse2", |bench| {
        bench.iter(|| {
            skin(
                &palette, &positions, &normals, &joints, &weights, &mut out_p, &mut out_n,
            )
            .unwrap();
            black_box((&out_p, &out_n));
        })
    });
    sinew_core::set_baseline_only(false);
    g.bench_function("lbs4_positions_normals_100k_before", |bench| {
        bench.iter(|| {
            before::skin(
                &palette, &positions, &normals, &joints, &weights, &mut out_p, &mut out_n,
            )
            .unwrap();
            black_box((&out_p, &out_n));
        })
    });
    g.finish();

    // Memory bandwidth, roughly: copy 256 MiB (far beyond the 32 MiB L3). Throughput counts the bytes
    // copied once; the memory traffic is that read plus that written.
    const BYTES: usize = 256 << 20;
    let src = vec![1u8; BYTES];
    let mut dst = vec![0u8; BYTES];
    let mut g = c.benchmark_group(format!("{clock}/memory"));
    g.sample_size(10);
    g.throughput(Throughput::Bytes(BYTES as u64));
    g.bench_function("memcpy_256MiB", |bench| {
        bench.iter(|| {
            dst.copy_from_slice(black_box(&src));
            black_box(&dst);
        })
    });
    g.finish();
}

fn wall(c: &mut Criterion) {
    frame(c, "wall");
    skinning(c, "wall");
}

/// The calling thread's CPU time.
#[cfg(target_os = "linux")]
struct ThreadCpu;

#[cfg(target_os = "linux")]
static WALL: WallTime = WallTime;

#[cfg(target_os = "linux")]
impl Measurement for ThreadCpu {
    type Intermediate = std::time::Duration;
    type Value = std::time::Duration;
    fn start(&self) -> Self::Intermediate {
        let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
        std::time::Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
    }
    fn end(&self, i: Self::Intermediate) -> Self::Value {
        self.start().saturating_sub(i)
    }
    fn add(&self, a: &Self::Value, b: &Self::Value) -> Self::Value {
        *a + *b
    }
    fn zero(&self) -> Self::Value {
        std::time::Duration::ZERO
    }
    fn to_f64(&self, v: &Self::Value) -> f64 {
        v.as_nanos() as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        WALL.formatter()
    }
}

#[cfg(target_os = "linux")]
fn cpu(c: &mut Criterion<ThreadCpu>) {
    frame(c, "cpu");
    skinning(c, "cpu");
}

/// The first implementation's skinning and local-to-model (commit 6dd0435), kept here only so that
/// every run measures before and after side by side under the same machine load.
mod before {
    use sinew_core::glam::{Mat3A, Mat4, Vec3, Vec3A, Vec4};
    use sinew_core::{Transform, MAX_INFLUENCES};

    pub fn local_to_model_and_palette(
        parents: &[Option<u16>],
        locals: &[Transform],
        inverse_bind: &[Mat4],
        models: &mut [Mat4],
        palette: &mut [Mat4],
    ) {
        for i in 0..parents.len() {
            models[i] = match parents[i] {
                Some(p) => mul_srt(&models[p as usize], &locals[i]),
                None => locals[i].to_mat4(),
            };
        }
        for ((m, ib), out) in models.iter().zip(inverse_bind).zip(palette.iter_mut()) {
            *out = mul_affine(m, ib);
        }
    }

    pub fn skin(
        palette: &[Mat4],
        positions: &[Vec3],
        normals: &[Vec3],
        joints: &[[u16; MAX_INFLUENCES]],
        weights: &[[f32; MAX_INFLUENCES]],
        out_positions: &mut [Vec3],
        out_normals: &mut [Vec3],
    ) -> Option<()> {
        let n = positions.len();
        for v in 0..n {
            let m = blend(palette, &joints[v], &weights[v])?;
            out_positions[v] = transform_point(&m, positions[v]);
            out_normals[v] = transform_normal(&m, normals[v]);
        }
        Some(())
    }

    /// `parent * local.to_mat4()` for an affine `parent` (bottom row `0 0 0 1`), without the terms that
    /// multiply the local matrix's zero bottom row. For such a parent the result equals the full product.
    #[inline(always)]
    fn mul_srt(parent: &Mat4, local: &Transform) -> Mat4 {
        let r = Mat3A::from_quat(local.rotation);
        let s = local.scale;
        let t = local.translation;
        let (px, py, pz, pw) = (parent.x_axis, parent.y_axis, parent.z_axis, parent.w_axis);
        let col = |c: Vec3A, k: f32| {
            let c = c * k;
            px * c.x + py * c.y + pz * c.z
        };
        Mat4::from_cols(
            col(r.x_axis, s.x),
            col(r.y_axis, s.y),
            col(r.z_axis, s.z),
            px * t.x + py * t.y + pz * t.z + pw,
        )
    }

    /// `a * b` for affine matrices: `b`'s bottom row is taken as `0 0 0 1` (its stored bottom row is not
    /// read). For affine inputs this equals the full product, up to the sign of zero components.
    #[inline(always)]
    fn mul_affine(a: &Mat4, b: &Mat4) -> Mat4 {
        let (ax, ay, az, aw) = (a.x_axis, a.y_axis, a.z_axis, a.w_axis);
        let col = |c: Vec4| ax * c.x + ay * c.y + az * c.z;
        Mat4::from_cols(
            col(b.x_axis),
            col(b.y_axis),
            col(b.z_axis),
            col(b.w_axis) + aw,
        )
    }

    /// The blended matrix's four columns (x, y, z axes and translation).
    #[inline(always)]
    fn blend(
        palette: &[Mat4],
        j: &[u16; MAX_INFLUENCES],
        w: &[f32; MAX_INFLUENCES],
    ) -> Option<[Vec4; 4]> {
        let m0 = palette.get(j[0] as usize)?;
        let m1 = palette.get(j[1] as usize)?;
        let m2 = palette.get(j[2] as usize)?;
        let m3 = palette.get(j[3] as usize)?;
        let (w0, w1, w2, w3) = (w[0], w[1], w[2], w[3]);
        Some([
            m0.x_axis * w0 + m1.x_axis * w1 + m2.x_axis * w2 + m3.x_axis * w3,
            m0.y_axis * w0 + m1.y_axis * w1 + m2.y_axis * w2 + m3.y_axis * w3,
            m0.z_axis * w0 + m1.z_axis * w1 + m2.z_axis * w2 + m3.z_axis * w3,
            m0.w_axis * w0 + m1.w_axis * w1 + m2.w_axis * w2 + m3.w_axis * w3,
        ])
    }

    #[inline(always)]
    fn transform_point(m: &[Vec4; 4], p: Vec3) -> Vec3 {
        (m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]).truncate()
    }

    #[inline(always)]
    fn transform_normal(m: &[Vec4; 4], n: Vec3) -> Vec3 {
        let a0 = Vec3A::from_vec4(m[0]);
        let a1 = Vec3A::from_vec4(m[1]);
        let a2 = Vec3A::from_vec4(m[2]);
        let c0 = a1.cross(a2);
        let c1 = a2.cross(a0);
        let c2 = a0.cross(a1);
        let r = c0 * n.x + c1 * n.y + c2 * n.z;
        let r = if a0.dot(c0) < 0.0 { -r } else { r };
        Vec3::from(r.normalize_or_zero())
    }
}

criterion_group!(wall_clock, wall);
#[cfg(target_os = "linux")]
criterion_group! {
    name = cpu_time;
    config = Criterion::default().with_measurement(ThreadCpu);
    targets = cpu
}
#[cfg(target_os = "linux")]
criterion_main!(wall_clock, cpu_time);
#[cfg(not(target_os = "linux"))]
criterion_main!(wall_clock);
