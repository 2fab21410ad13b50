//! Running a fit: each generation the search asks for is run as a sweep,
//! and every point's distance is read back from its files.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::measure::{Features, Horizon, Probe};
use super::search::{self, Evaluate};
use super::{Distance, Fit, FitError, prepare, reference_features};
use crate::record::Figures;
use crate::scene::Scene;
use crate::sweep::grid::{MAX_NAME, Point, safe, short};
use crate::sweep::shard::Shard;
use crate::sweep::storage::file;
use crate::sweep::{Measure, Measurement, Plan, PointResult, is_complete};

/// One evaluated point.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// Its index in the fit (0: the start).
    pub index: usize,
    /// The generation that ran it.
    pub generation: usize,
    /// Its name (of its files, under `gen-NNN/`).
    pub name: String,
    /// Each varied key's value, as run.
    pub values: Vec<String>,
    /// Its unit coordinates.
    pub x: Vec<f64>,
    /// Its figures.
    pub figures: Figures,
    /// What it measured.
    pub features: Features,
    /// Its distance.
    pub distance: Distance,
}

/// Why the search stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum Halt {
    /// The budget is spent (or the optimiser converged).
    Done,
    /// Ctrl-C: the points run so far are kept.
    Interrupted,
    /// This shard ran its points of a generation; other shards still run theirs.
    Pending {
        /// The generation.
        generation: usize,
        /// Its points not yet complete.
        missing: usize,
    },
}

/// What the fit reports while it runs.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A generation starts: how many points it runs here, how many were already done.
    Generation {
        /// Its number.
        generation: usize,
        /// Points to run here.
        run: usize,
        /// Points already complete.
        done: usize,
    },
    /// A point finished running.
    Ran {
        /// Its name.
        name: String,
        /// Wall time.
        time: Duration,
    },
    /// A point's distance is known (in index order).
    Evaluated {
        /// Its index.
        index: usize,
        /// Its distance.
        distance: f64,
        /// The best distance so far.
        best: f64,
    },
}

/// How a fit ended.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Why it stopped.
    pub halt: Halt,
    /// Every evaluated point, by index.
    pub points: Vec<Evaluated>,
    /// The reference's features.
    pub reference: Option<Features>,
}

impl Outcome {
    /// The best point: the smallest distance, the first of equals.
    pub fn best(&self) -> Option<&Evaluated> {
        self.points
            .iter()
            .min_by(|a, b| a.distance.total.total_cmp(&b.distance.total))
    }

    /// The start (index 0).
    pub fn start(&self) -> Option<&Evaluated> {
        self.points.first()
    }
}

struct State {
    generation: usize,
    next: usize,
    cache: HashMap<Vec<String>, usize>,
    points: Vec<Evaluated>,
    halt: Option<Halt>,
    errors: Vec<String>,
    failure: Option<FitError>,
}

struct Evaluator<'a> {
    fit: &'a Fit,
    dir: &'a Path,
    shard: Option<Shard>,
    jobs: usize,
    stop: &'a AtomicBool,
    dry: bool,
    reference: Option<&'a Features>,
    horizon: Option<Arc<Horizon>>,
    progress: Mutex<&'a mut (dyn FnMut(Progress) + Send)>,
    state: Mutex<State>,
}

