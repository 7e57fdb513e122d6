//! The front does not depend on how many threads evolve it: `mbgc train --threads` bounds the
//! fit by running it in a pool of that size, which is only right if the result is the same.

use mbgc_sr::select::Selection;
use mbgc_sr::{fit, Config, Dataset};

fn front_in_pool(threads: usize) -> Vec<(String, u64)> {
    let x: Vec<f64> = (0..40).map(|i| 0.1 + i as f64 / 8.0).collect();
    let z: Vec<f64> = (0..40).map(|i| ((i * 7) % 11) as f64 / 3.0).collect();
    let y: Vec<f64> = x
        .iter()
        .zip(&z)
        .map(|(x, z)| x.sqrt() * z + 0.3 * x * x)
        .collect();
    let data = Dataset::new(vec![x, z], y);
    let cfg = Config {
        population: 240,
        generations: 6,
        islands: 3,
        restarts: 2,
        selection: Selection::CrossValidation,
        seed: 11,
        ..Config::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let result = pool
        .install(|| fit(&data, &cfg, |_| {}))
        .expect("a valid front");
    result
        .front
        .iter()
        .map(|e| (format!("{:?}", e.program), e.train_nmse.to_bits()))
        .collect()
}

#[test]
fn one_two_and_three_threads_give_the_same_front_to_the_bit() {
    let one = front_in_pool(1);
    assert!(one.len() > 1, "{one:?}");
    assert_eq!(front_in_pool(2), one);
    assert_eq!(front_in_pool(3), one);
}
