//! Packed key times of compressed clip records (format 1.5, clip flag bit 5; docs/format.md).
//!
//! Key times are usually a subset of a uniform grid: key `k` sits at frame `i_k` of a step `h`, as
//! `(i_k * h) as f32`, up to a few ulps from how the source computed it. So a time is stored as the
//! gap to the previous key's frame (less one) and its difference in ulps from the grid time, each
//! in a fixed number of bits per clip. Lossless: the decoded times are the encoder's, bit for bit.

/// The fixed part of a packed key-time block: f64 step, u32 first frame, u8 gap bits, u8 residual
/// bits, two reserved zero bytes.
pub(crate) const HEADER: usize = 16;

/// Largest bit width of a gap or a residual.
pub(crate) const MAX_BITS: u8 = 32;

/// Smallest residual width: every key takes at least one bit, so a reader can bound the key count
/// by the bytes present before it allocates anything.
pub(crate) const MIN_RESIDUAL_BITS: u8 = 1;

/// A packed key-time block.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PackedTimes {
    /// Grid step, seconds.
    pub(crate) step: f64,
    /// Frame of the first key.
    pub(crate) first: u32,
    /// Bits per gap (frames between consecutive keys, less one).
    pub(crate) gap_bits: u8,
    /// Bits per residual (the time's bit pattern less the grid time's, two's complement).
    pub(crate) residual_bits: u8,
    /// Key 0's residual, then per further key its gap and residual, least significant bit first.
    pub(crate) data: Vec<u8>,
}

impl PackedTimes {
    /// Bytes of the block: header and data.
    pub(crate) fn len(&self) -> usize {
        HEADER + self.data.len()
    }
}

/// Bytes the packed data of `n` keys takes at these widths.
pub(crate) fn data_len(n: usize, gap_bits: u8, residual_bits: u8) -> u64 {
    let n = n as u64;
    let bits = if n == 0 {
        0
    } else {
        u64::from(residual_bits) + (n - 1) * (u64::from(gap_bits) + u64::from(residual_bits))
    };
    bits.div_ceil(8)
}

/// The grid time of frame `i`: what both ends compute.
fn grid(i: u64, step: f64) -> f32 {
    (i as f64 * step) as f32
}

/// Two's-complement width of the signed values, at least [`MIN_RESIDUAL_BITS`].
fn signed_bits(values: &[i64]) -> Option<u8> {
    (MIN_RESIDUAL_BITS..=MAX_BITS).find(|&w| {
        let (lo, hi) = if w == 0 {
            (0, 0)
        } else {
            (-(1i64 << (w - 1)), (1i64 << (w - 1)) - 1)
        };
        values.iter().all(|&v| v >= lo && v <= hi)
    })
}

/// `times` on the grid of `step`: each key's frame and its residual (the time's bit pattern less
/// the grid time's), and the widths that hold them.
struct Fit {
    step: f64,
    frames: Vec<u64>,
    residuals: Vec<i64>,
    gap_bits: u8,
    residual_bits: u8,
}

impl Fit {
    /// Bytes of the packed block.
    fn len(&self) -> usize {
        HEADER + data_len(self.frames.len(), self.gap_bits, self.residual_bits) as usize
    }

    /// The packed block: key 0's residual, then per further key its gap and residual, least
    /// significant bit first.
    fn pack(self) -> PackedTimes {
        let mut data =
            Vec::with_capacity(
                data_len(self.frames.len(), self.gap_bits, self.residual_bits) as usize,
            );
        // Bits not yet written (fewer than 8 between values) and how many.
        let (mut acc, mut held) = (0u64, 0u32);
        let mask = |w: u8| if w == 0 { 0 } else { u64::MAX >> (64 - w) };
        let mut put = |value: u64, width: u8| {
            // At most 7 held bits and 32 new ones: within the accumulator.
            acc |= (value & mask(width)) << held;
            held += u32::from(width);
            while held >= 8 {
                data.push(acc as u8);
                acc >>= 8;
                held -= 8;
            }
        };
        for k in 0..self.frames.len() {
            if k > 0 {
                put(self.frames[k] - self.frames[k - 1] - 1, self.gap_bits);
            }
            put(self.residuals[k] as u64, self.residual_bits);
        }
        if held > 0 {
            data.push(acc as u8);
        }
        PackedTimes {
            step: self.step,
            first: self.frames.first().copied().unwrap_or(0) as u32,
            gap_bits: self.gap_bits,
            residual_bits: self.residual_bits,
            data,
        }
    }
}

