//! Genetic-programming symbolic regression: readable equations fitted to tables.
//!
//! Given a table of inputs and one response, [`fit`] evolves expression trees (gplearn's
//! generational GP: tournaments, crossover, subtree, hoist and point mutation, parsimony) with
//! what stronger engines add (islands, elitism, Levenberg-Marquardt tuning of the constants,
//! linear scaling of the output, a hall of fame per tree size), and returns the Pareto front of
//! size against error with one equation picked by a stated rule ([`select`]). Operators are real
//! mathematics, not gplearn's protected ones: a tree that takes the log of a negative or divides
//! by zero on a training row, or on one of 512 random points in the box spanned by the training
//! inputs, is invalid, so the printed equation means exactly what was fitted.
//!
//! It is a general-purpose regression engine: it knows nothing of DEM, materials or calibration
//! (mbgc feeds it the responses of its simulations), reads and writes no files (the front and
//! [`Config`] are `serde` types the caller may store), and has no units: scale the inputs and
//! outputs yourself if their magnitudes differ widely.
//!
//! Trees are flat postfix arrays ([`program`]) over an alphabet of variables, constants and a
//! configurable function set ([`node`]); [`eval`] evaluates them in batches and scores them,
//! [`constants`] tunes their constants by Levenberg-Marquardt, [`engine`] evolves them, [`select`]
//! picks the returned equation from the Pareto front, [`expr`] simplifies and prints it, and
//! [`grad`] differentiates it exactly for gradient-based calibration.
//!
//! Entry points: [`Dataset::new`], [`Config`] (defaults follow gplearn and seed 004), [`fit`],
//! then [`FitResult::best`] and [`expr::infix`] to print it.
//!
//! # Example: recover a line
//!
//! A small search (200 trees, a few generations, fixed seed: the result is the same on every
//! machine and thread count) finds y = 2 x + 1 exactly.
//!
//! ```
//! use mbgc_sr::{fit, Config, Dataset};
//!
//! let x: Vec<f64> = (0..20).map(|i| i as f64 / 4.0).collect();
//! let y: Vec<f64> = x.iter().map(|x| 2.0 * x + 1.0).collect();
//! let data = Dataset::new(vec![x], y);
//! let cfg = Config {
//!     population: 200,
//!     generations: 5,
//!     islands: 2,
//!     seed: 7,
//!     ..Config::default()
//! };
//! let result = fit(&data, &cfg, |_| {}).expect("a valid equation");
//! let best = result.best();
//! let r2 = 1.0 - best.train_nmse;
//! assert!(r2 > 0.99, "train R^2 {r2}");
//!
//! // The equation is self-contained (the linear scaling is folded in): evaluate it at x = 10,
//! // outside the training range, and print it.
//! let mut out = [0.0];
//! assert!(mbgc_sr::eval::Evaluator::new().eval(&best.program, &[vec![10.0]], &mut out));
//! assert!((out[0] - 21.0).abs() < 1e-6, "{}", out[0]);
//! let printed = mbgc_sr::expr::infix(
//!     &mbgc_sr::expr::Expr::from_postfix(&best.program),
//!     &["x".to_string()],
//!     &mbgc_sr::expr::exact_constant,
//! );
//! assert_eq!(printed, "x*2.0 + 1.0");
//! ```
//!
//! # Example: simplify and print a tree
//!
//! ```
//! use mbgc_sr::expr::{exact_constant, infix, Expr};
//! use mbgc_sr::Node::{Add, Const, Mul, Sub, Var};
//!
//! // ((x * 1) + 0) * (2 * 3) - (y - y), in postfix.
//! let postfix = [
//!     Var(0), Const(1.0), Mul, Const(0.0), Add, Const(2.0), Const(3.0), Mul, Mul,
//!     Var(1), Var(1), Sub, Sub,
//! ];
//! let e = Expr::from_postfix(&postfix).simplify();
//! let names = ["x".to_string(), "y".to_string()];
//! assert_eq!(infix(&e, &names, &exact_constant), "x*6.0");
//! assert_eq!(e.size(), 3);
//! ```

#![warn(missing_docs)]

pub mod constants;
pub mod engine;
pub mod eval;
pub mod expr;
pub mod front;
pub mod grad;
pub mod node;
pub mod program;
pub mod seed;
pub mod select;

pub use engine::{fit, Config, FitResult, FrontEntry, Progress, SizeRange};
pub use eval::Dataset;
pub use node::Node;
