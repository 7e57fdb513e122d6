//! The evolutionary search: gplearn's generational GP with tournaments and parsimony, plus what
//! the stronger engines add: islands with ring migration, elitism, constant tuning of the most
//! promising trees, and a hall of fame that keeps the best tree of every size across generations.

use super::constants::Tuner;
use super::eval::{score, Dataset, Evaluator, Score};
use super::expr::Expr;
pub use super::front::FrontEntry;
use super::node::{parse_function_set, Node, SEED004_FUNCTIONS};
use super::program::{self, Alphabet, Program};
use super::select::{self, Selection};
use crate::seed::splitmix64;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of a run. Defaults follow gplearn (and seed 004: population 5000, parsimony 0.001,
/// functions + - * / sqrt log exp tanh) where gplearn has the setting.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Config {
    /// Trees per generation, all islands together (gplearn 1000, seed 004 5000); at least 2 per
    /// island.
    pub population: usize,
    /// Populations evaluated, the initial one included (as gplearn counts).
    pub generations: usize,
    /// Sub-populations evolving separately, exchanging `migrants` every `migration_interval`.
    pub islands: usize,
    /// Generations between migrations (0 is taken as 1).
    pub migration_interval: usize,
    /// Best trees of each island that replace the worst of the next island in the ring, at most
    /// half an island.
    pub migrants: usize,
    /// Trees drawn per tournament, the fittest (lowest penalised error) wins (gplearn 20): larger
    /// tournaments select harder and lose diversity sooner.
    pub tournament: usize,
    /// Probability that a child is a crossover of two tournament winners (gplearn 0.9).
    pub p_crossover: f64,
    /// Probability of subtree mutation: crossover with a fresh random tree (gplearn 0.01).
    pub p_subtree: f64,
    /// Probability of hoist mutation: a subtree replaced by one of its own subtrees, against
    /// bloat (gplearn 0.01).
    pub p_hoist: f64,
    /// Probability of point mutation (gplearn 0.01). The probabilities p_crossover, p_subtree,
    /// p_hoist, p_point and p_scale sum to at most 1; the rest is reproduction (the winner copied).
    pub p_point: f64,
    /// Probability that point mutation replaces each node by one of the same arity
    /// (gplearn 0.05).
    pub p_point_replace: f64,
    /// Variable `x` replaced by `x * c` (not in gplearn; taken from its reproduction share).
    pub p_scale: f64,
    /// Penalty per node added to the normalised error (1 - R^2), so it means the same for every
    /// response whatever its unit.
    pub parsimony: f64,
    /// The function set, comma-separated names of [`crate::node::FUNCTIONS`] (default seed 004's
    /// `add,sub,mul,div,sqrt,log,exp,tanh`).
    pub functions: String,
    /// Range (lo, hi), lo < hi, of random constants in new trees (gplearn (-1, 1)).
    pub const_range: (f64, f64),
    /// Depth range (min, max) of the initial ramped half-and-half trees and of subtree
    /// mutation's fresh trees (gplearn (2, 6)).
    pub init_depth: (usize, usize),
    /// Children longer than this are replaced by their parent (gplearn has no limit and bloats).
    pub max_length: usize,
    /// Best trees of each island copied unchanged into the next generation.
    pub elitism: usize,
    /// Fit the output as `a + b * tree` (Keijzer's linear scaling).
    pub linear_scaling: bool,
    /// Share of each island (the fittest) whose constants are tuned every generation.
    pub tune_fraction: f64,
    /// Levenberg-Marquardt steps per tuning during the search (the final polish takes 50).
    pub tune_iterations: usize,
    /// Rows used for tuning during the search (a fixed stride subset); the final tuning uses all.
    pub tune_rows: usize,
    /// Stop once the best normalised error has stayed below this for `stop_patience` generations.
    pub stop_nmse: f64,
    /// Generations the best error must stay below `stop_nmse` before the search stops.
    pub stop_patience: usize,
    /// Wall-clock limit in seconds (makes the result depend on machine speed).
    pub time_limit: Option<f64>,
    /// Seed of every random choice: with no `time_limit`, the result is a function of the data,
    /// the settings and this seed, whatever the number of threads.
    pub seed: u64,
    /// Independent searches (seeds `seed`, `seed + 1`, ...) whose Pareto fronts are merged
    /// before the equation is picked: one search's result varies with its seed, and the merged
    /// front is at least as good as each one at every size.
    #[serde(default = "one")]
    pub restarts: usize,
    /// The rule that picks the returned equation from the merged front.
    #[serde(default)]
    pub selection: Selection,
}