impl Evaluator<'_> {
    fn tell(&self, p: Progress) {
        (self.progress.lock().expect("progress lock"))(p)
    }

    /// Runs the new points of a generation and reads every point's result
    /// back; `None` when the search must stop (`state.halt` says why).
    fn generation(&self, points: &[Vec<f64>]) -> Option<Vec<f64>> {
        let mut st = self.state.lock().expect("state lock");
        if st.halt.is_some() {
            return None;
        }
        let texts: Vec<Vec<String>> = points
            .iter()
            .map(|x| {
                self.fit
                    .vary
                    .iter()
                    .zip(x)
                    .map(|(v, &x)| v.at(x).1)
                    .collect()
            })
            .collect();
        let mut new: Vec<usize> = Vec::new();
        for (k, t) in texts.iter().enumerate() {
            if !st.cache.contains_key(t) && !new.iter().any(|&n| texts[n] == *t) {
                new.push(k);
            }
        }
        let room = self.fit.budget.saturating_sub(st.next);
        let truncated = new.len() > room;
        new.truncate(room);
        if !new.is_empty() {
            let generation = st.generation;
            let first = st.next;
            let list: Vec<Point> = new
                .iter()
                .enumerate()
                .map(|(n, &k)| self.point(first + n, &texts[k], &points[k]))
                .collect();
            drop(st);
            let ran = self.run_generation(generation, &list);
            st = self.state.lock().expect("state lock");
            match ran {
                Err(e) => {
                    st.failure = Some(e);
                    st.halt = Some(Halt::Done);
                    return None;
                }
                Ok(Some(halt)) => {
                    st.halt = Some(halt);
                    return None;
                }
                Ok(None) => {}
            }
            let dir = self.generation_dir(generation);
            for (n, &k) in new.iter().enumerate() {
                let index = first + n;
                let name = &list[n].name;
                match self.read_point(&dir, name) {
                    Ok((figures, features)) => {
                        let distance = self.fit.distance(&features, &figures, self.reference);
                        let d = distance.total;
                        st.points.push(Evaluated {
                            index,
                            generation,
                            name: name.clone(),
                            values: texts[k].clone(),
                            x: points[k].clone(),
                            figures,
                            features,
                            distance,
                        });
                        st.cache.insert(texts[k].clone(), index);
                        let best = st
                            .points
                            .iter()
                            .map(|p| p.distance.total)
                            .fold(f64::INFINITY, f64::min);
                        drop(st);
                        self.tell(Progress::Evaluated {
                            index,
                            distance: d,
                            best,
                        });
                        st = self.state.lock().expect("state lock");
                    }
                    Err(e) => {
                        st.failure = Some(e);
                        st.halt = Some(Halt::Done);
                        return None;
                    }
                }
            }
            st.next = first + new.len();
            st.generation += 1;
        }
        if truncated {
            st.halt = Some(Halt::Done);
            return None;
        }
        Some(
            texts
                .iter()
                .map(|t| st.points[st.cache[t]].distance.total)
                .collect(),
        )
    }

    fn generation_dir(&self, generation: usize) -> PathBuf {
        self.dir.join(format!("gen-{generation:03}"))
    }

    fn point(&self, index: usize, texts: &[String], _x: &[f64]) -> Point {
        let mut name = format!("{index:03}");
        for (v, t) in self.fit.vary.iter().zip(texts) {
            name += &format!("_{}={t}", short(&v.key));
        }
        let mut name = safe(&name);
        name.truncate(MAX_NAME);
        Point {
            index,
            name,
            settings: self
                .fit
                .vary
                .iter()
                .zip(texts)
                .map(|(v, t)| (v.key.clone(), t.clone()))
                .collect(),
            overrides: self.fit.overrides_of(texts),
        }
    }

    /// Runs a generation's points as a sweep (this shard's, if sharded);
    /// `Some(halt)` if not all of them are complete afterwards.
    fn run_generation(&self, generation: usize, list: &[Point]) -> Result<Option<Halt>, FitError> {
        let dir = self.generation_dir(generation);
        let mut plan = Plan::of_points(
            &self.fit.preset,
            list.to_vec(),
            Some(self.fit.frames),
            None,
            "off",
        )?;
        let (lattice, frames) = (self.fit.lattice.clone(), self.fit.frames);
        let horizon = self.horizon.clone();
        plan.measurement = Some(Measurement(Arc::new(move |scene: &Scene| {
            Box::new(Probe::new(lattice.clone(), frames, scene).with_horizon(horizon.clone()))
                as Box<dyn Measure>
        })));
        if self.dry {
            let missing = list.iter().filter(|p| !is_complete(&dir, &p.name)).count();
            return Ok((missing > 0).then_some(Halt::Pending {
                generation,
                missing,
            }));
        }
        let outcome =
            crate::sweep::run(&plan, &dir, self.shard, self.jobs, self.stop, |p| match p {
                crate::sweep::Progress::Start { total, skipped } => {
                    self.tell(Progress::Generation {
                        generation,
                        run: total - skipped,
                        done: skipped,
                    })
                }
                crate::sweep::Progress::Done(r, t) => self.tell(Progress::Ran {
                    name: r.name.clone(),
                    time: t,
                }),
                crate::sweep::Progress::Error(_) => {}
            })?;
        if !outcome.errors.is_empty() {
            return Err(FitError::Points(outcome.errors));
        }
        let missing = list.iter().filter(|p| !is_complete(&dir, &p.name)).count();
        if missing == 0 {
            return Ok(None);
        }
        if self.stop.load(Ordering::Relaxed) {
            return Ok(Some(Halt::Interrupted));
        }
        Ok(Some(Halt::Pending {
            generation,
            missing,
        }))
    }

    fn read_point(&self, dir: &Path, name: &str) -> Result<(Figures, Features), FitError> {
        let path = dir.join(format!("{name}.json"));
        let text = std::fs::read_to_string(&path).map_err(file("reading", &path))?;
        let bad =
            |e: serde_json::Error| FitError::File(file("reading", &path)(std::io::Error::other(e)));
        let result: PointResult = serde_json::from_str(&text).map_err(bad)?;
        let features: Features =
            serde_json::from_value(result.measured.unwrap_or_default()).map_err(bad)?;
        Ok((result.figures, features))
    }
}

impl Evaluate for Evaluator<'_> {
    fn evaluate(&self, points: &[Vec<f64>]) -> Option<Vec<f64>> {
        self.generation(points)
    }
}

/// Runs (or resumes) a fit in `dir`: the points of `shard` (all without
/// one) on `jobs` threads; no new point starts once `stop` is set. A `dry`
/// fit runs nothing: it goes as far as the points on disk take it.
pub fn run(
    fit: &Fit,
    dir: &Path,
    shard: Option<Shard>,
    jobs: usize,
    stop: &AtomicBool,
    dry: bool,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<Outcome, FitError> {
    prepare(dir, &fit.manifest())?;
    let (reference, horizon) = reference_features(fit, dir, !dry)?;
    let eval = Evaluator {
        fit,
        dir,
        shard,
        jobs,
        stop,
        dry,
        reference: reference.as_ref(),
        horizon,
        progress: Mutex::new(progress),
        state: Mutex::new(State {
            generation: 0,
            next: 0,
            cache: HashMap::new(),
            points: Vec::new(),
            halt: None,
            errors: Vec::new(),
            failure: None,
        }),
    };
    search::search(fit.method, &fit.start_point(), fit.seed, fit.budget, &eval)?;
    let st = eval.state.into_inner().expect("state lock");
    if let Some(e) = st.failure {
        return Err(e);
    }
    if !st.errors.is_empty() {
        return Err(FitError::Points(st.errors));
    }
    Ok(Outcome {
        halt: st.halt.unwrap_or(Halt::Done),
        points: st.points,
        reference,
    })
}
