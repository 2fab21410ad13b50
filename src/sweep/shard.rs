//! Shards: which points of a grid one process runs, for batch engines.
//!
//! Shard `I/N` runs the points whose index `k` has `k mod N = I`. The shards
//! `0/N … (N−1)/N` together run every point exactly once, and each point's
//! files do not depend on which shard ran it.
//!
//! Without `--shard`, the shard comes from the environment:
//! - a Slurm array task: `I = (SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN) /
//!   SLURM_ARRAY_TASK_STEP`, `N = SLURM_ARRAY_TASK_COUNT`;
//! - a Kubernetes Indexed Job: `I = JOB_COMPLETION_INDEX`, with `N` given by
//!   `--shards N` (the Job's `completions`).

use std::str::FromStr;

/// One shard of a sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `0 ≤ index < count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// A checked shard.
    pub fn new(index: usize, count: usize, origin: &str) -> Result<Self, String> {
        if count == 0 {
            return Err(format!("{origin}: the number of shards must be at least 1"));
        }
        if index >= count {
            return Err(format!(
                "{origin}: shard {index} of {count} does not exist (shards are numbered 0 to {})",
                count - 1
            ));
        }
        Ok(Self { index, count })
    }

    /// Whether this shard runs the point at `index`.
    pub fn contains(&self, index: usize) -> bool {
        index % self.count == self.index
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let origin = format!("--shard {s}");
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("{origin}: expected I/N, e.g. 0/4 (the first of 4 shards)"))?;
        let num = |x: &str| {
            x.trim().parse::<usize>().map_err(|_| {
                format!("{origin}: `{x}` is not a whole number; expected I/N, e.g. 0/4")
            })
        };
        Shard::new(num(i)?, num(n)?, &origin)
    }
}

/// The shard given on the command line, else the one the environment
/// (`vars`) describes, else none (the whole grid).
pub fn resolve(
    flag: Option<Shard>,
    shards: Option<usize>,
    vars: impl Fn(&str) -> Option<String>,
) -> Result<Option<Shard>, String> {
    if let Some(s) = flag {
        return Ok(Some(s));
    }
    let num = |name: &str| -> Result<Option<usize>, String> {
        match vars(name) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse::<usize>()
                .map(Some)
                .map_err(|_| format!("{name}={v}: not a whole number")),
        }
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let count = match (shards, num("SLURM_ARRAY_TASK_COUNT")?) {
            (Some(n), _) | (None, Some(n)) => n,
            (None, None) => {
                return Err(
                    "SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT: give the number of shards with --shards N".into(),
                );
            }
        };
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        if id < min || !(id - min).is_multiple_of(step) {
            return Err(format!(
                "SLURM_ARRAY_TASK_ID={id} is not in the array {min}-…:{step}"
            ));
        }
        let origin = format!(
            "Slurm array task {id} (SLURM_ARRAY_TASK_MIN={min}, SLURM_ARRAY_TASK_STEP={step}, {count} tasks)"
        );
        return Shard::new((id - min) / step, count, &origin).map(Some);
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = shards.ok_or(
            "JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job): give the number of shards, the Job's completions, with --shards N",
        )?;
        return Shard::new(
            index,
            count,
            &format!("JOB_COMPLETION_INDEX={index} with --shards {count}"),
        )
        .map(Some);
    }
    if let Some(n) = shards {
        return Err(format!(
            "--shards {n}: no shard index in the environment (SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX); use --shard I/{n} to pick one"
        ));
    }
    Ok(None)
}