fn one() -> usize {
    1
}

impl Default for Config {
    fn default() -> Config {
        Config {
            population: 5000,
            generations: 20,
            islands: 4,
            migration_interval: 5,
            migrants: 10,
            tournament: DEFAULT_TOURNAMENT,
            p_crossover: 0.9,
            p_subtree: 0.01,
            p_hoist: 0.01,
            p_point: 0.01,
            p_point_replace: 0.05,
            p_scale: 0.03,
            parsimony: 0.001,
            functions: SEED004_FUNCTIONS.to_string(),
            const_range: (-1.0, 1.0),
            init_depth: (2, 6),
            max_length: 64,
            elitism: 2,
            linear_scaling: true,
            tune_fraction: 0.1,
            tune_iterations: 8,
            tune_rows: 256,
            stop_nmse: 1e-24,
            stop_patience: 3,
            time_limit: None,
            seed: 1,
            restarts: 1,
            selection: Selection::Best,
        }
    }
}

/// Most trees per generation (all islands together): beyond this one generation's trees alone
/// take gigabytes.
pub const MAX_POPULATION: usize = 1_000_000;
/// Most generations of one search.
pub const MAX_GENERATIONS: usize = 1_000_000;
/// Trees per tournament unless set (gplearn's 20).
pub const DEFAULT_TOURNAMENT: usize = 20;
/// Most islands.
pub const MAX_ISLANDS: usize = 1_000;
/// Most independent searches.
pub const MAX_RESTARTS: usize = 1_000;
/// Longest tree (nodes) a search may build: far beyond a readable equation.
pub const MAX_LENGTH: usize = 10_000;

/// The allowed range of one size setting of a [`Config`], from [`Config::sizes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeRange {
    /// The field (`max_length`; the command line spells it `--max-length`).
    pub name: &'static str,
    /// What it counts ("trees", "nodes"), for the message.
    pub unit: &'static str,
    /// The value given.
    pub value: usize,
    /// Smallest allowed value.
    pub min: usize,
    /// Largest allowed value.
    pub max: usize,
}

impl SizeRange {
    /// Whether the value lies in the range.
    pub fn holds(&self) -> bool {
        (self.min..=self.max).contains(&self.value)
    }

    /// The option of a command line that sets it: `--max-length`.
    pub fn flag(&self) -> String {
        format!("--{}", self.name.replace('_', "-"))
    }

    /// "{name} {value}: expected {min} to {max} {unit}", naming the field as `name` says.
    pub fn refusal(&self, name: &str) -> String {
        format!(
            "{name} {}: expected {} to {} {}",
            self.value, self.min, self.max, self.unit
        )
    }
}

impl Config {
    /// The size settings with their allowed ranges, in the order they are checked (a range may
    /// depend on an earlier setting: the population holds at least 2 trees per island, a
    /// tournament draws at most the population). Stated here once, for [`Config::check`] and
    /// for a command line naming its flags.
    pub fn sizes(&self) -> [SizeRange; 6] {
        let islands = self.islands.clamp(1, MAX_ISLANDS);
        let population = self.population.clamp(2 * islands, MAX_POPULATION);
        let range = |name, unit, value, min, max| SizeRange {
            name,
            unit,
            value,
            min,
            max,
        };
        [
            range("islands", "islands", self.islands, 1, MAX_ISLANDS),
            range(
                "population",
                "trees (at least 2 per island)",
                self.population,
                2 * islands,
                MAX_POPULATION,
            ),
            // A tournament beyond the population only repeats its draws; small populations keep
            // the default 20.
            range(
                "tournament",
                "trees (at most the population, or 20 below 20 trees)",
                self.tournament,
                1,
                population.max(DEFAULT_TOURNAMENT),
            ),
            range(
                "generations",
                "generations",
                self.generations,
                1,
                MAX_GENERATIONS,
            ),
            range("restarts", "searches", self.restarts, 1, MAX_RESTARTS),
            range("max_length", "nodes", self.max_length, 1, MAX_LENGTH),
        ]
    }

