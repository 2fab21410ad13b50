//! Self-collision's guarantee (docs/method.md §11b): from a state free of
//! crossings, a substep forms none, whatever the particles' moves; counted
//! at the substep's end by an independent brute-force check in `f64`. And
//! what happens at an exception: a driven particle goes where its body
//! takes it, and leaves no tangle once it is back. (A jerk, another
//! exception, is `stress_jerk`'s test in `self_collision.rs`.)

// Tests set their scenes up with the standard library's maths: they run on
// one machine, so the platform's math library is fine here.
#![allow(clippy::disallowed_methods)]

mod common;

use glam::Vec3;
use proptest::prelude::*;
use weft::solver::{ClothSpec, Params, Pose, Solver};

use common::calm;
use common::crossings::{brute_force_crossings, mesh};

/// The grid's rest spacing, metres.
const SPACING: f32 = 0.05;

/// A state to start a substep from, free of crossings.
#[derive(Clone, Copy, Debug)]
enum Layout {
    /// The grid flat, each particle off its place by up to a fifth of a
    /// spacing (non-adjacent primitives stay more than a third of a spacing
    /// apart, so nothing crosses).
    Flat,
    /// Folded in half: the upper half `gap` over the lower, mirrored, each
    /// particle off its place by up to a fifth of a spacing in the plane and
    /// a third of the gap across it.
    Folded { gap: f32 },
    /// Folded, the upper half shifted by half a cell, so that its edges
    /// cross the lower half's in the plane's projection: every edge nearly
    /// crosses another.
    Shifted { gap: f32 },
}

/// Particle `(i, j)` of an `n × n` grid laid out as `layout`, before the
/// wobble.
fn place(layout: Layout, n: u32, i: u32, j: u32) -> Vec3 {
    let (x, y) = (i as f32 * SPACING, j as f32 * SPACING);
    let half = n / 2;
    let over = |gap: f32, shift: f32| {
        // Column `half - 1 + k` lies over column `half - k`.
        let x = (2 * half - 1 - i) as f32 * SPACING + shift;
        Vec3::new(x, y + shift, gap)
    };
    match layout {
        Layout::Flat => Vec3::new(x, y, 0.0),
        Layout::Folded { gap } if i >= half => over(gap, 0.0),
        Layout::Shifted { gap } if i >= half => over(gap, 0.5 * SPACING),
        _ => Vec3::new(x, y, 0.0),
    }
}

/// A layout and its wobble, and a move for each particle: `scale` spacings
/// at most in every direction, and if `through`, the upper half carried
/// down through the lower by `gap` and `depth` spacings more.
#[derive(Clone, Debug)]
struct Case {
    n: u32,
    layout: Layout,
    wobble: Vec<[f32; 3]>,
    moves: Vec<[f32; 3]>,
    scale: f32,
    through: Option<f32>,
}

impl Case {
    fn start(&self) -> Vec<Vec3> {
        let n = self.n;
        let across = match self.layout {
            Layout::Flat => 0.2 * SPACING,
            Layout::Folded { gap } | Layout::Shifted { gap } => gap / 3.0,
        };
        (0..n * n)
            .map(|k| {
                let w = Vec3::from_array(self.wobble[k as usize]);
                let off = Vec3::new(0.2 * SPACING * w.x, 0.2 * SPACING * w.y, across * w.z);
                place(self.layout, n, k % n, k / n) + off
            })
            .collect()
    }

    fn end(&self, start: &[Vec3]) -> Vec<Vec3> {
        let n = self.n;
        let gap = match self.layout {
            Layout::Flat => 0.0,
            Layout::Folded { gap } | Layout::Shifted { gap } => gap,
        };
        start
            .iter()
            .enumerate()
            .map(|(k, &x)| {
                let m = Vec3::from_array(self.moves[k]) * (self.scale * SPACING);
                let down = match self.through {
                    Some(depth) if k as u32 % n >= n / 2 => gap + depth * SPACING,
                    _ => 0.0,
                };
                x + m - Vec3::Z * down
            })
            .collect()
    }
}

