//! Linear RGB radiometric quantities (radiance, flux, coefficients, throughput).

use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Sub};

/// Linear RGB triple. Used for every spectral quantity in haze (haze renders in RGB, like
/// Mitsuba 3's `*_rgb` variants).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb(pub [f32; 3]);

impl Rgb {
    pub const ZERO: Rgb = Rgb([0.0; 3]);
    pub const ONE: Rgb = Rgb([1.0; 3]);

    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Rgb([r, g, b])
    }
    pub const fn splat(v: f32) -> Self {
        Rgb([v; 3])
    }
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Rgb([f(self.0[0]), f(self.0[1]), f(self.0[2])])
    }
    /// Channel-wise maximum.
    pub fn max(self, o: Rgb) -> Self {
        Rgb([self.0[0].max(o.0[0]), self.0[1].max(o.0[1]), self.0[2].max(o.0[2])])
    }
    /// Channel-wise minimum.
    pub fn min(self, o: Rgb) -> Self {
        Rgb([self.0[0].min(o.0[0]), self.0[1].min(o.0[1]), self.0[2].min(o.0[2])])
    }
    pub fn max_component(self) -> f32 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }
    pub fn min_component(self) -> f32 {
        self.0[0].min(self.0[1]).min(self.0[2])
    }
    /// Arithmetic mean of the channels (the hero-channel pdf mixes channels with weight 1/3).
    pub fn mean(self) -> f32 {
        (self.0[0] + self.0[1] + self.0[2]) / 3.0
    }
    /// Rec. 709 luminance.
    pub fn luminance(self) -> f32 {
        0.212_671 * self.0[0] + 0.715_160 * self.0[1] + 0.072_169 * self.0[2]
    }
    pub fn is_black(self) -> bool {
        self.0 == [0.0; 3]
    }
    pub fn is_finite(self) -> bool {
        self.0.iter().all(|c| c.is_finite())
    }
    /// `exp(-self * d)` channel by channel: transmittance for extinction `self` over distance `d`.
    /// Grey extinction (equal channels, the common case) takes one `exp`: the same values.
    #[inline]
    pub fn exp_neg(self, d: f32) -> Self {
        let [r, g, b] = self.0;
        if r == g && g == b {
            Rgb::splat((-r * d).exp())
        } else {
            self.map(|s| (-s * d).exp())
        }
    }
}

impl Index<usize> for Rgb {
    type Output = f32;
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

macro_rules! rgb_binop {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for Rgb {
            type Output = Rgb;
            fn $f(self, o: Rgb) -> Rgb {
                Rgb([self.0[0] $op o.0[0], self.0[1] $op o.0[1], self.0[2] $op o.0[2]])
            }
        }
        impl $tr<f32> for Rgb {
            type Output = Rgb;
            fn $f(self, o: f32) -> Rgb {
                Rgb([self.0[0] $op o, self.0[1] $op o, self.0[2] $op o])
            }
        }
        impl $tra for Rgb {
            fn $fa(&mut self, o: Rgb) {
                *self = *self $op o;
            }
        }
        impl $tra<f32> for Rgb {
            fn $fa(&mut self, o: f32) {
                *self = *self $op o;
            }
        }
    };
}
rgb_binop!(Add, add, AddAssign, add_assign, +);
rgb_binop!(Mul, mul, MulAssign, mul_assign, *);
rgb_binop!(Div, div, DivAssign, div_assign, /);

impl Sub for Rgb {
    type Output = Rgb;
    fn sub(self, o: Rgb) -> Rgb {
        Rgb([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}

impl Mul<Rgb> for f32 {
    type Output = Rgb;
    fn mul(self, o: Rgb) -> Rgb {
        o * self
    }
}

impl std::iter::Sum for Rgb {
    fn sum<I: Iterator<Item = Rgb>>(iter: I) -> Rgb {
        iter.fold(Rgb::ZERO, |a, b| a + b)
    }
}

impl std::fmt::Display for Rgb {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "({}, {}, {})", self.0[0], self.0[1], self.0[2])
    }
}
