//! The number types the IBL twins' formulas (`reference::ibl_twin`) are written over: [`Real`],
//! implemented by f32 (the twin), f64 (the exact formula) and [`Iv`], interval arithmetic under a
//! [`Model`] of the arithmetic ([`Vulkan`] or [`CpuF32`]: their rules are in ibl_twin's docs).

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::marker::PhantomData;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// What the formulas need of a number: f32 (the twin), f64 (the exact formula) or [`Iv`] (the
/// error analysis). Method names are the GLSL built-ins'.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A GLSL float literal meant as written (its f32 value).
    fn lit(x: f32) -> Self;
    /// A GLSL float literal (or constant expression) that stands for an ideal constant: its f32
    /// value `glsl` in the twin, `ideal` in the exact formula, anything between in the analysis.
    fn ideal(glsl: f32, ideal: f64) -> Self;
    /// `float(u)`.
    fn from_u32(u: u32) -> Self;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn tan(self) -> Self;
    /// One-argument `atan`.
    fn atan(self) -> Self;
    /// GLSL `atan(self, x)` (self is y).
    fn atan2(self, x: Self) -> Self;
    fn acos(self) -> Self;
    fn exp2(self) -> Self;
    fn log2(self) -> Self;
    fn pow(self, y: Self) -> Self;
    fn floor(self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
    /// `self * x * x` as GLSL writes it (`(self·x)·x`); the analysis knows the result has the
    /// sign of `self`.
    fn mul_square(self, x: Self) -> Self;
    /// GLSL `dot` of three components (the twin sums x, y, z in order; a GPU may sum in any).
    fn dot3(a: [Self; 3], b: [Self; 3]) -> Self;
    /// A sum written `t0 + t1 + ...` (in order for the twin; the analysis allows any order).
    fn sum(terms: &[Self]) -> Self;
    /// The value of a quantity that every evaluation knows exactly (a branch condition).
    fn exact(self) -> f64;
}

impl Real for f32 {
    fn lit(x: f32) -> f32 {
        x
    }
    fn ideal(glsl: f32, _: f64) -> f32 {
        glsl
    }
    fn from_u32(u: u32) -> f32 {
        u as f32
    }
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }
    fn sin(self) -> f32 {
        f32::sin(self)
    }
    fn cos(self) -> f32 {
        f32::cos(self)
    }
    fn tan(self) -> f32 {
        f32::tan(self)
    }
    fn atan(self) -> f32 {
        f32::atan(self)
    }
    fn atan2(self, x: f32) -> f32 {
        f32::atan2(self, x)
    }
    fn acos(self) -> f32 {
        f32::acos(self)
    }
    fn exp2(self) -> f32 {
        f32::exp2(self)
    }
    fn log2(self) -> f32 {
        f32::log2(self)
    }
    fn pow(self, y: f32) -> f32 {
        f32::powf(self, y)
    }
    fn floor(self) -> f32 {
        f32::floor(self)
    }
    fn min(self, o: f32) -> f32 {
        f32::min(self, o)
    }
    fn max(self, o: f32) -> f32 {
        f32::max(self, o)
    }
    fn mul_square(self, x: f32) -> f32 {
        self * x * x
    }
    fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn sum(terms: &[f32]) -> f32 {
        terms.iter().fold(0.0, |s, t| s + t)
    }
    fn exact(self) -> f64 {
        self as f64
    }
}

impl Real for f64 {
    fn lit(x: f32) -> f64 {
        x as f64
    }
    fn ideal(_: f32, ideal: f64) -> f64 {
        ideal
    }
    fn from_u32(u: u32) -> f64 {
        u as f64
    }
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    fn sin(self) -> f64 {
        f64::sin(self)
    }
    fn cos(self) -> f64 {
        f64::cos(self)
    }
    fn tan(self) -> f64 {
        f64::tan(self)
    }
    fn atan(self) -> f64 {
        f64::atan(self)
    }
    fn atan2(self, x: f64) -> f64 {
        f64::atan2(self, x)
    }
    fn acos(self) -> f64 {
        f64::acos(self)
    }
    fn exp2(self) -> f64 {
        f64::exp2(self)
    }
    fn log2(self) -> f64 {
        f64::log2(self)
    }
    fn pow(self, y: f64) -> f64 {
        f64::powf(self, y)
    }
    fn floor(self) -> f64 {
        f64::floor(self)
    }
    fn min(self, o: f64) -> f64 {
        f64::min(self, o)
    }
    fn max(self, o: f64) -> f64 {
        f64::max(self, o)
    }
    fn mul_square(self, x: f64) -> f64 {
        self * x * x
    }
    fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn sum(terms: &[f64]) -> f64 {
        terms.iter().sum()
    }
    fn exact(self) -> f64 {
        self
    }
}

