//! Distances between the primitives of a mesh: a point and a triangle, two
//! segments (Ericson, "Real-Time Collision Detection", 5.1.5 and 5.1.9).

use glam::Vec3;

/// The distance from `p` to the triangle `t` (Ericson, "Real-Time Collision
/// Detection", 5.1.5).
#[inline]
pub(super) fn point_triangle(p: Vec3, t: [Vec3; 3]) -> f32 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return p.distance(a + ab * v);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return p.distance(a + ac * w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return p.distance(b + (c - b) * w);
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // Degenerate: the nearest corner is an upper bound; use the edges.
        return segment_point(a, b, p)
            .min(segment_point(b, c, p))
            .min(segment_point(a, c, p));
    }
    let inv = denom.recip();
    let (v, w) = (vb * inv, vc * inv);
    p.distance(a + ab * v + ac * w)
}

/// The distance from `p` to the segment `a b`.
#[inline]
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
}
