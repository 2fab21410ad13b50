//! The search: argmin's particle swarm (the default) or Nelder–Mead, over
//! the unit cube of the varied keys.
//!
//! Both run in argmin's executor; the fit's evaluator is its cost function.
//! Every cost argmin asks for goes through [`Evaluate`], one generation at
//! a time (the swarm asks for all its particles at once, Nelder–Mead for
//! one or two points per step): the evaluator runs the points it has not
//! run, in parallel or as a Slurm array job, and answers from the points'
//! files. When it cannot answer (the budget is spent, Ctrl-C, or other
//! shards still run the generation) it says so, the executor stops, and the
//! search ends; the evaluator knows why.
//!
//! The swarm draws from a xoshiro256++ generator seeded with `--seed`, and
//! argmin's steps are plain arithmetic on the answers, so the same seed and
//! the same answers give the same points, bit for bit; a resumed fit asks
//! for the same points again and is answered from disk.

use std::str::FromStr;

use argmin::core::{CostFunction, Error, Executor, SyncAlias};
use argmin::solver::neldermead::NelderMead;
use argmin::solver::particleswarm::ParticleSwarm;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

/// Which optimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// argmin's particle swarm (SPSO 2011's weights).
    Swarm,
    /// argmin's Nelder–Mead simplex, from the preset's values.
    NelderMead,
}

/// A `--method` that is neither.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("`{0}`: expected swarm or nelder-mead")]
pub struct MethodError(String);

impl FromStr for Method {
    type Err = MethodError;

    fn from_str(s: &str) -> Result<Self, MethodError> {
        match s {
            "swarm" | "pso" => Ok(Self::Swarm),
            "nelder-mead" | "nm" => Ok(Self::NelderMead),
            _ => Err(MethodError(s.into())),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Swarm => "swarm",
            Self::NelderMead => "nelder-mead",
        })
    }
}

/// The particles of a swarm over `dims` keys: 6 for one key, 2 more for
/// each further key, at most 12.
pub fn swarm_size(dims: usize) -> usize {
    (4 + 2 * dims).clamp(6, 12)
}

/// Answers a generation of points (unit coordinates) with their distances,
/// or says it cannot (`None`: the evaluator knows why).
pub trait Evaluate: Sync {
    /// The distances of `points`, in order.
    fn evaluate(&self, points: &[Vec<f64>]) -> Option<Vec<f64>>;
}

struct Objective<'a>(&'a dyn Evaluate);

/// argmin's error for "the evaluator stopped"; never shown.
#[derive(Debug, thiserror::Error)]
#[error("the evaluator stopped the search")]
struct Stopped;

impl CostFunction for Objective<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, Error> {
        let d = self.0.evaluate(std::slice::from_ref(p)).ok_or(Stopped)?;
        Ok(d[0])
    }

    fn bulk_cost<P>(&self, params: &[P]) -> Result<Vec<f64>, Error>
    where
        P: std::borrow::Borrow<Vec<f64>> + SyncAlias,
        f64: argmin::core::SendAlias,
        Self: SyncAlias,
    {
        let points: Vec<Vec<f64>> = params.iter().map(|p| p.borrow().clone()).collect();
        Ok(self.0.evaluate(&points).ok_or(Stopped)?)
    }
}

/// Why argmin itself failed (not the evaluator's stops).
#[derive(Debug, thiserror::Error)]
#[error("the optimiser failed: {0}")]
pub struct SearchError(String);

/// Runs the search from `start` (unit coordinates) until the evaluator
/// stops it or the optimiser converges.
pub fn search(
    method: Method,
    start: &[f64],
    seed: u64,
    budget: usize,
    eval: &dyn Evaluate,
) -> Result<(), SearchError> {
    // Generations answered from the cache cost no run: a bound on argmin's
    // steps keeps a search that only revisits points from going on forever.
    let steps = 4 * budget as u64 + 16;
    let dims = start.len();
    // The start first, so that every fit reports where it began.
    if eval.evaluate(&[start.to_vec()]).is_none() {
        return Ok(());
    }
    let problem = Objective(eval);
    let outcome = match method {
        Method::Swarm => {
            let solver = ParticleSwarm::new((vec![0.0; dims], vec![1.0; dims]), swarm_size(dims))
                .with_rng_generator(Xoshiro256PlusPlus::seed_from_u64(seed));
            Executor::new(problem, solver)
                .configure(|s| s.max_iters(steps))
                .run()
                .map(|_| ())
        }
        Method::NelderMead => {
            let mut simplex = vec![start.to_vec()];
            for k in 0..dims {
                let mut p = start.to_vec();
                p[k] = if p[k] + 0.25 <= 1.0 {
                    p[k] + 0.25
                } else {
                    p[k] - 0.25
                };
                simplex.push(p);
            }
            // argmin's Nelder–Mead evaluates its simplex without letting
            // the cost fail: the evaluator runs it first, and answers it
            // again from its files.
            if eval.evaluate(&simplex).is_none() {
                return Ok(());
            }
            let solver = NelderMead::new(simplex)
                .with_sd_tolerance(1e-6)
                .map_err(|e| SearchError(e.to_string()))?;
            Executor::new(problem, solver)
                .configure(|s| s.max_iters(steps))
                .run()
                .map(|_| ())
        }
    };
    match outcome {
        Ok(()) => Ok(()),
        Err(e) if e.downcast_ref::<Stopped>().is_some() => Ok(()),
        Err(e) => Err(SearchError(e.to_string())),
    }
}
