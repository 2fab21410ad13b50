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

/// A shard that does not exist, or that the environment names wrongly.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// No shards at all.
    #[error("{origin}: the number of shards must be at least 1")]
    NoShards {
        /// Where the shard came from (`--shard 0/0`, a Slurm task…).
        origin: String,
    },
    /// An index past the last shard.
    #[error("{origin}: shard {index} of {count} does not exist (shards are numbered 0 to {})", count - 1)]
    NoSuchShard {
        /// Where the shard came from.
        origin: String,
        /// The index.
        index: usize,
        /// How many shards there are.
        count: usize,
    },
    /// `--shard` not written `I/N`.
    #[error("{origin}: expected I/N, e.g. 0/4 (the first of 4 shards)")]
    Format {
        /// The flag as written.
        origin: String,
    },
    /// `I` or `N` not a whole number.
    #[error("{origin}: `{text}` is not a whole number; expected I/N, e.g. 0/4")]
    NotWhole {
        /// The flag as written.
        origin: String,
        /// The part that is not a number.
        text: String,
    },
    /// An environment variable that should be a whole number.
    #[error("{name}={value}: not a whole number")]
    Variable {
        /// The variable.
        name: String,
        /// Its value.
        value: String,
    },
    /// A Slurm task id without the task count.
    #[error(
        "SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT: give the number of shards with --shards N"
    )]
    SlurmCount,
    /// A Slurm task id outside its array.
    #[error("SLURM_ARRAY_TASK_ID={id} is not in the array {min}-…:{step}")]
    NotInArray {
        /// The task id.
        id: usize,
        /// The array's first id.
        min: usize,
        /// Its step.
        step: usize,
    },
    /// A Kubernetes completion index without the number of shards.
    #[error(
        "JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job): give the number of shards, the Job's completions, with --shards N"
    )]
    JobCount,
    /// `--shards N` without a shard index anywhere.
    #[error(
        "--shards {0}: no shard index in the environment (SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX); use --shard I/{0} to pick one"
    )]
    NoIndex(usize),
}

impl Shard {
    /// A checked shard.
    pub fn new(index: usize, count: usize, origin: &str) -> Result<Self, ShardError> {
        let origin = origin.to_string();
        if count == 0 {
            return Err(ShardError::NoShards { origin });
        }
        if index >= count {
            return Err(ShardError::NoSuchShard {
                origin,
                index,
                count,
            });
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
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, ShardError> {
        let origin = format!("--shard {s}");
        let (i, n) = s.split_once('/').ok_or_else(|| ShardError::Format {
            origin: origin.clone(),
        })?;
        let num = |x: &str| {
            x.trim().parse::<usize>().map_err(|_| ShardError::NotWhole {
                origin: origin.clone(),
                text: x.to_string(),
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
) -> Result<Option<Shard>, ShardError> {
    if let Some(s) = flag {
        return Ok(Some(s));
    }
    let num = |name: &str| -> Result<Option<usize>, ShardError> {
        match vars(name) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse::<usize>()
                .map(Some)
                .map_err(|_| ShardError::Variable {
                    name: name.to_string(),
                    value: v,
                }),
        }
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let count = match (shards, num("SLURM_ARRAY_TASK_COUNT")?) {
            (Some(n), _) | (None, Some(n)) => n,
            (None, None) => return Err(ShardError::SlurmCount),
        };
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        if id < min || !(id - min).is_multiple_of(step) {
            return Err(ShardError::NotInArray { id, min, step });
        }
        let origin = format!(
            "Slurm array task {id} (SLURM_ARRAY_TASK_MIN={min}, SLURM_ARRAY_TASK_STEP={step}, {count} tasks)"
        );
        return Shard::new((id - min) / step, count, &origin).map(Some);
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = shards.ok_or(ShardError::JobCount)?;
        return Shard::new(
            index,
            count,
            &format!("JOB_COMPLETION_INDEX={index} with --shards {count}"),
        )
        .map(Some);
    }
    if let Some(n) = shards {
        return Err(ShardError::NoIndex(n));
    }
    Ok(None)
}