/// The arithmetic an [`Iv`] models (see the module docs).
pub trait Model: Copy + Default + PartialEq + std::fmt::Debug + 'static {
    /// The Vulkan precision rules (true) or the CPU's f32 (false).
    const VULKAN: bool;
}

/// The Vulkan specification's precision rules for a GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vulkan;
impl Model for Vulkan {
    const VULKAN: bool = true;
}

/// The CPU's f32: IEEE operations rounded to nearest, libm within 2 ulp.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CpuF32;
impl Model for CpuF32 {
    const VULKAN: bool = false;
}

/// Ulps of a CPU libm function.
const LIBM_ULP: f64 = 2.0;
/// Vulkan: division, inversesqrt, atan (ulp); sin/cos (absolute); log2 near 1 (absolute).
const VK_DIV_ULP: f64 = 2.5;
const VK_INVERSESQRT_ULP: f64 = 2.0;
const VK_ATAN_ULP: f64 = 4096.0;
const VK_SIN_COS_ABS: f64 = 1.0 / 2048.0;
const VK_LOG2_ULP: f64 = 3.0;
const VK_LOG2_ABS: f64 = 1.0 / 2_097_152.0;
/// The smallest normal f32: results below it may be flushed to 0.
const MIN_NORMAL: f64 = f32::MIN_POSITIVE as f64;

/// A closed interval `[lo, hi]` that contains the exact value and every value the model `M`
/// allows (see the module docs). Endpoints may be infinite; NaN never appears.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iv<M: Model> {
    pub lo: f64,
    pub hi: f64,
    model: PhantomData<M>,
}

fn next32(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let b = x.to_bits();
    if x > 0.0 {
        f32::from_bits(b + 1)
    } else {
        f32::from_bits(b - 1)
    }
}

fn prev32(x: f32) -> f32 {
    -next32(-x)
}

/// The largest f32 ≤ `x + err`, where `x` is an f64 value and `err` the sign of the (tiny)
/// error of `x` (the true value is `x + err`, |err| below an f64 ulp of x; 0 if x is exact).
fn down32(x: f64, err: f64) -> f64 {
    if x.is_infinite() {
        return x;
    }
    let mut f = x as f32;
    if f as f64 > x || (f as f64 == x && err < 0.0) {
        f = prev32(f);
    }
    f as f64
}

/// The smallest f32 ≥ `x + err` (see [`down32`]).
fn up32(x: f64, err: f64) -> f64 {
    -down32(-x, -err)
}

/// One ulp of f32 at magnitude `m` (the spacing of f32 values in m's binade).
fn ulp32(m: f64) -> f64 {
    if !m.is_finite() {
        return f64::INFINITY;
    }
    if m < MIN_NORMAL {
        return 2f64.powi(-149);
    }
    let e = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    2f64.powi(e - 23)
}

/// The exact error of `a + b` rounded in f64 (TwoSum).
fn add_err(a: f64, b: f64, s: f64) -> f64 {
    if !s.is_finite() {
        return 0.0;
    }
    let bb = s - a;
    (a - (s - bb)) + (b - bb)
}

/// The exact error of `a · b` rounded in f64.
fn mul_err(a: f64, b: f64, p: f64) -> f64 {
    if !p.is_finite() || p == 0.0 {
        return 0.0;
    }
    a.mul_add(b, -p)
}

impl<M: Model> Iv<M> {
    pub fn new(lo: f64, hi: f64) -> Self {
        debug_assert!(!(lo > hi), "interval [{lo}, {hi}]");
        Iv {
            lo,
            hi,
            model: PhantomData,
        }
    }

    pub fn point(x: f64) -> Self {
        Self::new(x, x)
    }

    /// The interval `[lo, hi]` of exact f64 results widened by `abs` and by 4 f64 ulps (f64
    /// libm's own error), rounded outwards to f32 values, flushed.
    fn out(lo: f64, hi: f64, abs: f64) -> Self {
        let m = 4.0 * f64::EPSILON;
        let lo = if lo.is_finite() {
            lo - abs - m * lo.abs()
        } else {
            lo
        };
        let hi = if hi.is_finite() {
            hi + abs + m * hi.abs()
        } else {
            hi
        };
        Self::flushed(down32(lo, 0.0), up32(hi, 0.0))
    }

