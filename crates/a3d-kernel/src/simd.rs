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

    /// See [`super::Avx512::test`]; the caller checks the bounds.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx512f,avx512vl")]
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