    /// Checks the settings; the message names the field.
    pub fn check(&self) -> Result<Vec<Node>, String> {
        let functions =
            parse_function_set(&self.functions).map_err(|e| format!("functions: {e}"))?;
        let p_sum = self.p_crossover + self.p_subtree + self.p_hoist + self.p_point + self.p_scale;
        let prob = |name: &str, v: f64| -> Result<(), String> {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(format!("{name}: expected a probability in [0, 1], got {v}"))
            }
        };
        prob("p_crossover", self.p_crossover)?;
        prob("p_subtree", self.p_subtree)?;
        prob("p_hoist", self.p_hoist)?;
        prob("p_point", self.p_point)?;
        prob("p_point_replace", self.p_point_replace)?;
        prob("p_scale", self.p_scale)?;
        prob("tune_fraction", self.tune_fraction)?;
        if p_sum > 1.0 + 1e-12 {
            return Err(format!(
                "p_crossover + p_subtree + p_hoist + p_point + p_scale: expected at most 1, got {p_sum}"
            ));
        }
        if let Some(size) = self.sizes().iter().find(|s| !s.holds()) {
            return Err(size.refusal(size.name));
        }
        if self.init_depth.0 > self.init_depth.1 {
            return Err("init_depth: expected min <= max".into());
        }
        if self.const_range.0.is_nan()
            || self.const_range.0.partial_cmp(&self.const_range.1) != Some(std::cmp::Ordering::Less)
        {
            return Err("const_range: expected min < max".into());
        }
        if self.parsimony.is_nan() || self.parsimony < 0.0 {
            return Err(format!("parsimony: expected >= 0, got {}", self.parsimony));
        }
        Ok(functions)
    }
}

/// A member of the population: a tree and its score on the training rows.
#[derive(Clone, Debug)]
pub struct Individual {
    /// The tree, in postfix form, before the linear scaling is folded in.
    pub program: Program,
    /// Its normalised error and linear scaling on the training rows.
    pub score: Score,
    /// Normalised error plus parsimony penalty: what tournaments compare.
    pub fitness: f64,
    tuned: bool,
}

/// What [`fit`] reports to its callback after each generation.
#[derive(Clone, Debug)]
pub struct Progress {
    /// The generation just evaluated, from 0 (the random initial population); restarts count
    /// again from 0.
    pub generation: usize,
    /// Best normalised error (1 - R^2) in the hall of fame so far.
    pub best_nmse: f64,
    /// Members of the current Pareto front of size against error.
    pub front_size: usize,
    /// Nodes times rows evaluated so far in this search, tuning included: the work measure
    /// that compares engines independently of the machine.
    pub node_evals: u64,
    /// Wall-clock time of this search so far, s.
    pub seconds: f64,
}

/// What [`fit`] returns: the merged Pareto front and the equation picked from it.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// Non-dominated (size, error) trees, smallest first.
    pub front: Vec<FrontEntry>,
    /// Index in `front` of the returned equation (see [`select`]).
    pub chosen: usize,
    /// Cross-validated normalised error of each front member (with [`Selection::CrossValidation`]).
    pub cv_nmse: Option<Vec<f64>>,
    /// Populations evaluated (the most of any restart).
    pub generations: usize,
    /// Nodes times rows evaluated over all restarts, tuning included.
    pub node_evals: u64,
    /// Wall-clock time summed over the restarts, s.
    pub seconds: f64,
}

impl FitResult {
    /// The returned equation, `front[chosen]`.
    pub fn best(&self) -> &FrontEntry {
        &self.front[self.chosen]
    }
}
/// A generator per (seed, generation, slot): the result does not depend on thread scheduling.
fn child_rng(seed: u64, generation: usize, slot: usize) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(splitmix64(
        splitmix64(seed ^ (generation as u64) << 40) ^ slot as u64,
    ))
}

struct Scratch {
    eval: Evaluator,
    tuner: Tuner,
    out: Vec<f64>,
}

impl Scratch {
    fn new(rows: usize) -> Scratch {
        Scratch {
            eval: Evaluator::new(),
            tuner: Tuner::new(),
            out: vec![0.0; rows],
        }
    }
}

