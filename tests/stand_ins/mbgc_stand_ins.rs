//! `mbgc` with the test stand-in experiments registered: the integration tests of the campaign
//! machinery run this binary (built by `cargo test` as the example `mbgc_stand_ins`), so that
//! the shipped `mbgc` knows only real experiments.

mod sleep_test;

fn main() -> std::process::ExitCode {
    mbgc::campaign::registry::register("sleep-test", |_| Ok(Box::new(sleep_test::SleepTest)))
        .expect("register sleep-test");
    mbgc::cli::main()
}