/// `times` on the grid of `step`, or `None` when they do not fit it (two keys on one frame, a
/// frame or a residual too large).
fn fit(times: &[f32], step: f64) -> Option<Fit> {
    if !(step.is_finite() && step > 0.0) || times.is_empty() {
        return None;
    }
    let mut frames = Vec::with_capacity(times.len());
    let mut residuals = Vec::with_capacity(times.len());
    for &t in times {
        let f = (f64::from(t) / step).round();
        if !(0.0..=f64::from(u32::MAX)).contains(&f) {
            return None;
        }
        let f = f as u64;
        if frames.last().is_some_and(|&p| f <= p) {
            return None;
        }
        frames.push(f);
        residuals.push(i64::from(t.to_bits()) - i64::from(grid(f, step).to_bits()));
    }
    let largest_gap = frames
        .windows(2)
        .map(|w| w[1] - w[0] - 1)
        .max()
        .unwrap_or(0);
    let gap_bits = (64 - largest_gap.leading_zeros()) as u8;
    let residual_bits = signed_bits(&residuals)?;
    if gap_bits > MAX_BITS {
        return None;
    }
    Some(Fit {
        step,
        frames,
        residuals,
        gap_bits,
        residual_bits,
    })
}

/// The smallest packing of `times` (strictly increasing, finite, at least 0) on the grids sinew
/// tries: the clip's nominal rate and its halvings down to 1/256 of a frame (the glTF importer
/// splits intervals into 2^k pieces, at most 256: docs/formats/gltf.md), and the step that
/// puts the last key on a whole frame of the nominal rate (the first of equals, in that order).
/// `None` when none fits. Only the smallest is packed.
pub(crate) fn pack(times: &[f32], sample_rate: f32) -> Option<PackedTimes> {
    let rate = f64::from(sample_rate);
    if !(rate.is_finite() && rate > 0.0) {
        return None;
    }
    let mut steps: Vec<f64> = (0..=8).map(|m| 1.0 / rate / f64::from(1u32 << m)).collect();
    if let Some(&last) = times.last() {
        let frames = (f64::from(last) * rate).round();
        if frames >= 1.0 {
            steps.push(f64::from(last) / frames);
        }
    }
    steps
        .into_iter()
        .filter_map(|s| fit(times, s))
        .min_by_key(Fit::len)
        .map(Fit::pack)
}

/// Why a packed block does not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum UnpackError {
    /// The step is not a finite positive number.
    Step,
    /// A width is above [`MAX_BITS`], or the residual width below [`MIN_RESIDUAL_BITS`].
    Width,
    /// The data is shorter than the widths require.
    Short,
    /// A decoded time is not a finite number at least 0 (or a frame overflows).
    Time,
}