    /// `[lo, hi]` (already f32 values) with 0 added where a denormal result could be flushed.
    fn flushed(lo: f64, hi: f64) -> Self {
        let (lo, hi) = if lo.is_nan() || hi.is_nan() {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (lo, hi)
        };
        if lo < MIN_NORMAL && hi > -MIN_NORMAL {
            Self::new(lo.min(0.0), hi.max(0.0))
        } else {
            Self::new(lo, hi)
        }
    }

    /// Magnitude of the largest endpoint.
    pub fn mag(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    pub fn contains(self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    pub fn width(self) -> f64 {
        self.hi - self.lo
    }

    /// Widened by `ulps` ulp of its magnitude (and rounded outwards).
    fn widen_ulps(self, ulps: f64) -> Self {
        let m = [self.lo, self.hi]
            .iter()
            .filter(|x| x.is_finite())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        Self::out(self.lo, self.hi, ulps * ulp32(m))
    }

    /// The hull of `self` and `o`.
    pub fn hull(self, o: Self) -> Self {
        Self::new(self.lo.min(o.lo), self.hi.max(o.hi))
    }

    /// A correctly rounded binary operation from the exact f64 candidates at the corners (each
    /// with the sign of its f64 rounding error).
    fn rounded(candidates: &[(f64, f64)]) -> Self {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for &(x, e) in candidates {
            let (x, e) = if x.is_nan() { (0.0, 0.0) } else { (x, e) };
            lo = lo.min(down32(x, e));
            hi = hi.max(up32(x, e));
        }
        Self::flushed(lo, hi)
    }

    fn sin_range(lo: f64, hi: f64) -> (f64, f64) {
        use std::f64::consts::{FRAC_PI_2, TAU};
        if !(lo.is_finite() && hi.is_finite()) || hi - lo >= TAU {
            return (-1.0, 1.0);
        }
        // Is c + 2kπ in [lo, hi] for some integer k?
        let hits = |c: f64| ((lo - c) / TAU).ceil() <= ((hi - c) / TAU).floor();
        let (a, b) = (lo.sin(), hi.sin());
        let mut r = (a.min(b), a.max(b));
        if hits(FRAC_PI_2) {
            r.1 = 1.0;
        }
        if hits(-FRAC_PI_2) {
            r.0 = -1.0;
        }
        r
    }

    fn cos_range(lo: f64, hi: f64) -> (f64, f64) {
        use std::f64::consts::{PI, TAU};
        if !(lo.is_finite() && hi.is_finite()) || hi - lo >= TAU {
            return (-1.0, 1.0);
        }
        let hits = |c: f64| ((lo - c) / TAU).ceil() <= ((hi - c) / TAU).floor();
        let (a, b) = (lo.cos(), hi.cos());
        let mut r = (a.min(b), a.max(b));
        if hits(0.0) {
            r.1 = 1.0;
        }
        if hits(PI) {
            r.0 = -1.0;
        }
        r
    }

    /// The exact range of atan2 over the box y × x, the angle taken continuously: a box that
    /// meets the negative x axis gets angles around π (in (0, 2π)), which callers compare
    /// modulo 2π; a box containing the origin gets [-π, π].
    fn atan2_range(y: Self, x: Self) -> (f64, f64) {
        use std::f64::consts::PI;
        if x.lo <= 0.0 && x.hi >= 0.0 && y.lo <= 0.0 && y.hi >= 0.0 {
            return (-PI, PI);
        }
        let corners = [(y.lo, x.lo), (y.lo, x.hi), (y.hi, x.lo), (y.hi, x.hi)];
        let cut = x.hi < 0.0 && y.lo <= 0.0 && y.hi >= 0.0;
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for (yy, xx) in corners {
            let a = if cut {
                PI + (-yy).atan2(-xx)
            } else {
                yy.atan2(xx)
            };
            r = (r.0.min(a), r.1.max(a));
        }
        r
    }
}

impl<M: Model> Add for Iv<M> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        let (a, b) = (self.lo + o.lo, self.hi + o.hi);
        Self::rounded(&[
            (a, add_err(self.lo, o.lo, a)),
            (b, add_err(self.hi, o.hi, b)),
        ])
    }
}

impl<M: Model> Neg for Iv<M> {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.hi, -self.lo)
    }
}

impl<M: Model> Sub for Iv<M> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        self + -o
    }
}

impl<M: Model> Mul for Iv<M> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let c = |a: f64, b: f64| {
            let p = a * b;
            (p, mul_err(a, b, p))
        };
        Self::rounded(&[
            c(self.lo, o.lo),
            c(self.lo, o.hi),
            c(self.hi, o.lo),
            c(self.hi, o.hi),
        ])
    }
}

