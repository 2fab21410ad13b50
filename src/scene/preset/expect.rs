//! The `[expect]` table: bounds a recording must stay within, judged by
//! `record::verdict` (CI's pass or fail).

use serde::{Deserialize, Serialize};

/// Per-family bounds (none unless given).
pub type FamilyBounds = crate::solver::PerFamily<Option<f32>>;

/// What a recording must satisfy; `weft record` exits non-zero otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Expect {
    /// Largest edge strain allowed at any frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_strain: Option<f32>,
    /// Largest violation allowed at any frame, per family.
    pub max_violation: FamilyBounds,
    /// Kinetic energy (J) the cloth must be below at the end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settle_energy: Option<f32>,
    /// The state must stay finite.
    pub finite: bool,
}

impl Default for Expect {
    fn default() -> Self {
        Self {
            max_strain: None,
            max_violation: FamilyBounds::default(),
            settle_energy: None,
            finite: true,
        }
    }
}
