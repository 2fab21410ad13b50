//! A drag in the events: the debugger's pull written as its start, its end
//! and its path, in millimetres, rather than one line per move of its
//! target (each move is still logged, whole, in `params`, for replay).

use crate::scene::Tuning;
use crate::solver::Pull;

/// The most points of a path an event lists (evenly chosen, the first and
/// the last always among them).
const PATH_POINTS: usize = 12;

/// What an event says of a change of the tuning.
#[derive(Debug, PartialEq)]
pub(super) enum Said {
    /// The change is not a pull's alone: say it key by key.
    NotADrag,
    /// A pull's target moved: nothing now, the path at the end.
    Nothing,
    /// This.
    Event(String),
}

/// The drag under way: its particle, where it began and its target's path.
#[derive(Debug, Default)]
pub(super) struct Drag {
    path: Vec<[f64; 3]>,
    started: u64,
}

impl Drag {
    /// What the change from `old` to `new`, at `frame`, says. A change of
    /// other keys as well is said key by key, the drag's path kept.
    pub(super) fn said(&mut self, old: &Tuning, new: &Tuning, frame: u64) -> Said {
        let others = Tuning { pull: None, ..*old } != Tuning { pull: None, ..*new };
        let event = match (old.pull, new.pull) {
            (None, Some(p)) => {
                self.path = vec![p.target.to_array()];
                self.started = frame;
                Some(format!(
                    "grabbed particle {}, pulled towards {} with {} N/m",
                    p.particle,
                    mm(p.target.to_array()),
                    p.stiffness
                ))
            }
            (Some(a), Some(b)) if a.particle == b.particle => {
                if a.target != b.target {
                    self.path.push(b.target.to_array());
                }
                None
            }
            (Some(p), None) => {
                let text = self.ended(&p, frame);
                self.path.clear();
                Some(text)
            }
            (Some(_), Some(p)) => {
                self.path = vec![p.target.to_array()];
                self.started = frame;
                return Said::NotADrag;
            }
            (None, None) => None,
        };
        match event {
            _ if others => Said::NotADrag,
            Some(text) => Said::Event(text),
            None => Said::Nothing,
        }
    }

    /// The event at the end of a drag of `p`: from where to where, over
    /// which frames, along which points.
    fn ended(&self, p: &Pull, frame: u64) -> String {
        let moves = self.path.len().saturating_sub(1);
        let (Some(first), Some(last)) = (self.path.first(), self.path.last()) else {
            return format!("let go of particle {}", p.particle);
        };
        let mut text = format!(
            "let go of particle {} (frames {}–{frame}): pulled from {} to {} in {moves} moves",
            p.particle,
            self.started,
            mm(*first),
            mm(*last)
        );
        if self.path.len() > 2 {
            let n = self.path.len();
            let k = PATH_POINTS.min(n);
            let points: Vec<String> = (0..k)
                .map(|i| mm(self.path[i * (n - 1) / (k - 1)]))
                .collect();
            text += &format!(", along {}", points.join(" "));
        }
        text
    }
}

/// A point in metres to the millimetre: `(0.512, -1.030, 0.880) m`.
fn mm(p: [f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3}) m", p[0], p[1], p[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drag_is_its_start_its_end_and_its_path() {
        let preset = crate::scene::load::load("hanging_sheet", &[])
            .unwrap()
            .preset;
        let free = Tuning::of(&preset);
        let at = |z: f64| Tuning {
            pull: Some(Pull {
                particle: 7,
                target: glam::DVec3::new(0.5, 0.123_456_789_012, z),
                stiffness: 20.0,
            }),
            ..free
        };
        let mut drag = Drag::default();
        let Said::Event(start) = drag.said(&free, &at(1.0), 10) else {
            panic!("no event at the grab");
        };
        assert_eq!(
            start,
            "grabbed particle 7, pulled towards (0.500, 0.123, 1.000) m with 20 N/m"
        );
        for k in 1..=30 {
            let z = 1.0 + k as f64 * 0.01;
            assert_eq!(drag.said(&at(z - 0.01), &at(z), 10 + k), Said::Nothing);
        }
        let Said::Event(end) = drag.said(&at(1.3), &free, 50) else {
            panic!("no event at the end");
        };
        assert!(
            end.starts_with(
                "let go of particle 7 (frames 10–50): pulled from (0.500, 0.123, 1.000) m \
                 to (0.500, 0.123, 1.300) m in 30 moves, along (0.500, 0.123, 1.000) m"
            ),
            "{end}"
        );
        assert_eq!(end.matches(") m").count(), 2 + PATH_POINTS, "{end}");
        // A change of anything else is said key by key, a drag's path
        // kept through it.
        let mut tuned = at(1.0);
        tuned.solver.iterations += 1;
        assert_eq!(drag.said(&free, &at(1.0), 60), Said::Event(start.clone()));
        assert_eq!(drag.said(&at(1.0), &tuned, 61), Said::NotADrag);
        let Said::Event(end) = drag.said(
            &tuned,
            &Tuning {
                pull: None,
                ..tuned
            },
            62,
        ) else {
            panic!("no event at the end");
        };
        assert!(end.contains("(frames 60–62)"), "{end}");
    }
}