impl<M: Model> Div for Iv<M> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return Self::new(f64::NEG_INFINITY, f64::INFINITY);
        }
        // Corner quotients with the sign of their f64 error (from the exact remainder).
        let c = |a: f64, b: f64| {
            let q = a / b;
            if !q.is_finite() || !a.is_finite() || !b.is_finite() || q == 0.0 {
                return (q, 0.0);
            }
            let r = (-q).mul_add(b, a);
            (q, r * b.signum())
        };
        let exact = Self::rounded(&[
            c(self.lo, o.lo),
            c(self.lo, o.hi),
            c(self.hi, o.lo),
            c(self.hi, o.hi),
        ]);
        if M::VULKAN {
            exact.widen_ulps(VK_DIV_ULP)
        } else {
            exact
        }
    }
}

impl<M: Model> Real for Iv<M> {
    fn lit(x: f32) -> Self {
        Self::point(x as f64)
    }
    fn ideal(glsl: f32, ideal: f64) -> Self {
        let g = glsl as f64;
        Self::new(g.min(ideal), g.max(ideal))
    }
    fn from_u32(u: u32) -> Self {
        let x = u as f64;
        Self::rounded(&[(x, 0.0)])
    }
    fn sqrt(self) -> Self {
        let lo = self.lo.max(0.0);
        let hi = self.hi.max(0.0);
        if hi == 0.0 {
            return Self::point(0.0);
        }
        if M::VULKAN {
            // Inherited from 1/inversesqrt(x); sqrt(0) = 0 (module docs).
            let inv = Self::out(
                1.0 / hi.sqrt(),
                if lo > 0.0 {
                    1.0 / lo.sqrt()
                } else {
                    f64::INFINITY
                },
                0.0,
            )
            .widen_ulps(VK_INVERSESQRT_ULP);
            let inv = Self::new(inv.lo.max(0.0), inv.hi);
            let r = Self::lit(1.0) / inv;
            Self::new(r.lo.max(0.0), r.hi)
        } else {
            let c = |x: f64| {
                let q = x.sqrt();
                if q == 0.0 || !q.is_finite() {
                    return (q, 0.0);
                }
                (q, (-q).mul_add(q, x))
            };
            Self::rounded(&[c(lo), c(hi)])
        }
    }
    fn sin(self) -> Self {
        let (a, b) = Self::sin_range(self.lo, self.hi);
        if M::VULKAN {
            Self::out(a, b, VK_SIN_COS_ABS)
        } else {
            Self::out(a, b, LIBM_ULP * ulp32(a.abs().max(b.abs())))
        }
    }
    fn cos(self) -> Self {
        let (a, b) = Self::cos_range(self.lo, self.hi);
        if M::VULKAN {
            Self::out(a, b, VK_SIN_COS_ABS)
        } else {
            Self::out(a, b, LIBM_ULP * ulp32(a.abs().max(b.abs())))
        }
    }
    fn tan(self) -> Self {
        if M::VULKAN {
            // Inherited from sin/cos.
            return self.sin() / self.cos();
        }
        use std::f64::consts::{FRAC_PI_2, PI};
        let pole = self.lo.is_infinite()
            || self.hi.is_infinite()
            || ((self.lo - FRAC_PI_2) / PI).ceil() <= ((self.hi - FRAC_PI_2) / PI).floor();
        if pole {
            return Self::new(f64::NEG_INFINITY, f64::INFINITY);
        }
        let (a, b) = (self.lo.tan(), self.hi.tan());
        Self::out(a, b, LIBM_ULP * ulp32(a.abs().max(b.abs())))
    }
    fn atan(self) -> Self {
        let (a, b) = (self.lo.atan(), self.hi.atan());
        let ulps = if M::VULKAN { VK_ATAN_ULP } else { LIBM_ULP };
        Self::out(a, b, ulps * ulp32(a.abs().max(b.abs())))
    }
    fn atan2(self, x: Self) -> Self {
        let (a, b) = Self::atan2_range(self, x);
        let ulps = if M::VULKAN { VK_ATAN_ULP } else { LIBM_ULP };
        Self::out(a, b, ulps * ulp32(a.abs().max(b.abs())))
    }
    fn acos(self) -> Self {
        if M::VULKAN {
            // Inherited from atan(sqrt(1 - x·x), x).
            let one = Self::lit(1.0);
            return (one - self * self).sqrt().atan2(self);
        }
        let (a, b) = (
            self.hi.clamp(-1.0, 1.0).acos(),
            self.lo.clamp(-1.0, 1.0).acos(),
        );
        Self::out(a, b, LIBM_ULP * ulp32(b.abs()))
    }
    fn exp2(self) -> Self {
        let (a, b) = (self.lo.exp2(), self.hi.exp2());
        let ulps = if M::VULKAN {
            3.0 + 2.0 * self.mag()
        } else {
            LIBM_ULP
        };
        let r = Self::out(a, b, ulps * ulp32(a.abs().max(b.abs())));
        Self::new(r.lo.max(0.0), r.hi)
    }
    fn log2(self) -> Self {
        if self.hi < 0.0 {
            return Self::new(f64::NEG_INFINITY, f64::INFINITY); // undefined
        }
        let a = if self.lo > 0.0 {
            self.lo.log2()
        } else {
            f64::NEG_INFINITY
        };
        let b = self.hi.log2();
        let m = a.abs().max(b.abs());
        let abs = if M::VULKAN {
            let near_one = self.lo <= 2.0 && self.hi >= 0.5;
            VK_LOG2_ULP * ulp32(m) + if near_one { VK_LOG2_ABS } else { 0.0 }
        } else {
            LIBM_ULP * ulp32(m)
        };
        Self::out(a, b, abs)
    }
    fn pow(self, y: Self) -> Self {
        // For x ≥ 0 and y > 0 (the only uses): pow(0, y) = 0.
        debug_assert!(y.lo > 0.0);
        if self.hi <= 0.0 {
            return Self::point(0.0);
        }
        let with_zero = self.lo <= 0.0;
        let x = Self::new(self.lo.max(2f64.powi(-149)), self.hi);
        let r = if M::VULKAN {
            // Inherited from exp2(y·log2(x)).
            (y * x.log2()).exp2()
        } else {
            let c = [
                x.lo.powf(y.lo),
                x.lo.powf(y.hi),
                x.hi.powf(y.lo),
                x.hi.powf(y.hi),
            ];
            let (a, b) = c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, &v| {
                (r.0.min(v), r.1.max(v))
            });
            Self::out(a, b, LIBM_ULP * ulp32(a.abs().max(b.abs())))
        };
        if with_zero {
            r.hull(Self::point(0.0))
        } else {
            r
        }
    }
    fn floor(self) -> Self {
        Self::new(self.lo.floor(), self.hi.floor())
    }
    fn min(self, o: Self) -> Self {
        Self::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }
    fn max(self, o: Self) -> Self {
        Self::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }
    fn mul_square(self, x: Self) -> Self {
        // (self·x)·x = self·x²·(1+δ1)(1+δ2): the exact self·x² widened by two roundings.
        let sq = if x.lo <= 0.0 && x.hi >= 0.0 {
            (0.0, x.mag() * x.mag())
        } else {
            let (a, b) = (x.lo * x.lo, x.hi * x.hi);
            (a.min(b), a.max(b))
        };
        let c = [
            self.lo * sq.0,
            self.lo * sq.1,
            self.hi * sq.0,
            self.hi * sq.1,
        ];
        let (a, b) = c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, &v| {
            let v = if v.is_nan() { 0.0 } else { v };
            (r.0.min(v), r.1.max(v))
        });
        Self::out(a, b, 0.0).widen_ulps(2.0)
    }
    fn dot3(a: [Self; 3], b: [Self; 3]) -> Self {
        Self::sum(&[a[0] * b[0], a[1] * b[1], a[2] * b[2]])
    }
    fn sum(terms: &[Self]) -> Self {
        // Any order: each of the n-1 additions rounds a partial sum no larger than the sum of the
        // terms' magnitudes.
        let (mut lo, mut hi, mut mag) = (0.0f64, 0.0f64, 0.0f64);
        for t in terms {
            lo += t.lo;
            hi += t.hi;
            mag += t.mag();
        }
        let n = terms.len().saturating_sub(1) as f64;
        Self::out(lo, hi, n * ulp32(mag))
    }
    fn exact(self) -> f64 {
        debug_assert!(self.lo == self.hi, "a branch on an inexact value");
        self.lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outward_rounding_is_exact_on_f32_values() {
        let one = Iv::<CpuF32>::lit(1.0);
        let y = Iv::<CpuF32>::lit(0.75);
        // 1 - 0.75 is exact in f32.
        assert_eq!(one - y, Iv::point(0.25));
        // 1 + 2^-30 is not: the enclosure is the two f32 neighbours.
        let r = one + Iv::lit(2f32.powi(-30));
        assert_eq!((r.lo, r.hi), (1.0, 1.0 + f32::EPSILON as f64));
        let third = Iv::<CpuF32>::lit(1.0) / Iv::lit(3.0);
        assert!(third.contains((1.0f32 / 3.0) as f64) && third.width() <= 6e-8);
        assert!(Iv::<Vulkan>::lit(2.0).sqrt().contains(2f64.sqrt()));
    }
}