fn evaluate(p: &Program, data: &Dataset, lin: bool, s: &mut Scratch) -> Score {
    if s.eval.eval(p, &data.x, &mut s.out) {
        score(&s.out, data, lin)
    } else {
        Score::INVALID
    }
}

fn individual(program: Program, score: Score, parsimony: f64, tuned: bool) -> Individual {
    let fitness = score.nmse + parsimony * program.len() as f64;
    Individual {
        program,
        score,
        fitness,
        tuned,
    }
}

fn tournament<'a>(island: &'a [Individual], k: usize, rng: &mut ChaCha8Rng) -> &'a Individual {
    let mut best = &island[rng.random_range(0..island.len())];
    for _ in 1..k {
        let c = &island[rng.random_range(0..island.len())];
        if c.fitness < best.fitness {
            best = c;
        }
    }
    best
}

/// Random points in the box spanned by the training inputs: a tree entering the hall of fame must
/// be finite on all of them, since the saved model claims that box as its valid domain.
fn domain_probe(train: &Dataset, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(seed ^ 0xd0d0));
    let n = 512;
    let x = train
        .x
        .iter()
        .map(|c| {
            let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mut col: Vec<f64> = (0..n)
                .map(|_| {
                    if hi > lo {
                        rng.random_range(lo..=hi)
                    } else {
                        lo
                    }
                })
                .collect();
            // The corners of each axis are where tails blow up first.
            col[0] = lo;
            col[1] = hi;
            col
        })
        .collect();
    Dataset::new(x, vec![0.0; n])
}

struct HallOfFame {
    /// Best tree of each length (index = length).
    slots: Vec<Option<Individual>>,
}

impl HallOfFame {
    fn update(&mut self, pop: &[Individual], probe: &Dataset, s: &mut Scratch) {
        let mut best: Vec<Option<&Individual>> = vec![None; self.slots.len()];
        for ind in pop.iter().filter(|i| i.score.is_valid()) {
            let l = ind.program.len();
            if l < best.len() && best[l].is_none_or(|b| ind.score.nmse < b.score.nmse) {
                best[l] = Some(ind);
            }
        }
        let mut out = vec![0.0; probe.rows()];
        for (l, cand) in best.into_iter().enumerate() {
            let Some(c) = cand else { continue };
            if self.slots[l]
                .as_ref()
                .is_some_and(|h| h.score.nmse <= c.score.nmse)
            {
                continue;
            }
            if s.eval.eval(&c.program, &probe.x, &mut out) {
                self.slots[l] = Some(c.clone());
            }
        }
    }

    /// Non-dominated members, smallest first.
    fn front(&self) -> Vec<&Individual> {
        let mut out: Vec<&Individual> = Vec::new();
        for ind in self.slots.iter().flatten() {
            if out.last().is_none_or(|b| ind.score.nmse < b.score.nmse) {
                out.push(ind);
            }
        }
        out
    }
}

/// Every `stride`-th row, so that tuning during the search sees the whole range of the data.
fn stride_subset(data: &Dataset, max_rows: usize) -> Dataset {
    if data.rows() <= max_rows {
        return data.clone();
    }
    let idx: Vec<usize> = (0..max_rows).map(|i| i * data.rows() / max_rows).collect();
    data.subset(&idx)
}

/// Runs the search on `train` (`cfg.restarts` times, fronts merged) and returns the Pareto front
/// with the chosen equation.
pub fn fit(
    train: &Dataset,
    cfg: &Config,
    mut progress: impl FnMut(&Progress),
) -> Result<FitResult, String> {
    cfg.check()?;
    if cfg.selection == Selection::CrossValidation && train.rows() < 2 * select::FOLDS {
        return Err(format!(
            "selection: cross-validation needs at least {} training rows ({} folds of 2), got {}; \
             pick by the knee instead (`--select best`)",
            2 * select::FOLDS,
            select::FOLDS,
            train.rows()
        ));
    }
    let mut entries = Vec::new();
    let (mut generations, mut node_evals, mut seconds) = (0, 0, 0.0);
    for k in 0..cfg.restarts {
        let one = Config {
            seed: cfg.seed.wrapping_add(k as u64),
            ..cfg.clone()
        };
        let r = fit_once(train, &one, &mut progress)?;
        generations = generations.max(r.generations);
        node_evals += r.node_evals;
        seconds += r.seconds;
        entries.extend(r.front);
    }
    let front = pareto(entries)?;
    let (chosen, cv_nmse) = match cfg.selection {
        Selection::Best => (select::pick(&front), None),
        Selection::CrossValidation => {
            let cv = select::cross_validation_errors(&front, train, cfg.linear_scaling, cfg.seed);
            (select::pick_cross_validated(&cv), Some(cv))
        }
    };
    Ok(FitResult {
        chosen,
        cv_nmse,
        front,
        generations,
        node_evals,
        seconds,
    })
}

