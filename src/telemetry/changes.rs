//! Parameter changes in words, for the events a run logs and for `weft
//! compare`: each key that changed, with its old and new value; a pull
//! that starts or ends reads `pull → {…}` or `pull → none`.

use crate::scene::Tuning;

/// "solver.weights.normality 0.2 → 0.3, solver.iterations 10 → 12".
pub fn describe_changes(old: &Tuning, new: &Tuning) -> String {
    let a: toml::Table = toml::Table::try_from(old).expect("tuning serializes");
    let b: toml::Table = toml::Table::try_from(new).expect("tuning serializes");
    let mut changes = Vec::new();
    diff("", &a, &b, &mut changes);
    if changes.is_empty() {
        "none".into()
    } else {
        changes.join(", ")
    }
}

/// A value as a person writes it: floats (alone or in a list) in their
/// shortest `f32` form.
fn short(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => (*f as f32).to_string(),
        toml::Value::Array(a) => {
            let items: Vec<String> = a.iter().map(short).collect();
            format!("[{}]", items.join(", "))
        }
        other => other.to_string(),
    }
}

fn diff(prefix: &str, a: &toml::Table, b: &toml::Table, out: &mut Vec<String>) {
    for (k, vb) in b {
        let key = format!("{prefix}{k}");
        match (a.get(k), vb) {
            (Some(toml::Value::Table(ta)), toml::Value::Table(tb)) => {
                diff(&format!("{key}."), ta, tb, out)
            }
            (Some(va), vb) if va == vb => {}
            (Some(va), vb) => out.push(format!("{key} {} → {}", short(va), short(vb))),
            (None, vb) => out.push(format!("{key} → {}", short(vb))),
        }
    }
    // A key only the old one has (the pull, let go of).
    for k in a.keys().filter(|k| !b.contains_key(*k)) {
        out.push(format!("{prefix}{k} → none"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::Pull;

    #[test]
    fn a_pull_is_described_when_it_starts_moves_and_ends() {
        let preset = crate::scene::load::load("hanging_sheet", &[])
            .unwrap()
            .preset;
        let free = Tuning::of(&preset);
        let held = Tuning {
            pull: Some(Pull {
                particle: 7,
                target: glam::DVec3::new(0.5, 0.0, 1.0),
                stiffness: 20.0,
            }),
            ..free
        };
        let start = describe_changes(&free, &held);
        assert!(start.starts_with("pull → "), "{start}");
        assert!(start.contains("particle = 7"), "{start}");
        let mut moved = held;
        moved.pull.as_mut().unwrap().target.z = 1.5;
        assert_eq!(
            describe_changes(&held, &moved),
            "pull.target [0.5, 0, 1] → [0.5, 0, 1.5]"
        );
        assert_eq!(describe_changes(&moved, &free), "pull → none");
    }
}
