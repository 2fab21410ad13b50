//! Counting where a cloth passes through itself, independently of the
//! solver: every edge of the grid's mesh against every triangle, in `f64`.

use glam::{DVec3, Vec3};

/// The triangle mesh of a `weft × warp` grid, built here from the grid
/// alone: each cell split along its (i, j)–(i+1, j+1) diagonal.
pub fn mesh(weft: u32, warp: u32) -> (Vec<[u32; 2]>, Vec<[u32; 3]>) {
    let idx = |i: u32, j: u32| j * weft + i;
    let (mut edges, mut triangles) = (Vec::new(), Vec::new());
    for j in 0..warp {
        for i in 0..weft {
            if i + 1 < weft {
                edges.push([idx(i, j), idx(i + 1, j)]);
            }
            if j + 1 < warp {
                edges.push([idx(i, j), idx(i, j + 1)]);
            }
            if i + 1 < weft && j + 1 < warp {
                edges.push([idx(i, j), idx(i + 1, j + 1)]);
                triangles.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                triangles.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
    }
    (edges, triangles)
}

/// The signed volume of the tetrahedron `(a, b, c, d)`, in `f64`.
fn orient(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).cross(c - a).dot(d - a)
}

/// Whether segment `u v` passes through triangle `t`: its ends on opposite
/// sides of the plane and the point where it meets the plane inside the
/// triangle, each by more than 1 µm (an edge that only touches a triangle,
/// or lies in its plane, does not cross). Signed volumes and distances to
/// the edges' lines, in `f64`: a method unlike the solver's.
fn crosses(u: DVec3, v: DVec3, t: [DVec3; 3]) -> bool {
    const MARGIN: f64 = 1e-6;
    let area2 = (t[1] - t[0]).cross(t[2] - t[0]).length();
    let (su, sv) = (orient(t[0], t[1], t[2], u), orient(t[0], t[1], t[2], v));
    if su * sv >= 0.0 || su.abs().min(sv.abs()) <= MARGIN * area2 {
        return false;
    }
    let p = u + (v - u) * (su / (su - sv));
    let n = (t[1] - t[0]).cross(t[2] - t[0]) / area2;
    (0..3).all(|k| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        (b - a).cross(p - a).dot(n) > MARGIN * (b - a).length()
    })
}

/// Every (edge, triangle) pair sharing no particle that crosses: each edge
/// against each triangle, with a bounding-box test first for speed.
pub fn brute_force_crossings(x: &[Vec3], edges: &[[u32; 2]], triangles: &[[u32; 3]]) -> usize {
    let p: Vec<DVec3> = x.iter().map(|v| v.as_dvec3()).collect();
    let boxes: Vec<(DVec3, DVec3)> = triangles
        .iter()
        .map(|t| {
            let c = t.map(|k| p[k as usize]);
            (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]))
        })
        .collect();
    let mut count = 0;
    for e in edges {
        let (u, v) = (p[e[0] as usize], p[e[1] as usize]);
        let (lo, hi) = (u.min(v), u.max(v));
        for (t, (tlo, thi)) in triangles.iter().zip(&boxes) {
            if hi.cmplt(*tlo).any()
                || lo.cmpgt(*thi).any()
                || t.contains(&e[0])
                || t.contains(&e[1])
            {
                continue;
            }
            if crosses(u, v, t.map(|k| p[k as usize])) {
                count += 1;
            }
        }
    }
    count
}
