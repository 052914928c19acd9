//! Kernel interpolation (the seed paper's Eq. 1–3): weight functions, two
//! neighbour searches with one contract (the uniform cell grid of `grid.rs`, the
//! mapper's default, and the kiddo k-d tree of `neighbours.rs`, the reference),
//! and the Shepard-normalised mapper that is parallel over query points. Pure
//! computation, no I/O.
//!
//! Kernels follow the paper's notation: R = d/h, w(R) = α·shape(R), with α the
//! normalisation that makes ∫w = 1 over the line, plane or space.

pub mod calibrate;
pub mod grid;
pub mod loo;
pub mod mapper;
pub mod neighbours;
pub mod simd;

use std::f64::consts::PI;

/// A smoothing kernel.
pub trait Kernel: Sync {
    /// Short name: `cubic`, `gaussian`, `wendland`.
    fn name(&self) -> &'static str;
    /// The unnormalised shape at R = d/h (0 beyond the support).
    fn shape(&self, r_over_h: f64) -> f64;
    /// Support radius in units of h (the Gaussian's truncation radius).
    fn support(&self) -> f64;
    /// The paper's normalisation α in 1, 2 or 3 dimensions.
    fn alpha(&self, dim: usize, h: f64) -> f64;
    /// w(d) = α·shape(d/h).
    fn weight(&self, d: f64, h: f64, dim: usize) -> f64 {
        self.alpha(dim, h) * self.shape(d / h)
    }
}

/// Monaghan & Lattanzio's cubic spline (paper Eq. 2), support 2h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicSpline;

impl Kernel for CubicSpline {
    fn name(&self) -> &'static str {
        "cubic"
    }
    #[inline]
    fn shape(&self, r: f64) -> f64 {
        // Both pieces first, then a choice the compiler makes without a branch.
        let inner = 2.0 / 3.0 - r * r + 0.5 * r * r * r;
        let t = 2.0 - r;
        let outer = t * t * t / 6.0;
        let w = if r < 2.0 { outer } else { 0.0 };
        if r < 1.0 { inner } else { w }
    }
    fn support(&self) -> f64 {
        2.0
    }
    fn alpha(&self, dim: usize, h: f64) -> f64 {
        match dim {
            1 => 1.0 / h,
            2 => 15.0 / (7.0 * PI * h * h),
            _ => 3.0 / (2.0 * PI * h * h * h),
        }
    }
}

/// The Gaussian (paper Eq. 3), truncated at `cutoff`·h (default 3h). The mass
/// beyond the cut-off is dropped; [`Gaussian::truncated_mass`] says how much.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    pub cutoff: f64,
}

impl Default for Gaussian {
    fn default() -> Gaussian {
        Gaussian { cutoff: 3.0 }
    }
}

impl Gaussian {
    /// Fraction of ∫w lost by the truncation: erfc(c) in 1D, e^{−c²} in 2D,
    /// erfc(c) + 2c·e^{−c²}/√π in 3D (1.2e-4 at c = 3 in 2D).
    pub fn truncated_mass(&self, dim: usize) -> f64 {
        let c = self.cutoff;
        match dim {
            1 => libm::erfc(c),
            2 => (-c * c).exp(),
            _ => libm::erfc(c) + 2.0 * c * (-c * c).exp() / PI.sqrt(),
        }
    }
}

impl Kernel for Gaussian {
    fn name(&self) -> &'static str {
        "gaussian"
    }
    fn shape(&self, r: f64) -> f64 {
        if r <= self.cutoff {
            (-r * r).exp()
        } else {
            0.0
        }
    }
    fn support(&self) -> f64 {
        self.cutoff
    }
    fn alpha(&self, dim: usize, h: f64) -> f64 {
        match dim {
            1 => 1.0 / (PI.sqrt() * h),
            2 => 1.0 / (PI * h * h),
            _ => 1.0 / (PI.powf(1.5) * h * h * h),
        }
    }
}

/// Wendland C2, support 2h: with q = d/h, w = α(1 − q/2)⁴(2q + 1) in 2D and 3D
/// (α = 7/(4πh²), 21/(16πh³)) and α(1 − q/2)³(1.5q + 1) in 1D (α = 5/(8h)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WendlandC2 {
    dim1: bool,
}

impl WendlandC2 {
    pub fn new(dim: usize) -> WendlandC2 {
        WendlandC2 { dim1: dim == 1 }
    }
}

impl Kernel for WendlandC2 {
    fn name(&self) -> &'static str {
        "wendland"
    }
    fn shape(&self, q: f64) -> f64 {
        if q >= 2.0 {
            return 0.0;
        }
        let t = 1.0 - 0.5 * q;
        if self.dim1 {
            t * t * t * (1.5 * q + 1.0)
        } else {
            t * t * t * t * (2.0 * q + 1.0)
        }
    }
    fn support(&self) -> f64 {
        2.0
    }
    fn alpha(&self, dim: usize, h: f64) -> f64 {
        match dim {
            1 => 5.0 / (8.0 * h),
            2 => 7.0 / (4.0 * PI * h * h),
            _ => 21.0 / (16.0 * PI * h * h * h),
        }
    }
}

