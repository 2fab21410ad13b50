//! Distances between the primitives of a mesh: a point and a triangle, two
//! segments (Ericson, "Real-Time Collision Detection", 5.1.5 and 5.1.9).
//!
//! The searches measure them eight at a time, in lanes: every case of the
//! one-at-a-time function is computed, with the same arithmetic in the same
//! order, and each lane takes its own. So a lane's distance is bit for bit
//! the one-at-a-time distance (tested), on any processor, and what is built
//! from it does not depend on how the pairs were batched.

use glam::Vec3;

/// The distance from `p` to the triangle `t` (Ericson, "Real-Time Collision
/// Detection", 5.1.5): the definition [`point_triangle_distances`] keeps to.
#[cfg(test)]
pub(super) fn point_triangle(p: Vec3, t: [Vec3; 3]) -> f32 {
    match closest_on_triangle(p, t) {
        Some(q) => p.distance(q),
        // Degenerate: the nearest corner is an upper bound; use the edges.
        None => {
            let [a, b, c] = t;
            segment_point(a, b, p)
                .min(segment_point(b, c, p))
                .min(segment_point(a, c, p))
        }
    }
}

/// The point of triangle `t` nearest to `p` (Ericson, "Real-Time Collision
/// Detection", 5.1.5); `None` for a degenerate triangle.
pub(super) fn closest_on_triangle(p: Vec3, t: [Vec3; 3]) -> Option<Vec3> {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return Some(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return Some(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return Some(a + ab * v);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return Some(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return Some(a + ac * w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return Some(b + (c - b) * w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let inv = denom.recip();
    let (v, w) = (vb * inv, vc * inv);
    Some(a + ab * v + ac * w)
}

/// The distance from `p` to the segment `a b`.
#[cfg(test)]
fn segment_point(a: Vec3, b: Vec3, p: Vec3) -> f32 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let s = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * s)
}

/// The distance between segments `p1 q1` and `p2 q2`.
#[cfg(test)]
fn segment_segment(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    closest_on_segments(p1, q1, p2, q2).0
}

/// The distance between segments `p1 q1` and `p2 q2`, and where along each
/// the nearest points are (Ericson, "Real-Time Collision Detection", 5.1.9).
#[inline]
pub(super) fn closest_on_segments(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> (f32, f32, f32) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    const EPS: f32 = 1e-20;
    let (s, t);
    if a <= EPS && e <= EPS {
        return (p1.distance(p2), 0.0, 0.0);
    }
    if a <= EPS {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    ((p1 + d1 * s).distance(p2 + d2 * t), s, t)
}

/// Eight segments at a time, in lanes.
type Lanes = wide::f32x8;

/// [`closest_on_segments`]'s distance for eight pairs of segments at once:
/// `ends[k]` is `p1 q1 p2 q2` of pair `k`. The same arithmetic in the same
/// order, every case computed and the lane's own chosen, so each lane is
/// bit for bit the one-at-a-time distance.
#[inline(always)]
pub(super) fn segment_distances(ends: &[[Vec3; 4]; 8]) -> [f32; 8] {
    let sub = |a: [Lanes; 3], b: [Lanes; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [Lanes; 3], b: [Lanes; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let [p1, q1, p2, q2] = in_lanes(ends);
    let (d1, d2, r) = (sub(q1, p1), sub(q2, p2), sub(p1, p2));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let (c, b) = (dot(d1, r), dot(d1, d2));
    let (zero, one, eps) = (Lanes::ZERO, Lanes::ONE, Lanes::splat(1e-20));
    let clamp = |v: Lanes| v.max(zero).min(one);
    let (a_point, e_point) = (a.simd_le(eps), e.simd_le(eps));
    // Divisors of the lanes that do not use them are 1: no lane's choice
    // sees an infinity or a NaN it did not make itself.
    let (a_div, e_div) = (a_point.select(one, a), e_point.select(one, e));
    let denom = a * e - b * b;
    let s0 = denom.simd_gt(zero).select(
        clamp((b * f - c * e) / denom.simd_gt(zero).select(denom, one)),
        zero,
    );
    let t0 = (b * s0 + f) / e_div;
    let (below, above) = (t0.simd_lt(zero), t0.simd_gt(one));
    let mut s = below.select(clamp(-c / a_div), above.select(clamp((b - c) / a_div), s0));
    let mut t = below.select(zero, above.select(one, t0));
    // One segment a point: the nearest point of the other to it.
    s = e_point.select(clamp(-c / a_div), s);
    t = e_point.select(zero, t);
    s = a_point.select(zero, s);
    t = a_point.select(clamp(f / e_div), t);
    // Both points: their distance (s = t = 0 gives it).
    s = (a_point & e_point).select(zero, s);
    t = (a_point & e_point).select(zero, t);
    let gap = |k: usize| (p1[k] + d1[k] * s) - (p2[k] + d2[k] * t);
    let (x, y, z) = (gap(0), gap(1), gap(2));
    (x * x + y * y + z * z).sqrt().to_array()
}

/// [`point_triangle`] for eight points and triangles at once: `pt[k]` is
/// `p a b c` of pair `k`. Every region's distance is computed with the
/// one-at-a-time arithmetic, and each lane takes the first region whose
/// test it passes, in the same order: bit for bit the one-at-a-time
/// distance.
#[inline(always)]
pub(super) fn point_triangle_distances(pt: &[[Vec3; 4]; 8]) -> [f32; 8] {
    type V = [Lanes; 3];
    let sub = |a: V, b: V| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: V, b: V| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let along = |a: V, d: V, s: Lanes| [a[0] + d[0] * s, a[1] + d[1] * s, a[2] + d[2] * s];
    let length = |a: V| dot(a, a).sqrt();
    let (zero, one) = (Lanes::ZERO, Lanes::ONE);
    let [p, a, b, c] = in_lanes(pt);
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    let vc = d1 * d4 - d3 * d2;
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    let denom = va + vb + vc;
    // The regions, in the order the one-at-a-time test meets them. A lane
    // takes only its own region's value: what the others divide by zero
    // is dropped.
    let regions = [
        (d1.simd_le(zero) & d2.simd_le(zero), length(ap)),
        (d3.simd_ge(zero) & d4.simd_le(d3), length(bp)),
        (
            vc.simd_le(zero) & d1.simd_ge(zero) & d3.simd_le(zero),
            length(sub(p, along(a, ab, d1 / (d1 - d3)))),
        ),
        (d6.simd_ge(zero) & d5.simd_le(d6), length(cp)),
        (
            vb.simd_le(zero) & d2.simd_ge(zero) & d6.simd_le(zero),
            length(sub(p, along(a, ac, d2 / (d2 - d6)))),
        ),
        (
            va.simd_le(zero) & (d4 - d3).simd_ge(zero) & (d5 - d6).simd_ge(zero),
            length(sub(
                p,
                along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))),
            )),
        ),
        (
            denom.abs().simd_le(Lanes::splat(f32::MIN_POSITIVE)),
            segment_point_lanes(a, b, p)
                .min(segment_point_lanes(b, c, p))
                .min(segment_point_lanes(a, c, p)),
        ),
    ];
    let inv = one / denom;
    let (vv, ww) = (vb * inv, vc * inv);
    let inside = along(along(a, ab, vv), ac, ww);
    let mut d = length(sub(p, inside));
    for (region, distance) in regions.into_iter().rev() {
        d = region.select(distance, d);
    }
    d.to_array()
}

/// Eight sets of four points as four points of eight lanes: point `i` of
/// set `k` is lane `k` of the `i`-th.
#[inline(always)]
fn in_lanes(sets: &[[Vec3; 4]; 8]) -> [[Lanes; 3]; 4] {
    let mut v = [[[0.0f32; 8]; 3]; 4];
    for (k, set) in sets.iter().enumerate() {
        for (i, point) in set.iter().enumerate() {
            v[i][0][k] = point.x;
            v[i][1][k] = point.y;
            v[i][2][k] = point.z;
        }
    }
    // Spelled out: a nested `map` is left as a call, not inlined.
    let point = |i: usize| {
        [
            Lanes::new(v[i][0]),
            Lanes::new(v[i][1]),
            Lanes::new(v[i][2]),
        ]
    };
    [point(0), point(1), point(2), point(3)]
}

/// [`segment_point`] in lanes.
#[inline(always)]
fn segment_point_lanes(a: [Lanes; 3], b: [Lanes; 3], p: [Lanes; 3]) -> Lanes {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let along = ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2];
    let positive = l2.simd_gt(Lanes::ZERO);
    let s = positive.select(
        (along / positive.select(l2, Lanes::ONE))
            .max(Lanes::ZERO)
            .min(Lanes::ONE),
        Lanes::ZERO,
    );
    let g = [0, 1, 2].map(|k| p[k] - (a[k] + ab[k] * s));
    (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt()
}

/// Calls `f(i, j, d)` with the distance `d` between edges `segments[i]`
/// and `segments[j]` for every pair of `pairs`, in order, measured eight at
/// a time (the last eight padded with its last pair, not reported).
pub(super) fn for_each_edge_distance(
    x: &[Vec3],
    segments: &[[u32; 2]],
    pairs: &[(u32, u32)],
    mut f: impl FnMut(u32, u32, f32),
) {
    let mut lanes = [[Vec3::ZERO; 4]; 8];
    for eight in pairs.chunks(8) {
        for (k, lane) in lanes.iter_mut().enumerate() {
            let (i, j) = eight[k.min(eight.len() - 1)];
            let (e, g) = (segments[i as usize], segments[j as usize]);
            *lane = [e[0], e[1], g[0], g[1]].map(|q| x[q as usize]);
        }
        let d = segment_distances(&lanes);
        for (&(i, j), &d) in eight.iter().zip(&d) {
            f(i, j, d);
        }
    }
}

/// Calls `f(p, t, d)` with the distance `d` of particle `p` from triangle
/// `t` for every pair of `pairs`, in order, measured eight at a time (the
/// last eight padded as for edges).
pub(super) fn for_each_face_distance(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    pairs: &[(u32, u32)],
    mut f: impl FnMut(u32, u32, f32),
) {
    let mut lanes = [[Vec3::ZERO; 4]; 8];
    for eight in pairs.chunks(8) {
        for (k, lane) in lanes.iter_mut().enumerate() {
            let (p, t) = eight[k.min(eight.len() - 1)];
            let [a, b, c] = triangles[t as usize];
            *lane = [p, a, b, c].map(|q| x[q as usize]);
        }
        let d = point_triangle_distances(&lanes);
        for (&(p, t), &d) in eight.iter().zip(&d) {
            f(p, t, d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_agree_with_sampling() {
        let mut seed = 12345u32;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        for _ in 0..200 {
            let v: Vec<Vec3> = (0..5).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
            let d = segment_segment(v[0], v[1], v[2], v[3]);
            let dt = point_triangle(v[4], [v[0], v[1], v[2]]);
            let (mut ss, mut st) = (f32::INFINITY, f32::INFINITY);
            let n = 60;
            for i in 0..=n {
                for j in 0..=n {
                    let (s, t) = (i as f32 / n as f32, j as f32 / n as f32);
                    ss = ss.min((v[0] + (v[1] - v[0]) * s).distance(v[2] + (v[3] - v[2]) * t));
                    if s + t <= 1.0 {
                        let y = v[0] + (v[1] - v[0]) * s + (v[2] - v[0]) * t;
                        st = st.min(y.distance(v[4]));
                    }
                }
            }
            assert!(d <= ss + 1e-5 && d >= ss - 0.05, "{d} {ss}");
            assert!(dt <= st + 1e-5 && dt >= st - 0.05, "{dt} {st}");
        }
    }

    /// Checks `lanes` against `one`, lane by lane, bit for bit, over rounds
    /// of eight sets of four points on a coarse lattice (so that parallel,
    /// touching, crossing and on-plane cases come up often); every fifth
    /// round, point `k` repeats point `copy(k)` where that is given (a
    /// degenerate segment or triangle).
    fn lanes_match_one_at_a_time(
        seed: u32,
        copy: impl Fn(usize) -> Option<usize>,
        lanes: impl Fn(&[[Vec3; 4]; 8]) -> [f32; 8],
        one: impl Fn([Vec3; 4]) -> f32,
    ) {
        let mut seed = seed;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed % 9) as f32 * 0.25 - 1.0
        };
        for round in 0..600 {
            let mut v = [[Vec3::ZERO; 4]; 8];
            for lane in &mut v {
                for k in 0..4 {
                    lane[k] = match copy(k) {
                        Some(j) if round % 5 == 0 => lane[j],
                        _ => Vec3::new(rnd(), rnd(), rnd()),
                    };
                }
            }
            let d = lanes(&v);
            for (lane, &points) in v.iter().enumerate() {
                let one = one(points);
                assert_eq!(
                    d[lane].to_bits(),
                    one.to_bits(),
                    "round {round} lane {lane}"
                );
            }
        }
    }

    #[test]
    fn eight_points_and_triangles_at_a_time_are_one_at_a_time_bit_for_bit() {
        lanes_match_one_at_a_time(
            4242,
            |k| (k == 3).then_some(2),
            point_triangle_distances,
            |[p, a, b, c]| point_triangle(p, [a, b, c]),
        );
    }

    #[test]
    fn eight_at_a_time_is_one_at_a_time_bit_for_bit() {
        lanes_match_one_at_a_time(
            777,
            |k| (k % 2 == 1).then(|| k - 1),
            segment_distances,
            |[p1, q1, p2, q2]| closest_on_segments(p1, q1, p2, q2).0,
        );
    }
}
