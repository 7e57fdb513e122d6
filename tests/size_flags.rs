//! Every size a user gives is bounded with a message naming the flag and its range: nothing
//! aborts on an allocation or runs for days because a zero too many was typed.

mod common;

use common::fails;

/// A huge value and zero for each size flag: a clean refusal naming the flag, no panic, no
/// abort (exit code 1, not 134).
#[test]
fn huge_and_zero_sizes_are_refused_by_name() {
    let huge = "100000000000000";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--bayes",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--starts",
                huge,
            ],
            "--starts",
        ),
        (
            vec![
                "calibrate",
                "--material",
                "examples/gravel.toml",
                "--starts",
                "0",
            ],
            "--starts",
        ),
        (
            vec![
                "diagnose",
                "--measurements",
                "examples/measurements/control.toml",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "diagnose",
                "--measurements",
                "examples/measurements/control.toml",
                "--starts",
                huge,
            ],
            "--starts",
        ),
        (
            vec![
                "sensitivity",
                "sobol",
                "--model",
                "models/diagnose_local.json",
                "--samples",
                "64",
                "--bootstrap",
                huge,
            ],
            "--bootstrap",
        ),
        (
            vec![
                "sensitivity",
                "sobol",
                "--model",
                "models/diagnose_local.json",
                "--samples",
                huge,
            ],
            "--samples",
        ),
        (
            vec![
                "sample", "--method", "sobol", "--dim", "3", "--n", huge, "--out", "x.csv",
            ],
            "--n",
        ),
    ];
    for (args, flag) in cases {
        let o = common::mbgc(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let e = fails(&args);
        assert!(e.contains(flag), "{args:?}: {e}");
    }
}
