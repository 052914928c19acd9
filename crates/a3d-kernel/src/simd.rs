//! The grid's distance test with AVX-512 where the processor has it: the one
//! module of the workspace with `unsafe` (the workspace denies it
//! everywhere else). Eight candidates are tested per instruction and the
//! hits packed with `vcompresspd`, against a branch-free store per candidate
//! in the portable loop of `grid.rs`.
//!
//! Both give the same bits: each lane computes `(p_x − q_x)² + (p_y − q_y)²
//! [+ (p_z − q_z)²]` with the same IEEE operations in the same order (no
//! fused multiply-add), and the hits come out in the same order. The unsafe
//! is confined to two things: calling a function compiled for AVX-512, which
//! [`Avx512`] only does once the processor has said it has the features, and
//! unaligned loads and stores, each checked against the slice's length first.
#![allow(unsafe_code)]

/// Proof that this processor runs AVX-512F and AVX-512VL instructions: only
/// [`Avx512::detect`] makes one.
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

impl Avx512 {
    /// The token, where the processor has AVX-512F and VL.
    pub fn detect() -> Option<Avx512> {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("popcnt")
            {
                return Some(Avx512(()));
            }
        }
        None
    }

    /// Runs `f` compiled for AVX-512 (and AVX2): `f` and what it inlines
    /// get the wider vectors where the compiler vectorises (the weights'
    /// square roots, divisions and polynomials). The same operations as the
    /// portable build, element by element, so the same bits.
    #[inline(always)]
    pub fn run<R>(self, f: impl FnOnce() -> R) -> R {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the token exists only where the processor has AVX-512F and VL.
        unsafe {
            x86::run(f)
        }
        #[cfg(not(target_arch = "x86_64"))]
        f()
    }

    /// The cubic spline's shapes of the neighbours at squared distances `d2`
    /// for smoothing length `h` into `w` (its length set to `d2`'s): eight
    /// at a time, the last eight masked, with the operations of
    /// [`crate::CubicSpline`]'s shape in its order on `sqrt(d2) / h` (IEEE
    /// square root and division, and no multiply and add fused, but for the
    /// division by 6, done exactly without the divider), so the bits of
    /// [`crate::KernelKind::weights`] on `sqrt(d2)`, without the scalar loop
    /// and its mispredicted branch the compiler leaves for a list's tail.
    pub fn cubic(self, d2: &[f64], h: f64, w: &mut Vec<f64>) {
        w.clear();
        w.resize(d2.len(), 0.0);
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the token exists only where the processor has AVX-512F and
        // VL; `w` is as long as `d2`, and every load and store is masked to
        // the lanes below that length.
        unsafe {
            x86::cubic(d2, h, w)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (d2, h);
            unreachable!("no AVX-512 token off x86-64")
        }
    }

    /// Tests the `blocks` of the padded columns against `q` (`zs` unread
    /// unless `d3`), writing each hit's grid position and squared distance
    /// to `pos` and `d2` from 0 in block order; returns the count. Every
    /// block must lie in the columns (8 points from its start) and the
    /// outputs hold 8 more than the blocks' points: checked, a panic
    /// otherwise (a bug, never input).
    pub fn test(
        self,
        [xs, ys, zs]: [&[f64]; 3],
        d3: bool,
        blocks: &[Block],
        q: [f64; 3],
        r2: f64,
        (pos, d2): (&mut [u32], &mut [f64]),
    ) -> usize {
        let cols = xs
            .len()
            .min(ys.len())
            .min(if d3 { zs.len() } else { usize::MAX });
        assert!(blocks.iter().all(|b| b.at as usize + 8 <= cols));
        assert!(pos.len() >= (blocks.len() + 1) * 8 && d2.len() >= (blocks.len() + 1) * 8);
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the token exists only where the processor has AVX-512F
        // and VL; the loads and stores are in bounds (asserted above).
        unsafe {
            x86::test(xs, ys, zs, d3, blocks, q, r2, pos, d2)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (xs, ys, zs, d3, blocks, q, r2, pos, d2);
            unreachable!("no AVX-512 token off x86-64")
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Block;
    use std::arch::x86_64::*;

    /// Calls `f`, inlined, with the features enabled.
    #[target_feature(enable = "avx512f,avx512vl,avx2")]
    #[inline]
    pub(super) unsafe fn run<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// See [`super::Avx512::cubic`]; the caller makes `w` as long as `d2`.
    #[target_feature(enable = "avx512f,avx512vl,fma")]
    pub(super) unsafe fn cubic(d2: &[f64], h: f64, w: &mut [f64]) {
        let n = d2.len().min(w.len());
        let (h, one, two) = (_mm512_set1_pd(h), _mm512_set1_pd(1.0), _mm512_set1_pd(2.0));
        let (third2, half, six) = (
            _mm512_set1_pd(2.0 / 3.0),
            _mm512_set1_pd(0.5),
            _mm512_set1_pd(6.0),
        );
        let sixth = _mm512_set1_pd(1.0 / 6.0);
        let mut i = 0;
        while i < n {
            let m: u8 = if n - i >= 8 {
                0xff
            } else {
                (1u8 << (n - i)) - 1
            };
            // SAFETY: the lanes of `m` lie below n, within both slices.
            unsafe {
                let r = _mm512_div_pd(
                    _mm512_sqrt_pd(_mm512_maskz_loadu_pd(m, d2.as_ptr().add(i))),
                    h,
                );
                // 2/3 − r·r + 0.5·r·r·r, left to right.
                let cube = _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(half, r), r), r);
                let inner = _mm512_add_pd(_mm512_sub_pd(third2, _mm512_mul_pd(r, r)), cube);
                // (2 − r)³ / 6, left to right.
                let t = _mm512_sub_pd(two, r);
                let outer = div6(_mm512_mul_pd(_mm512_mul_pd(t, t), t), sixth, six);
                // outer where r < 2, else 0; inner where r < 1 (NaN: 0).
                let v = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask::<_CMP_LT_OQ>(r, two), outer);
                let v = _mm512_mask_mov_pd(v, _mm512_cmp_pd_mask::<_CMP_LT_OQ>(r, one), inner);
                _mm512_mask_storeu_pd(w.as_mut_ptr().add(i), m, v);
            }
            i += 8;
        }
    }

    /// `x / 6`, correctly rounded as the division gives it, for x in
    /// [2⁻¹⁶⁰, 1] (the cubic's (2 − r)³ with r < 2, r a double): without
    /// the divider, which the square root and d/h keep busy. q₀ = x·(1/6) is
    /// within an ulp of x/6, so the remainder x − 6q₀ is exact (one fused
    /// multiply-add) and q₀ + rem·(1/6), rounded once, lies within 2⁻⁵² ulp
    /// of x/6. x/6 never lies within a sixth of an ulp of a midpoint between
    /// two doubles (x = X·2ᵉ with X an integer, X/3 is a whole number plus
    /// 0, 1/3 or 2/3, which sits at least 1/12 from an odd multiple of 1/4
    /// or 1/24 from one of 1/8, a sixth of the ulp either way), so both round
    /// to the same double. Lanes outside the range are never kept.
    #[inline]
    #[target_feature(enable = "avx512f,fma")]
    fn div6(x: __m512d, sixth: __m512d, six: __m512d) -> __m512d {
        let q = _mm512_mul_pd(x, sixth);
        let rem = _mm512_fnmadd_pd(q, six, x);
        _mm512_fmadd_pd(rem, sixth, q)
    }

    /// See [`super::Avx512::test`]; the caller checks the bounds.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f,avx512vl,popcnt")]
    pub(super) unsafe fn test(
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        d3: bool,
        blocks: &[Block],
        q: [f64; 3],
        r2: f64,
        pos: &mut [u32],
        d2: &mut [f64],
    ) -> usize {
        let (qx, qy, qz) = (
            _mm512_set1_pd(q[0]),
            _mm512_set1_pd(q[1]),
            _mm512_set1_pd(q[2]),
        );
        let r2 = _mm512_set1_pd(r2);
        let iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut len = 0usize;
        for b in blocks {
            let at = b.at as usize;
            // SAFETY: at + 8 ≤ every column's length and len + 8 ≤ the
            // outputs' (the caller's asserts: len grows by at most 8 a block).
            unsafe {
                let dx = _mm512_sub_pd(_mm512_loadu_pd(xs.as_ptr().add(at)), qx);
                let dy = _mm512_sub_pd(_mm512_loadu_pd(ys.as_ptr().add(at)), qy);
                let mut s = _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy));
                if d3 {
                    let dz = _mm512_sub_pd(_mm512_loadu_pd(zs.as_ptr().add(at)), qz);
                    s = _mm512_add_pd(s, _mm512_mul_pd(dz, dz));
                }
                let hit = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(s, r2) & (b.valid as u8);
                _mm512_storeu_pd(d2.as_mut_ptr().add(len), _mm512_maskz_compress_pd(hit, s));
                let ids = _mm256_add_epi32(_mm256_set1_epi32(at as i32), iota);
                _mm256_storeu_si256(
                    pos.as_mut_ptr().add(len).cast(),
                    _mm256_maskz_compress_epi32(hit, ids),
                );
                len += hit.count_ones() as usize;
            }
        }
        len
    }
}

/// Eight grid positions (the grid's LANES) from `at` tested together;
/// `valid`: the lanes (bits) that belong to the runs.
#[derive(Clone, Copy, Debug)]
pub struct Block {
    pub(crate) at: u32,
    pub(crate) valid: u32,
}

impl Block {
    /// A block with no valid lane (a placeholder, never tested).
    pub(crate) const EMPTY: Block = Block { at: 0, valid: 0 };
}
