//! Untangling: moves tangled particles so that the curves along which the
//! cloth passes through itself shrink (after Volino & Magnenat-Thalmann,
//! "Resolving surface collisions through intersection contour
//! minimization", 2006).
//!
//! Where the cloth passes through itself, its triangles meet along closed
//! curves (or curves that end at its border): the **intersection
//! contours**. Each point `q` of a contour is an edge `e` of one layer
//! crossing a triangle (unit normal `n`) of the other; two triangles that
//! meet do so along a segment between two such points, so the contour's
//! length is `L = Σ |q_i − q_j|` over those segments, and `L = 0` once the
//! layers are apart. Moving the edge's layer by `δ` against the triangle's
//! slides `q` along the edge to stay in the triangle's plane:
//!
//! ```text
//! Δq = J δ,   J = I − e nᵀ / (e · n)
//! ```
//!
//! so `∂L/∂δ = Jᵀ g`, with `g = Σ_j (q_i − q_j) / |q_i − q_j|` the contour's
//! pull at `q_i`. Each crossing moves its edge's ends by `−Jᵀg` and its
//! triangle's corners by `+Jᵀg`, shared by inverse mass and each end's and
//! corner's weight in `q`, at most [`STEP`] rest spacings a substep: a
//! contour around a layer poked through another shrinks to nothing, one
//! that ends at the border slides off it. No history is needed: the
//! crossings alone decide which way.

use std::collections::HashMap;

use glam::Vec3;

/// How far, in rest spacings, one crossing moves its particles in a substep.
pub(crate) const STEP: f32 = 0.05;

/// An edge that crosses a triangle it shares no particle with, and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    pub edge: [u32; 2],
    pub triangle: [u32; 3],
    pub at: Vec3,
}

