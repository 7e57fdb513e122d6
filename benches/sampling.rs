//! Design generation time: 1000 points in 12 dimensions for every method must take well under a
//! second. Prints each method's time and its ratio to the budget; exits non-zero when a method
//! exceeds half a second ("well under").
//!
//!     cargo bench --bench sampling

use mbgc::sampling::Method;
use mbgc_studies::sampling_quality::timing;

fn main() {
    let (n, dim) = (1000, 12);
    let budget = 0.5;
    let times = timing(&Method::ALL, n, dim, 5).expect("timing run");
    println!("design generation, {n} points x {dim} dimensions, best of 5 (budget {budget} s)");
    println!(
        "{:<12} {:>10} {:>10} {:>12}",
        "method", "best s", "median s", "best/budget"
    );
    let mut over = false;
    for t in &times {
        let ratio = t.best_s / budget;
        over |= ratio > 1.0;
        println!(
            "{:<12} {:>10.4} {:>10.4} {:>12.3}",
            t.method, t.best_s, t.median_s, ratio
        );
    }
    if over {
        eprintln!("a method exceeded the budget");
        std::process::exit(1);
    }
}
