//! The near list's search: every particle–triangle and edge–edge pair
//! nearer than the reach, each particle allowed its drift (the module
//! above has the argument). Boxes before distances: the particles' and the
//! edges' boxes, sorted along the axis the cloth spreads farthest along
//! (`prune.rs`), give the candidates, whose distances are measured eight at
//! a time (`distance.rs`), in blocks of triangles (then of sorted edges)
//! that the threads share and join in block order.

use glam::Vec3;

use super::*;

impl NearPairs {
    /// [`NearPairs::search`], each particle allowed to drift [`AHEAD`]
    /// times as far as it moved beyond the mean in the last substep
    /// measured ([`NearPairs::passes`]), up to [`AHEAD_MOST`] reaches: a
    /// particle that moves fast keeps its pairs for as long as the slow
    /// ones.
    pub(in crate::solver::self_collision::path) fn search_ahead(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
    ) -> bool {
        let (dx, dy) = spec.spacing();
        let most = AHEAD_MOST * REACH * dx.min(dy);
        let moved = std::mem::take(&mut self.step.particle);
        let found = self.search_scaled(x, triangles, spec, &moved, AHEAD, most);
        self.step.particle = moved;
        found
    }

    /// [`NearPairs::search`] at the substep's start `from`, after the last
    /// [`NearPairs::holds`] found a particle drifted beyond the list in
    /// this substep alone (the list was searched at `from`): each particle
    /// allowed [`ALLOWANCE`] times that drift.
    pub(in crate::solver::self_collision::path) fn search_for_substep(
        &mut self,
        from: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
    ) -> bool {
        let drift = std::mem::take(&mut self.drift.particle);
        let found = self.search_scaled(from, triangles, spec, &drift, ALLOWANCE, f32::INFINITY);
        self.drift.particle = drift;
        found
    }

    /// [`NearPairs::search_allowing`] each particle `factor` times its
    /// `moved`, up to `most` (none if `moved` is not one per particle).
    fn search_scaled(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
        moved: &[f32],
        factor: f32,
        most: f32,
    ) -> bool {
        self.allow.clear();
        if moved.len() == x.len() {
            self.allow
                .extend(moved.iter().map(|d| (factor * d).min(most)));
        }
        self.search_allowing(x, triangles, spec)
    }

    /// Finds every pair nearer than the reach at `x` (a state free of
    /// crossings). Returns false if a position is not finite.
    pub(in crate::solver::self_collision::path) fn search(
        &mut self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        spec: &ClothSpec,
    ) -> bool {
        self.allow.clear();
        self.search_allowing(x, triangles, spec)
    }

    /// [`NearPairs::search`], each particle allowed to drift `self.allow[i]`
    /// farther before the list no longer holds (none past the end of
    /// `allow`, which the caller fills): a pair is listed if it is nearer
    /// than the reach plus the largest allowance among each primitive's
    /// corners.
    fn search_allowing(&mut self, x: &[Vec3], triangles: &[[u32; 3]], spec: &ClothSpec) -> bool {
        self.start_known = false;
        self.allow.resize(x.len(), 0.0);
        self.at.clear();
        self.faces.clear();
        self.edges.clear();
        if !x.iter().all(|v| v.is_finite()) {
            return false;
        }
        let (dx, dy) = spec.spacing();
        let reach = REACH * dx.min(dy);
        let axis = widest_axis(x);
        // Particle against triangle: the particles within `reach` of a
        // triangle's box, then by distance.
        let allow = &self.allow;
        let most = |ids: &[u32]| ids.iter().fold(0.0f32, |m, &k| m.max(allow[k as usize]));
        self.points.build(
            axis,
            x.iter()
                .zip(allow)
                .map(|(&p, &a)| (p - Vec3::splat(a), p + Vec3::splat(a))),
        );
        let threads = if triangles.len() >= PARALLEL_MIN {
            team::available()
        } else {
            1
        };
        // A box test is exact per axis up to rounding: grown a little more,
        // it keeps every pair nearer than `reach`.
        let grow = reach * (1.0 + BOX_SLACK);
        let points = &self.points;
        let blocks = team::run_blocks(threads, triangles.len(), BLOCK, |range| {
            let mut near = Vec::new();
            for t in range {
                let tri = triangles[t];
                let c = tri.map(|k| x[k as usize]);
                let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                let grow = Vec3::splat(grow + most(&tri));
                points.within(lo - grow, hi + grow, |p| {
                    if !tri.contains(&p) {
                        near.push((p, t as u32));
                    }
                });
            }
            let mut found = Vec::new();
            for_each_face_distance(x, triangles, &near, |p, t, d| {
                if d < reach + allow[p as usize] + most(&triangles[t as usize]) {
                    found.push((p, t, d));
                }
            });
            found
        });
        self.faces.extend(blocks.into_iter().flatten());
        // Edge against edge: the edges whose boxes, each grown by half of
        // `reach`, overlap, then by distance. Each pair once, the edge
        // listed first as `e`.
        self.segments.clear();
        for p in 0..x.len() as u32 {
            for q in edges_at(p, spec).filter(|&q| q > p) {
                self.segments.push([p, q]);
            }
        }
        self.boxes.build(
            axis,
            self.segments.iter().map(|e| {
                let (u, v) = (x[e[0] as usize], x[e[1] as usize]);
                let half = Vec3::splat(0.5 * grow + most(e));
                (u.min(v) - half, u.max(v) + half)
            }),
        );
        let (boxes, segments) = (&self.boxes, &self.segments);
        let blocks = team::run_blocks(threads, boxes.len(), BLOCK, |range| {
            // Edges that share a particle are no pair (most of the boxes
            // that overlap): left out before their distances, which are
            // measured eight at a time.
            let mut near = Vec::new();
            boxes.overlapping(range, |i, j| {
                let (e, f) = (segments[i as usize], segments[j as usize]);
                if !f.contains(&e[0]) && !f.contains(&e[1]) {
                    near.push((i.min(j), i.max(j)));
                }
            });
            let mut found = Vec::new();
            for_each_edge_distance(x, segments, &near, |i, j, d| {
                let (e, f) = (segments[i as usize], segments[j as usize]);
                if d < reach + most(&e) + most(&f) {
                    found.push((i, j, d));
                }
            });
            found
        });
        self.edges.extend(blocks.into_iter().flatten());

        self.at.extend_from_slice(x);
        self.reach = reach;
        self.drift.zero(x.len());
        true
    }
}
