//! Vectors and quaternions with a lane value per component ([`V3`],
//! [`Q4`]), and the half-angle turn of every lane ([`turn_by`]): each
//! operation in glam's order, so that a lane gives glam's bits.

use glam::{Quat, Vec3};

use super::Lane;
use crate::solver::rotation::{FOURTH_ORDER, NEGLIGIBLE_TURN};

/// A vector per lane.
#[derive(Clone, Copy)]
pub(crate) struct V3<F: Lane> {
    pub x: F,
    pub y: F,
    pub z: F,
}

impl<F: Lane> V3<F> {
    #[inline(always)]
    pub(super) fn from_lanes(v: F::Array<Vec3>) -> Self {
        let v = v.as_ref();
        Self {
            x: F::new(F::each(|k| v[k].x)),
            y: F::new(F::each(|k| v[k].y)),
            z: F::new(F::each(|k| v[k].z)),
        }
    }

    /// `v` in every lane.
    #[inline(always)]
    pub(crate) fn splat(v: Vec3) -> Self {
        Self {
            x: F::splat(v.x),
            y: F::splat(v.y),
            z: F::splat(v.z),
        }
    }

    /// `values[idx[k]]` in each lane `k`.
    #[inline(always)]
    pub(crate) fn gather(values: &[Vec3], idx: &F::Array<u32>) -> Self {
        Self::from_lanes(F::each(|k| values[idx.as_ref()[k] as usize]))
    }

    /// Lane `k`'s vector.
    #[inline(always)]
    pub(crate) fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x.at(k), self.y.at(k), self.z.at(k))
    }

    /// Sets lane `k`'s vector.
    #[inline(always)]
    pub(crate) fn set_lane(&mut self, k: usize, v: Vec3) {
        self.x.set(k, v.x);
        self.y.set(k, v.y);
        self.z.set(k, v.z);
    }

    /// `a` in the lanes of `mask`, `b` elsewhere.
    #[inline(always)]
    pub(crate) fn select(mask: F, a: Self, b: Self) -> Self {
        Self {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }

    /// Set in the lanes whose point lies in the box `[lo, hi]`, bounds
    /// included (as glam's `x.cmpge(lo).all() && x.cmple(hi).all()`).
    #[inline(always)]
    pub(crate) fn in_box(self, lo: Self, hi: Self) -> F {
        self.x.simd_ge(lo.x)
            & self.y.simd_ge(lo.y)
            & self.z.simd_ge(lo.z)
            & self.x.simd_le(hi.x)
            & self.y.simd_le(hi.y)
            & self.z.simd_le(hi.z)
    }

    /// As glam's `Vec3::dot`.
    #[inline(always)]
    pub(crate) fn dot(self, o: Self) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// As glam's `Vec3::cross`.
    #[inline(always)]
    pub(crate) fn cross(self, o: Self) -> Self {
        Self {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// As glam's `Vec3::length_squared`.
    #[inline(always)]
    pub(crate) fn length_squared(self) -> F {
        self.dot(self)
    }

    /// As glam's `Vec3::length`.
    #[inline(always)]
    pub(crate) fn length(self) -> F {
        self.dot(self).sqrt()
    }
}

impl<F: Lane> std::ops::Add for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<F: Lane> std::ops::Sub for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<F: Lane> std::ops::Mul<F> for V3<F> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: F) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// A quaternion per lane.
#[derive(Clone, Copy)]
pub(crate) struct Q4<F: Lane> {
    pub x: F,
    pub y: F,
    pub z: F,
    pub w: F,
}

impl<F: Lane> Q4<F> {
    #[inline(always)]
    pub(super) fn lane(&self, k: usize) -> Quat {
        Quat::from_xyzw(self.x.at(k), self.y.at(k), self.z.at(k), self.w.at(k))
    }

    /// Each lane's normal (as [`normal_of`](crate::solver::rotation::normal_of)).
    #[inline(always)]
    pub(crate) fn normal(&self) -> V3<F> {
        let two = F::splat(2.0);
        V3 {
            x: two * (self.x * self.z + self.w * self.y),
            y: two * (self.y * self.z - self.w * self.x),
            z: F::ONE - two * (self.x * self.x + self.y * self.y),
        }
    }

    /// `self * q`, with glam's order of operations for `Quat`'s product.
    #[inline(always)]
    fn mul(self, q: Self) -> Self {
        let l = self;
        Self {
            x: (l.w * q.x + l.x * q.w) + (l.y * q.z - l.z * q.y),
            y: (l.w * q.y - l.x * q.z) + (l.y * q.w + l.z * q.x),
            z: (l.w * q.z + l.x * q.y) + (l.z * q.w - l.y * q.x),
            w: (l.w * q.w - l.x * q.x) - (l.y * q.y + l.z * q.z),
        }
    }
}

/// [`turn_by`](crate::solver::rotation::turn_by) by its half-angle series, in
/// every lane; the mask says which lanes are within the series' range (the
/// others need the scalar turn). The fourth-order terms only where they
/// count ([`FOURTH_ORDER`]): elsewhere `θ⁴` would be subnormal for the tiny
/// turns of a resting cloth.
#[inline(always)]
pub(crate) fn turn_by<F: Lane>(q: Q4<F>, r: V3<F>) -> (Q4<F>, F) {
    // As the scalar `angle_squared`: components under NEGLIGIBLE_TURN left out.
    let kept = |v: F| v.abs().simd_lt(NEGLIGIBLE_TURN).select(F::ZERO, v);
    let t2 = V3 {
        x: kept(r.x),
        y: kept(r.y),
        z: kept(r.z),
    }
    .length_squared();
    let (c, s) = (
        F::ONE - t2 * F::splat(1.0 / 8.0),
        F::splat(0.5) - t2 * F::splat(1.0 / 48.0),
    );
    let fourth = t2.simd_ge(FOURTH_ORDER);
    let (c, s) = if fourth.none() {
        (c, s)
    } else {
        // At least FOURTH_ORDER² in every lane, so never subnormal; the
        // lanes below keep the second-order values.
        let t2 = t2.max(F::splat(FOURTH_ORDER));
        let t4 = t2 * t2;
        (
            fourth.select(c + t4 * F::splat(1.0 / 384.0), c),
            fourth.select(s + t4 * F::splat(1.0 / 3840.0), s),
        )
    };
    let d = Q4 {
        x: r.x * s,
        y: r.y * s,
        z: r.z * s,
        w: c,
    };
    (d.mul(q), t2.simd_lt(0.0025))
}
