//! Results as a page: `report.html` beside a sweep's, a fit's or a
//! comparison's files, one self-contained HTML file with plots (SVG, drawn
//! by `plotters`) that opens from the file system, without a network or a
//! build step.
//!
//! - [`sweep`]: each figure against each varied key and over two keys as a
//!   heatmap, the best point by each figure, every point's verdict;
//! - [`fit`]: the distance by run and by generation, each varied key's
//!   path towards the fit, the distance's terms for the start, the fit and
//!   the reference;
//! - [`compare`]: the figures over time for each run, where the runs part,
//!   what differs in their inputs.
//!
//! Each page names the command that made its results, the weft (and solver
//! revision) that ran them, and links each recording with the command that
//! opens it. [`page`] writes the HTML, [`plot`] the plots. [`from_dir`]
//! tells which of the three a directory holds and makes its page
//! (`weft report DIR`); the commands write theirs as they finish.

pub mod compare;
pub mod fit;
pub mod page;
pub mod plot;
pub mod sweep;

use std::path::{Path, PathBuf};

use crate::solver::Family;

/// The page's file name, in the results' directory.
pub const REPORT: &str = "report.html";

/// A figure a page plots: its name (as `--sort` and `--fail-if` know it),
/// its label, its unit and which way is better.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The name [`crate::compare::figure`] knows.
    pub name: String,
    /// What a reader calls it.
    pub label: String,
    /// Its unit.
    pub unit: &'static str,
    /// Whether more is better (speed); less is better for the rest.
    pub higher_is_better: bool,
}

impl Figure {
    fn new(name: &str, label: &str, unit: &'static str) -> Self {
        Self {
            name: name.into(),
            label: label.into(),
            unit,
            higher_is_better: false,
        }
    }

    /// The label with its unit, for an axis.
    pub fn axis(&self) -> String {
        format!("{} ({})", self.label, self.unit)
    }

    /// `lowest` or `highest`.
    pub fn better(&self) -> &'static str {
        if self.higher_is_better {
            "highest"
        } else {
            "lowest"
        }
    }
}

/// The figures a sweep's page plots, in order: max strain, each family's
/// max violation, the final kinetic energy, the speed.
pub fn figures() -> Vec<Figure> {
    let mut v = vec![Figure::new("max_strain", "max strain", "relative")];
    for f in Family::ALL {
        v.push(Figure::new(
            &format!("max_violation.{}", f.name()),
            &format!("max violation {}", f.name()),
            violation_unit(f),
        ));
    }
    v.push(Figure::new("final_energy", "final kinetic energy", "J"));
    v.push(Figure {
        higher_is_better: true,
        ..Figure::new("steps_per_second", "steps per second", "frames/s")
    });
    v
}

/// The unit of a family's violation (docs/method.md §12).
pub fn violation_unit(f: Family) -> &'static str {
    match f.name() {
        "stretch" => "relative",
        "self" => "m",
        _ => "rad",
    }
}

/// Why a page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    /// The page (or the comparison's manifest) could not be written.
    #[error(transparent)]
    Write(#[from] crate::sweep::storage::FileError),
    /// The directory holds none of the results a page is made of.
    #[error(
        "{}: no finished sweep, fit or comparison here (no sweep.json, fit.json or compare.json); \
         `weft sweep PRESET --set … --out DIR`, `weft fit PRESET --vary … --out DIR` or \
         `weft compare A.rrd B.rrd --out DIR` make one",
        .0.display()
    )]
    Nothing(PathBuf),
    /// The results could not be read.
    #[error("{}: {why}", dir.display())]
    Read {
        /// The directory.
        dir: PathBuf,
        /// What went wrong, with the command that would make it right.
        why: String,
    },
}

/// Writes `html` to `dir/report.html` (through a temporary file, so a
/// reader never sees half a page); returns its path.
pub fn write(dir: &Path, html: &str) -> Result<PathBuf, ReportError> {
    let path = dir.join(REPORT);
    crate::sweep::storage::write_shared(&path, html.as_bytes())?;
    Ok(path)
}

/// What a directory of results holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A sweep (`sweep.json`, or finished points).
    Sweep,
    /// A fit (`fit.json`).
    Fit,
    /// A comparison (`compare.json`).
    Comparison,
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Sweep => "sweep",
            Self::Fit => "fit",
            Self::Comparison => "comparison",
        })
    }
}

/// Which results `dir` holds, if any.
pub fn kind(dir: &Path) -> Option<Kind> {
    if dir.join(crate::fit::MANIFEST).is_file() {
        Some(Kind::Fit)
    } else if dir.join(compare::MANIFEST).is_file() {
        Some(Kind::Comparison)
    } else if dir.join(crate::sweep::MANIFEST).is_file() {
        Some(Kind::Sweep)
    } else {
        None
    }
}

/// Makes the page of the results in `dir` and writes it there.
pub fn from_dir(dir: &Path) -> Result<(Kind, PathBuf), ReportError> {
    let read = |why: String| ReportError::Read {
        dir: dir.into(),
        why,
    };
    let kind = kind(dir).ok_or_else(|| ReportError::Nothing(dir.into()))?;
    let html = match kind {
        Kind::Sweep => {
            let c = crate::sweep::collect::read(dir).map_err(|e| read(e.to_string()))?;
            sweep::page(&c, dir)?
        }
        Kind::Fit => fit::page_of_dir(dir)?,
        Kind::Comparison => compare::page_of_dir(dir)?,
    };
    Ok((kind, write(dir, &html)?))
}

/// A table cell linking a recording beside the page (`href` relative to
/// the page's directory `dir`), or saying it is missing.
pub fn rrd_cell(dir: &Path, file: &str) -> page::Cell {
    if dir.join(file).is_file() {
        page::Cell::link(file, file)
    } else {
        page::Cell::text("(none)")
    }
}

/// `s` quoted for a POSIX shell if it needs it.
pub fn shell(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "._-/=,:+@".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        s.into()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// A link to a file anywhere (absolute, so that it opens from the page
/// wherever the page is), with the command that opens it.
pub fn file_link(path: &Path, command: &str) -> String {
    let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    format!(
        "<a href=\"{}\">{}</a> ({})",
        page::esc(&abs.display().to_string()),
        page::esc(&path.display().to_string()),
        page::code(&format!("{command} {}", shell(&path.display().to_string())))
    )
}
