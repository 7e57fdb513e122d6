//! LIGGGHTS end to end on a tiny case. Ignored by default (needs the `liggghts` package):
//! cargo test --test liggghts -- --ignored

use mbgc::liggghts;
use mbgc_studies::dem_scene::{jittered_lattice, liggghts_case, BenchSpec, BENCHMARK_BOX};

#[test]
#[ignore = "runs LIGGGHTS (apt-get install liggghts)"]
fn tiny_case_settles_inside_the_box() {
    // Asked for explicitly (--ignored), a missing LIGGGHTS is a failure, not a pass.
    assert!(
        liggghts::find_binary().is_some(),
        "LIGGGHTS is not installed: this test needs `liggghts` (or `lmp_auto`) on PATH \
         (Debian: apt-get install liggghts)"
    );
    // 200 particles in the bottom 6 cm, so they reach the floor within the 2000 settling steps.
    let (positions, radii) =
        jittered_lattice(200, [0.0; 3], [0.12, 0.12, 0.06], 0.0075, 0.01, 3).unwrap();
    let top = |p: &[[f64; 3]], r: &[f64]| {
        p.iter()
            .zip(r)
            .map(|(p, r)| p[2] + r)
            .fold(f64::MIN, f64::max)
    };
    let initial_top = top(&positions, &radii);
    let case = liggghts_case(&BenchSpec::default(), positions, radii.clone(), 2000, 500);

    let dir = tempfile::tempdir().unwrap();
    let res = liggghts::closed_box::run(dir.path(), &case).unwrap();

    assert!(res.version.starts_with("LIGGGHTS"), "{}", res.version);
    assert!(res.timed_wall_s > 0.0 && res.particle_steps_per_s > 0.0);
    assert_eq!(res.settled_positions.len(), 200);
    assert_eq!(res.settled_radii, radii);
    for (p, r) in res.settled_positions.iter().zip(&res.settled_radii) {
        for k in 0..3 {
            // Impacts at ~1 m/s press a few % of a radius into a wall; 10 % is far outside.
            assert!(
                p[k] - r > -0.1 * r && p[k] + r < BENCHMARK_BOX[k] + 0.1 * r,
                "{p:?} r={r}"
            );
        }
    }
    let settled_top = top(&res.settled_positions, &res.settled_radii);
    assert!(
        settled_top < initial_top,
        "settled top {settled_top} not below initial top {initial_top}"
    );
}