/// The non-dominated entries, smallest first: each is more accurate than every smaller one.
fn pareto(mut entries: Vec<FrontEntry>) -> Result<Vec<FrontEntry>, String> {
    entries.sort_by(|a, b| {
        a.size
            .cmp(&b.size)
            .then(a.train_nmse.total_cmp(&b.train_nmse))
    });
    let mut front: Vec<FrontEntry> = Vec::new();
    for e in entries {
        if e.train_nmse.is_finite() && front.last().is_none_or(|b| e.train_nmse < b.train_nmse) {
            front.push(e);
        }
    }
    if front.is_empty() {
        return Err("no valid equation was found (every tree hit an invalid domain)".into());
    }
    Ok(front)
}

/// What one search returns: its front, before the merge and the pick.
struct Search {
    front: Vec<FrontEntry>,
    generations: usize,
    node_evals: u64,
    seconds: f64,
}

/// One search with `cfg.seed`.
fn fit_once(
    train: &Dataset,
    cfg: &Config,
    mut progress: impl FnMut(&Progress),
) -> Result<Search, String> {
    let functions = cfg.check()?;
    if train.rows() < 2 {
        return Err("the training data has fewer than 2 rows".into());
    }
    let start = Instant::now();
    let alphabet = Alphabet {
        functions,
        n_vars: train.n_vars(),
        const_range: cfg.const_range,
    };
    let lin = cfg.linear_scaling;
    let tune_data = stride_subset(train, cfg.tune_rows);
    let probe = domain_probe(train, cfg.seed);
    let island_size = cfg.population / cfg.islands;
    let n = island_size * cfg.islands;
    let rows = train.rows();
    let mut node_evals = 0u64;
    let mut hof = HallOfFame {
        slots: vec![None; cfg.max_length + 1],
    };
    let mut main_scratch = Scratch::new(rows);

    // Generation 0: ramped half-and-half.
    let (mut pop, evals): (Vec<Individual>, Vec<u64>) = (0..n)
        .into_par_iter()
        .map_init(
            || Scratch::new(rows),
            |s, slot| {
                let mut rng = child_rng(cfg.seed, 0, slot);
                let mut p = alphabet.ramped_tree(cfg.init_depth, &mut rng);
                if p.len() > cfg.max_length {
                    p = alphabet.random_tree(1, true, &mut rng);
                }
                let before = s.eval.node_evals;
                let sc = evaluate(&p, train, lin, s);
                (
                    individual(p, sc, cfg.parsimony, false),
                    s.eval.node_evals - before,
                )
            },
        )
        .unzip();
    node_evals += evals.iter().sum::<u64>();

    let mut below_since: Option<usize> = None;
    let mut generation = 0;
    loop {
        // Constant tuning of each island's fittest untuned members (Lamarckian: kept).
        let n_tune = ((island_size as f64 * cfg.tune_fraction).ceil() as usize).min(island_size);
        if n_tune > 0 && cfg.tune_iterations > 0 {
            let mut picks = Vec::new();
            for isl in 0..cfg.islands {
                let mut order: Vec<usize> = (isl * island_size..(isl + 1) * island_size).collect();
                order.sort_by(|&a, &b| pop[a].fitness.total_cmp(&pop[b].fitness).then(a.cmp(&b)));
                picks.extend(order.into_iter().filter(|&i| !pop[i].tuned).take(n_tune));
            }
            let tuned: Vec<(usize, Individual, u64)> = picks
                .par_iter()
                .map_init(
                    || Scratch::new(rows),
                    |s, &i| {
                        let mut p = pop[i].program.clone();
                        let before = s.tuner_evals();
                        s.tuner.tune(&mut p, &tune_data, lin, cfg.tune_iterations);
                        let sc = evaluate(&p, train, lin, s);
                        let ind = individual(p, sc, cfg.parsimony, true);
                        (i, ind, s.tuner_evals() - before)
                    },
                )
                .collect();
            for (i, ind, e) in tuned {
                node_evals += e;
                if ind.fitness <= pop[i].fitness {
                    pop[i] = ind;
                } else {
                    pop[i].tuned = true;
                }
            }
        }
        hof.update(&pop, &probe, &mut main_scratch);
        let front = hof.front();
        let best_nmse = front.last().map_or(f64::INFINITY, |b| b.score.nmse);
        progress(&Progress {
            generation,
            best_nmse,
            front_size: front.len(),
            node_evals,
            seconds: start.elapsed().as_secs_f64(),
        });
        if best_nmse <= cfg.stop_nmse {
            let since = *below_since.get_or_insert(generation);
            if generation - since >= cfg.stop_patience {
                break;
            }
        }
        generation += 1;
        let out_of_time = cfg
            .time_limit
            .is_some_and(|t| start.elapsed().as_secs_f64() >= t);
        if generation >= cfg.generations || out_of_time {
            generation -= 1;
            break;
        }

        // Ring migration: each island's best replace the next island's worst.
        if cfg.islands > 1 && generation % cfg.migration_interval.max(1) == 0 {
            let m = cfg.migrants.min(island_size / 2);
            let mut moves = Vec::new();
            for isl in 0..cfg.islands {
                let mut order: Vec<usize> = (isl * island_size..(isl + 1) * island_size).collect();
                order.sort_by(|&a, &b| pop[a].fitness.total_cmp(&pop[b].fitness).then(a.cmp(&b)));
                let dest = (isl + 1) % cfg.islands;
                let mut dorder: Vec<usize> =
                    (dest * island_size..(dest + 1) * island_size).collect();
                dorder.sort_by(|&a, &b| pop[b].fitness.total_cmp(&pop[a].fitness).then(a.cmp(&b)));
                for k in 0..m {
                    moves.push((order[k], dorder[k]));
                }
            }
            let snapshot: Vec<Individual> = moves.iter().map(|&(s, _)| pop[s].clone()).collect();
            for ((_, d), ind) in moves.into_iter().zip(snapshot) {
                pop[d] = ind;
            }
        }

        let elites: Vec<Vec<usize>> = (0..cfg.islands)
            .map(|isl| {
                let mut order: Vec<usize> = (isl * island_size..(isl + 1) * island_size).collect();
                order.sort_by(|&a, &b| pop[a].fitness.total_cmp(&pop[b].fitness).then(a.cmp(&b)));
                order.truncate(cfg.elitism.min(island_size));
                order
            })
            .collect();
        let prev = &pop;
        let (next, evals): (Vec<Individual>, Vec<u64>) = (0..n)
            .into_par_iter()
            .map_init(
                || Scratch::new(rows),
                |s, slot| {
                    let isl = slot / island_size;
                    let pos = slot % island_size;
                    if pos < elites[isl].len() {
                        return (prev[elites[isl][pos]].clone(), 0);
                    }
                    let island = &prev[isl * island_size..(isl + 1) * island_size];
                    let mut rng = child_rng(cfg.seed, generation, slot);
                    let parent = tournament(island, cfg.tournament, &mut rng);
                    let r: f64 = rng.random();
                    let child = if r < cfg.p_crossover {
                        let donor = tournament(island, cfg.tournament, &mut rng);
                        program::crossover(&parent.program, &donor.program, &mut rng)
                    } else if r < cfg.p_crossover + cfg.p_subtree {
                        program::subtree_mutation(
                            &parent.program,
                            &alphabet,
                            cfg.init_depth,
                            &mut rng,
                        )
                    } else if r < cfg.p_crossover + cfg.p_subtree + cfg.p_hoist {
                        program::hoist_mutation(&parent.program, &mut rng)
                    } else if r < cfg.p_crossover + cfg.p_subtree + cfg.p_hoist + cfg.p_point {
                        program::point_mutation(
                            &parent.program,
                            &alphabet,
                            cfg.p_point_replace,
                            &mut rng,
                        )
                    } else if r < cfg.p_crossover
                        + cfg.p_subtree
                        + cfg.p_hoist
                        + cfg.p_point
                        + cfg.p_scale
                    {
                        program::scale_mutation(&parent.program, &alphabet, &mut rng)
                    } else {
                        return (parent.clone(), 0);
                    };
                    if child.len() > cfg.max_length {
                        return (parent.clone(), 0);
                    }
                    let before = s.eval.node_evals;
                    let sc = evaluate(&child, train, lin, s);
                    (
                        individual(child, sc, cfg.parsimony, false),
                        s.eval.node_evals - before,
                    )
                },
            )
            .unzip();
        node_evals += evals.iter().sum::<u64>();
        pop = next;
    }

    // Final polish of the hall of fame on all training rows, fold the scaling in, simplify.
    let members: Vec<Individual> = hof.slots.iter().flatten().cloned().collect();
    let polished: Vec<(FrontEntry, u64)> = members
        .par_iter()
        .map_init(
            || Scratch::new(rows),
            |s, ind| {
                let before = s.tuner_evals();
                let mut p = ind.program.clone();
                let sc = s.tuner.tune(&mut p, train, lin, 50);
                let e = s.tuner_evals() - before;
                (finish(&p, sc, ind, train, &probe, s), e)
            },
        )
        .collect();
    let mut entries: Vec<FrontEntry> = Vec::new();
    for (entry, e) in polished {
        node_evals += e;
        entries.push(entry);
    }
    let front = pareto(entries)?;
    Ok(Search {
        front,
        generations: generation + 1,
        node_evals,
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl Scratch {
    fn tuner_evals(&self) -> u64 {
        self.eval.node_evals + self.tuner.node_evals()
    }
}

/// Folds `intercept + slope * tree` into one tree, simplifies it, and keeps the simpler of the
/// tuned and untuned versions that is valid on the domain probe.
fn finish(
    tuned: &Program,
    tuned_score: Score,
    original: &Individual,
    train: &Dataset,
    probe: &Dataset,
    s: &mut Scratch,
) -> FrontEntry {
    let candidates = [
        (tuned.clone(), tuned_score),
        (original.program.clone(), original.score),
    ];
    let mut best: Option<FrontEntry> = None;
    let mut out_probe = vec![0.0; probe.rows()];
    for (p, sc) in candidates {
        if !sc.is_valid() {
            continue;
        }
        // Also try without the intercept and without the slope: an intercept of 1e-16 left by
        // round-off is noise, and dropping it makes the equation say what it is.
        let variants = [
            (sc.intercept, sc.slope),
            (0.0, sc.slope),
            (sc.intercept, 1.0),
            (0.0, 1.0),
        ];
        for (a, b) in variants {
            let folded = Expr::Binary(
                Node::Add,
                Box::new(Expr::Const(a)),
                Box::new(Expr::Binary(
                    Node::Mul,
                    Box::new(Expr::Const(b)),
                    Box::new(Expr::from_postfix(&p)),
                )),
            );
            let simple = folded.simplify().to_postfix();
            if !s.eval.eval(&simple, &probe.x, &mut out_probe) {
                continue;
            }
            let fs = evaluate(&simple, train, false, s);
            if !fs.is_valid() {
                continue;
            }
            let e = FrontEntry {
                size: simple.len(),
                program: simple,
                train_nmse: fs.nmse,
            };
            let better = match &best {
                None => true,
                Some(b) => {
                    // Smaller wins when it is as accurate up to round-off.
                    let tol = (b.train_nmse * (1.0 + 1e-6)).max(super::select::ERROR_FLOOR);
                    (e.size < b.size && e.train_nmse <= tol)
                        || (e.size >= b.size
                            && e.train_nmse < b.train_nmse
                            && b.train_nmse > super::select::ERROR_FLOOR)
                }
            };
            if better {
                best = Some(e);
            }
        }
    }
    best.unwrap_or(FrontEntry {
        program: original.program.clone(),
        size: original.program.len(),
        train_nmse: f64::INFINITY,
    })
}