/// Decodes `n` key times. Checks the step, the widths, that `data` holds the bits and that every
/// time is finite and at least 0; the caller checks that they increase.
pub(crate) fn unpack(
    step: f64,
    first: u32,
    gap_bits: u8,
    residual_bits: u8,
    data: &[u8],
    n: usize,
) -> Result<Vec<f32>, UnpackError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(UnpackError::Step);
    }
    if gap_bits > MAX_BITS || !(MIN_RESIDUAL_BITS..=MAX_BITS).contains(&residual_bits) {
        return Err(UnpackError::Width);
    }
    if (data.len() as u64) < data_len(n, gap_bits, residual_bits) {
        return Err(UnpackError::Short);
    }
    let mut bit = 0usize;
    let mut get = |width: u8| -> u64 {
        let mut v = 0u64;
        for b in 0..usize::from(width) {
            let at = bit + b;
            if data.get(at / 8).is_some_and(|x| x >> (at % 8) & 1 != 0) {
                v |= 1 << b;
            }
        }
        bit += usize::from(width);
        v
    };
    let mut out = Vec::with_capacity(n);
    let mut frame = u64::from(first);
    for k in 0..n {
        if k > 0 {
            frame = frame
                .checked_add(get(gap_bits) + 1)
                .ok_or(UnpackError::Time)?;
        }
        let raw = get(residual_bits);
        // Sign-extend the residual from its width.
        let shift = 64 - u32::from(residual_bits);
        let residual = ((raw << shift) as i64) >> shift;
        let bits = i64::from(grid(frame, step).to_bits()) + residual;
        let t = u32::try_from(bits)
            .ok()
            .filter(|&b| b <= f32::MAX.to_bits())
            .map(f32::from_bits)
            .ok_or(UnpackError::Time)?;
        out.push(t);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(times: &[f32], rate: f32) -> PackedTimes {
        let p = pack(times, rate).expect("packs");
        let back = unpack(
            p.step,
            p.first,
            p.gap_bits,
            p.residual_bits,
            &p.data,
            times.len(),
        )
        .expect("unpacks");
        assert_eq!(
            back.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
            times.iter().map(|t| t.to_bits()).collect::<Vec<_>>()
        );
        p
    }

    #[test]
    fn uniform_keys_with_gaps_cost_a_few_bits_each() {
        // Every third frame of a 30 Hz clip, as `k / 30` in f32: gaps of 2 (stored as 1), no
        // residual on one of the two grids.
        let times: Vec<f32> = (0..100).map(|k| (3 * k) as f32 / 30.0).collect();
        let p = round_trip(&times, 30.0);
        assert_eq!((p.first, p.gap_bits), (0, 2));
        assert!((1..=2).contains(&p.residual_bits), "{p:?}");
        assert!(p.len() < 100, "{} bytes", p.len());
    }

    #[test]
    fn capture_times_from_an_f64_frame_time_round_trip() {
        // BVH: (k * frame_time) computed in f64, stored as f32, nominal rate 1 / frame_time in f32.
        let ft = 0.0083333_f64;
        let times: Vec<f32> = (0..2752).map(|k| (k as f64 * ft) as f32).collect();
        let p = round_trip(&times, (1.0 / ft) as f32);
        assert_eq!(p.gap_bits, 0);
        assert!(p.residual_bits <= 3, "{p:?}");
        assert!(
            p.len() < 2752,
            "{} bytes against {} as f32",
            p.len(),
            4 * 2752
        );
    }

    #[test]
    fn rounded_decimal_times_and_irregular_times_round_trip() {
        // glTF exporters often write times rounded to six decimals; some keys fall between frames.
        let decimals: Vec<f32> = (0..130)
            .map(|k| ((k as f64 / 24.0 * 1e6).round() / 1e6) as f32)
            .collect();
        round_trip(&decimals, 24.0);
        let irregular = [0.0f32, 0.5625, 1.0, 1.5, 2.0625, 2.5, 3.0, 3.5625];
        round_trip(&irregular, 2.0);
        // Starting late, and one key.
        round_trip(&[1.25, 1.5, 2.0], 4.0);
        round_trip(&[0.75], 24.0);
    }

    #[test]
    fn times_that_fit_no_grid_are_left_as_f32() {
        // Two keys on one frame of the nominal grid and of the last-key grid.
        assert!(pack(&[0.0, 0.001, 0.002, 1.0], 1.0).is_none());
        assert!(pack(&[0.0, 1.0], 0.0).is_none());
        assert!(pack(&[0.0, 1.0], f32::NAN).is_none());
    }

    #[test]
    fn bad_blocks_are_errors() {
        assert_eq!(unpack(f64::NAN, 0, 0, 1, &[0], 1), Err(UnpackError::Step));
        assert_eq!(unpack(-1.0, 0, 0, 1, &[0], 1), Err(UnpackError::Step));
        assert_eq!(unpack(0.1, 0, 33, 1, &[0; 64], 2), Err(UnpackError::Width));
        assert_eq!(unpack(0.1, 0, 0, 0, &[0; 64], 2), Err(UnpackError::Width));
        assert_eq!(unpack(0.1, 0, 8, 8, &[0; 2], 2), Err(UnpackError::Short));
        // A residual that makes the time negative, and a grid time beyond f32.
        assert_eq!(unpack(0.1, 0, 0, 2, &[0b11], 1), Err(UnpackError::Time));
        assert_eq!(unpack(1e300, 5, 0, 1, &[0], 1), Err(UnpackError::Time));
        assert_eq!(
            unpack(0.5, u32::MAX, 32, 1, &[0xFE; 9], 3).map(|v| v.len()),
            Ok(3)
        );
    }
}
