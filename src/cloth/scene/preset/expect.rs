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
    /// Most edges allowed to cross a triangle of the cloth at any logged
    /// frame (0: the cloth never passes through itself). A whole number;
    /// read as a number so that a wrong one is refused with its range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_crossings: Option<f64>,
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
            max_crossings: None,
            settle_energy: None,
            finite: true,
        }
    }
}