/// Moves the particles at `x` of every crossing in `crossings` by up to
/// `step` (metres) so that the intersection contours shrink. `triangles`
/// are the mesh's: the two beside each crossing edge carry the contour on.
/// The crossings are taken in their order and each particle's moves summed
/// in it, so the result does not depend on how they were found.
pub(crate) fn untangle(
    x: &mut [Vec3],
    inv_mass: &[f32],
    triangles: &[[u32; 3]],
    crossings: &[Crossing],
    step: f32,
) {
    if crossings.is_empty() {
        return;
    }
    let mut pull = vec![Vec3::ZERO; crossings.len()];
    for [i, j] in segments(triangles, crossings) {
        let d = crossings[i].at - crossings[j].at;
        let len = d.length();
        if len > 0.0 && len.is_finite() {
            pull[i] += d / len;
            pull[j] -= d / len;
        }
    }
    for (c, g) in crossings.iter().zip(pull) {
        let [p, o] = c.edge.map(|k| k as usize);
        let [a, b, cc] = c.triangle.map(|k| k as usize);
        let e = x[o] - x[p];
        let n = (x[b] - x[a]).cross(x[cc] - x[a]).normalize_or_zero();
        let en = e.dot(n);
        if n == Vec3::ZERO || en.abs() <= f32::EPSILON * e.length() {
            continue;
        }
        // −Jᵀ g: the edge's layer moves this way, the triangle's the other.
        let dir = -(g - n * (e.dot(g) / en));
        let len = dir.length();
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        let dir = dir / len;
        // Weights in the crossing point: along the edge, and barycentric
        // in the triangle.
        let s = ((c.at - x[p]).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        let bary = barycentric(c.at, [x[a], x[b], x[cc]]);
        let ids = [p, o, a, b, cc];
        let weights = [1.0 - s, s, bary[0], bary[1], bary[2]];
        let sides = [1.0, 1.0, -1.0, -1.0, -1.0];
        let total: f32 = (0..5).map(|k| weights[k].powi(2) * inv_mass[ids[k]]).sum();
        if total <= 0.0 {
            continue;
        }
        let lambda = step * len.min(1.0) / total;
        for k in 0..5 {
            x[ids[k]] += dir * (sides[k] * lambda * weights[k] * inv_mass[ids[k]]);
        }
    }
}

/// The contour's segments: pairs of crossings that lie on one pair of
/// triangles meeting (a triangle beside one's edge and the one it
/// crosses), in order.
fn segments(triangles: &[[u32; 3]], crossings: &[Crossing]) -> Vec<[usize; 2]> {
    // The triangles beside each crossing edge.
    let mut beside: HashMap<[u32; 2], Vec<[u32; 3]>> = HashMap::new();
    for c in crossings {
        beside.entry(sorted2(c.edge)).or_default();
    }
    for &t in triangles {
        for k in 0..3 {
            let e = sorted2([t[k], t[(k + 1) % 3]]);
            if let Some(list) = beside.get_mut(&e) {
                list.push(sorted3(t));
            }
        }
    }
    let mut on_pair: HashMap<([u32; 3], [u32; 3]), Vec<usize>> = HashMap::new();
    for (i, c) in crossings.iter().enumerate() {
        let crossed = sorted3(c.triangle);
        for &t in &beside[&sorted2(c.edge)] {
            let key = if t < crossed {
                (t, crossed)
            } else {
                (crossed, t)
            };
            on_pair.entry(key).or_default().push(i);
        }
    }
    let mut segments: Vec<[usize; 2]> = on_pair
        .values()
        .filter(|ends| ends.len() == 2)
        .map(|ends| [ends[0], ends[1]])
        .collect();
    segments.sort_unstable();
    segments
}

/// The barycentric coordinates of `q` in triangle `t` (projected on its
/// plane), clamped to the triangle.
fn barycentric(q: Vec3, t: [Vec3; 3]) -> [f32; 3] {
    let (v0, v1, v2) = (t[1] - t[0], t[2] - t[0], q - t[0]);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= f32::MIN_POSITIVE {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

fn sorted2([a, b]: [u32; 2]) -> [u32; 2] {
    if a <= b { [a, b] } else { [b, a] }
}

fn sorted3(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::cloth::ClothSpec;
    use crate::solver::self_collision::tangles::scan_crossings;
    use crate::solver::topology::Topology;

    fn crossings(x: &[Vec3], triangles: &[[u32; 3]], spec: &ClothSpec) -> Vec<Crossing> {
        let mut found = Vec::new();
        scan_crossings(x, triangles, spec, None, |edge, triangle, at| {
            found.push(Crossing { edge, triangle, at });
        });
        found
    }

    fn length(triangles: &[[u32; 3]], c: &[Crossing]) -> f32 {
        segments(triangles, c)
            .iter()
            .map(|&[i, j]| c[i].at.distance(c[j].at))
            .sum()
    }

    #[test]
    fn a_layer_poked_through_another_is_drawn_back_as_its_contour_shrinks() {
        // A 12 × 12 sheet folded in half: columns 6–11 lie over columns 0–5,
        // two spacings above, but for a 2 × 2 patch pushed one spacing
        // below the lower layer. The contour's pull alone (no other
        // constraint) undoes it, the contour never longer than at the start
        // (a step is discrete: as the contour closes to a cell, a move can
        // cross another edge for a round).
        let spec = ClothSpec {
            weft: 12,
            warp: 12,
            width: 1.1,
            height: 1.1,
            ..ClothSpec::default()
        };
        let triangles = Topology::grid(&spec).triangles;
        let d = 0.1;
        let mut x: Vec<Vec3> = (0..144u32)
            .map(|k| {
                let (i, j) = ((k % 12) as f32, (k / 12) as f32);
                if i < 6.0 {
                    Vec3::new(i * d, j * d, 0.0)
                } else {
                    let poked = (8.0..=9.0).contains(&i) && (5.0..=6.0).contains(&j);
                    // Off the lower grid by a fraction: no crossing on a border.
                    let z = if poked { -d } else { 2.0 * d };
                    Vec3::new((10.7 - i) * d, (j + 0.4) * d, z)
                }
            })
            .collect();
        let inv_mass = vec![1.0; x.len()];
        let mut c = crossings(&x, &triangles, &spec);
        assert!(!c.is_empty(), "the patch does not cross the lower layer");
        let start = length(&triangles, &c);
        for round in 0..100 {
            untangle(&mut x, &inv_mass, &triangles, &c, STEP * d);
            c = crossings(&x, &triangles, &spec);
            let now = length(&triangles, &c);
            assert!(
                now < start,
                "round {round}: the contour {now}, from {start}"
            );
            if c.is_empty() {
                // Not by sliding off the lower layer's border: the patch
                // is still within it, on the side of the rest of its layer.
                for k in [68, 69, 80, 81] {
                    let p = x[k];
                    assert!(
                        (0.0..0.5).contains(&p.x) && (0.0..1.1).contains(&p.y),
                        "{k} at {p}"
                    );
                }
                return;
            }
        }
        panic!("{} crossings left after 100 rounds", c.len());
    }
}
