//! Parameter changes in words, for the events a run logs and for `weft
//! compare`.

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

/// A value as a person writes it: floats in their shortest `f32` form.
fn short(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => (*f as f32).to_string(),
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
}