/// The kernels a3d-init offers, dispatched without virtual calls in hot loops.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum KernelKind {
    Cubic,
    Gaussian { cutoff: f64 },
    Wendland { dim1: bool },
}

impl KernelKind {
    /// Parses `cubic`, `gaussian` or `wendland` for a problem of dimension `dim`.
    pub fn parse(s: &str, dim: usize) -> Option<KernelKind> {
        match s {
            "cubic" | "cubic-spline" => Some(KernelKind::Cubic),
            "gaussian" | "gauss" => Some(KernelKind::Gaussian { cutoff: 3.0 }),
            "wendland" | "wendland-c2" => Some(KernelKind::Wendland { dim1: dim == 1 }),
            _ => None,
        }
    }

    /// The same kernel for a problem of dimension `dim` (the Wendland
    /// function has its own form in 1D).
    pub fn for_dim(self, dim: usize) -> KernelKind {
        match self {
            KernelKind::Wendland { .. } => KernelKind::Wendland { dim1: dim == 1 },
            k => k,
        }
    }

    /// The paper's spacing rule (§2.2): h = factor · l with l the median
    /// nearest-node spacing; 1.0 for the cubic spline (and Wendland), 0.8 for
    /// the Gaussian. The one place this constant lives.
    pub fn spacing_factor(self) -> f64 {
        match self {
            KernelKind::Gaussian { .. } => 0.8,
            _ => 1.0,
        }
    }
}

impl KernelKind {
    /// `w[i] = shape(distance(xs[i]) / h)` for every entry of `xs`, the kernel
    /// chosen once for the whole list, in one loop the compiler vectorises:
    /// what [`KernelKind::shapes`], [`KernelKind::weights`] and
    /// [`KernelKind::weights_squared`] share.
    #[inline(always)]
    fn fill<T: Copy>(self, xs: &[T], h: f64, w: &mut Vec<f64>, distance: impl Fn(T) -> f64) {
        #[inline(always)]
        fn each<T: Copy>(
            xs: &[T],
            h: f64,
            w: &mut Vec<f64>,
            distance: impl Fn(T) -> f64,
            shape: impl Fn(f64) -> f64,
        ) {
            w.clear();
            w.extend(xs.iter().map(|&x| shape(distance(x) / h)));
        }
        match self {
            KernelKind::Cubic => each(xs, h, w, distance, |q| CubicSpline.shape(q)),
            KernelKind::Gaussian { cutoff } => {
                each(xs, h, w, distance, |q| Gaussian { cutoff }.shape(q))
            }
            KernelKind::Wendland { dim1 } => {
                each(xs, h, w, distance, |q| WendlandC2 { dim1 }.shape(q))
            }
        }
    }

    /// `w[i] = shape(d[i] / h)` for every neighbour `(_, d)` of `found`, the
    /// kernel chosen once for the whole list.
    pub fn shapes(self, found: &[(u32, f64)], h: f64, w: &mut Vec<f64>) {
        self.fill(found, h, w, |(_, d)| d);
    }

    /// `w[i] = shape(d[i] / h)` for every distance of `d` (the same values
    /// as [`KernelKind::shapes`]), in one loop the compiler vectorises.
    #[inline(always)]
    pub fn weights(self, d: &[f64], h: f64, w: &mut Vec<f64>) {
        self.fill(d, h, w, |d| d);
    }

    /// [`KernelKind::weights`] on the distances `sqrt(d2[i])`, from the
    /// squared distances the grid finds: the cubic spline's in AVX-512 where
    /// `simd` is given ([`simd::Avx512::cubic`], the same bits).
    #[inline(always)]
    pub fn weights_squared(self, d2: &[f64], h: f64, simd: Option<simd::Avx512>, w: &mut Vec<f64>) {
        match (self, simd) {
            (KernelKind::Cubic, Some(simd)) => simd.cubic(d2, h, w),
            _ => self.fill(d2, h, w, f64::sqrt),
        }
    }
}

impl Kernel for KernelKind {
    fn name(&self) -> &'static str {
        match self {
            KernelKind::Cubic => CubicSpline.name(),
            KernelKind::Gaussian { .. } => "gaussian",
            KernelKind::Wendland { .. } => "wendland",
        }
    }
    #[inline]
    fn shape(&self, r: f64) -> f64 {
        match *self {
            KernelKind::Cubic => CubicSpline.shape(r),
            KernelKind::Gaussian { cutoff } => Gaussian { cutoff }.shape(r),
            KernelKind::Wendland { dim1 } => WendlandC2 { dim1 }.shape(r),
        }
    }
    fn support(&self) -> f64 {
        match *self {
            KernelKind::Cubic => 2.0,
            KernelKind::Gaussian { cutoff } => cutoff,
            KernelKind::Wendland { .. } => 2.0,
        }
    }
    fn alpha(&self, dim: usize, h: f64) -> f64 {
        match *self {
            KernelKind::Cubic => CubicSpline.alpha(dim, h),
            KernelKind::Gaussian { cutoff } => Gaussian { cutoff }.alpha(dim, h),
            KernelKind::Wendland { dim1 } => WendlandC2 { dim1 }.alpha(dim, h),
        }
    }
}