fn case() -> impl Strategy<Value = Case> {
    let layout = prop_oneof![
        Just(Layout::Flat),
        (1e-4f32..0.5 * SPACING).prop_map(|gap| Layout::Folded { gap }),
        (1e-4f32..2e-3).prop_map(|gap| Layout::Folded { gap }),
        (1e-4f32..0.2 * SPACING).prop_map(|gap| Layout::Shifted { gap }),
    ];
    (4u32..=8, layout).prop_flat_map(|(n, layout)| {
        let cube = || prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), (n * n) as usize);
        (cube(), cube(), 0.0f32..1.5, prop::option::of(0.0f32..1.0)).prop_map(
            move |(wobble, moves, scale, through)| Case {
                n,
                layout,
                wobble,
                moves,
                scale,
                through,
            },
        )
    })
}

/// A solver for an `n × n` grid with the shipped defaults (self-collision
/// on), one substep a step and no damping, so that the update takes the
/// particles from `start` exactly by their last move, to `end`.
fn solver_at(n: u32, start: &[Vec3], end: &[Vec3]) -> Solver {
    let spec = ClothSpec {
        weft: n,
        warp: n,
        width: (n - 1) as f32 * SPACING,
        height: (n - 1) as f32 * SPACING,
        thickness: 0.004,
        imperfection: 0.0,
        ..ClothSpec::default()
    };
    let params = Params {
        substeps: 1,
        damping: 1.0,
        ..Params::default()
    };
    let mut s = Solver::new(spec, params, &[Pose::IDENTITY]).unwrap();
    let st = s.state_mut();
    st.position.copy_from_slice(start);
    for (prev, (&x, &e)) in st.prev_position.iter_mut().zip(start.iter().zip(end)) {
        *prev = x - (e - x);
    }
    s
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// From a state free of crossings (flat, folded, layers nearly
    /// touching, edges nearly crossing), moved in one substep by up to a
    /// spacing and a half in any direction, and often carried through the
    /// other layer: no edge crosses a triangle at the substep's end.
    #[test]
    fn no_substep_forms_a_crossing(case in case()) {
        let start = case.start();
        let (edges, triangles) = mesh(case.n, case.n);
        prop_assume!(brute_force_crossings(&start, &edges, &triangles) == 0);
        let mut s = solver_at(case.n, &start, &case.end(&start));
        s.step(&calm(), &[Pose::IDENTITY]).unwrap();
        let x = &s.state().position;
        prop_assert!(x.iter().all(|p| p.is_finite()));
        prop_assert_eq!(brute_force_crossings(x, &edges, &triangles), 0);
    }
}

#[test]
fn a_driven_particle_goes_where_its_body_takes_it_and_leaves_no_tangle_behind() {
    // An 8 × 8 sheet folded in half, 1 cm between the layers; a particle of
    // the upper half is driven by a body straight down past the lower half
    // in one step, and back up the next. A body moves it where it must go
    // (the exception): the free particles of the lower layer give way ahead
    // of it, or its edges cross that layer, and then the solver's count says
    // so, as the brute force does. Once it is back, nothing crosses.
    let n = 8;
    let layout = Layout::Folded { gap: 0.01 };
    let start: Vec<Vec3> = (0..n * n).map(|k| place(layout, n, k % n, k / n)).collect();
    let (edges, triangles) = mesh(n, n);
    assert_eq!(brute_force_crossings(&start, &edges, &triangles), 0);
    let mut s = solver_at(n, &start, &start);
    let driven = (3 * n + 5) as usize;
    s.attach(driven, 0);
    let at = |z: f32| [Pose::new(Vec3::Z * z, glam::Quat::IDENTITY)];
    s.step(&calm(), &at(-0.03)).unwrap();
    let x = &s.state().position;
    assert!(
        x[driven].z < -0.01,
        "the body takes it past the lower layer: {}",
        x[driven]
    );
    let crossed = brute_force_crossings(x, &edges, &triangles);
    assert_eq!(
        s.self_crossings(),
        crossed,
        "the solver counts what the brute force does"
    );
    for _ in 0..60 {
        s.step(&calm(), &at(0.0)).unwrap();
    }
    let x = &s.state().position;
    assert!((x[driven].z - 0.01).abs() < 1e-3, "back: {}", x[driven]);
    assert_eq!(brute_force_crossings(x, &edges, &triangles), 0);
}
