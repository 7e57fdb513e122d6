//! Design methods: size, range, determinism, extension, and seed 004's ranking in 10-D.

use mbgc::sampling::metrics::mid;
use mbgc::sampling::{extend_design, lhs::Lhs, Method, Points};

fn one_shot(m: Method, d: usize, n: usize, seed: u64) -> Points {
    extend_design(m.sampler().as_ref(), &Points::new(d), n, seed).unwrap()
}

#[test]
fn every_method_gives_n_points_in_the_cube_reproducibly() {
    for m in Method::ALL {
        let a = one_shot(m, 3, 40, 7);
        let b = one_shot(m, 3, 40, 7);
        let c = one_shot(m, 3, 40, 8);
        assert_eq!(a.len(), 40, "{}", m.name());
        assert!(
            a.as_flat()
                .iter()
                .all(|v| (0.0..1.0).contains(v) || *v == 1.0),
            "{}",
            m.name()
        );
        assert_eq!(a, b, "{}: same seed must give the same design", m.name());
        assert_ne!(a, c, "{}: another seed must give another design", m.name());
    }
}

#[test]
fn sequences_continue_their_own_prefix_exactly() {
    for m in [Method::Sobol, Method::Halton, Method::Random] {
        let s = m.sampler();
        let first = one_shot(m, 4, 30, 3);
        let more = extend_design(s.as_ref(), &first, 20, 3).unwrap();
        let mut joined = first.clone();
        joined.append(&more);
        assert_eq!(joined, one_shot(m, 4, 50, 3), "{}", m.name());
    }
}

/// Mean MID over seeds of 50 + 50 points against one-shot designs of 100, for a base from the
/// method itself and a foreign base (maximin LHS of another seed). New points cannot move old
/// ones apart, so the target is the smaller of the one-shot MID and the base's MID.
fn extension_ratio(m: Method, d: usize, foreign: bool) -> f64 {
    let seeds = 1..=5u64;
    let (mut ext, mut target) = (0.0, 0.0);
    for s in seeds {
        let base = if foreign {
            extend_design(&Lhs::maximin(), &Points::new(d), 50, s + 100).unwrap()
        } else {
            one_shot(m, d, 50, s)
        };
        let new = extend_design(m.sampler().as_ref(), &base, 50, s).unwrap();
        let mut all = base.clone();
        all.append(&new);
        // The old points stay first, unchanged and in order.
        assert_eq!(&all.as_flat()[..base.as_flat().len()], base.as_flat());
        ext += mid(&all);
        target += mid(&one_shot(m, d, 100, s)).min(mid(&base));
    }
    ext / target
}

#[test]
fn extended_designs_are_as_space_filling_as_one_shot_designs() {
    for m in [
        Method::FssfF,
        Method::FssfFr,
        Method::Mipt,
        Method::Sobol,
        Method::Halton,
    ] {
        for d in [2, 10] {
            for foreign in [false, true] {
                let r = extension_ratio(m, d, foreign);
                assert!(
                    r >= 0.9,
                    "{} {d}-D foreign={foreign}: MID ratio {r:.3}",
                    m.name()
                );
            }
        }
    }
}

#[test]
fn one_shot_methods_refuse_to_extend() {
    let base = one_shot(Method::Random, 2, 10, 1);
    for m in [Method::Lhs, Method::LhsMaximin] {
        let e = extend_design(m.sampler().as_ref(), &base, 5, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("one-shot"), "{e}");
    }
}

#[test]
fn sobol_refuses_more_points_than_its_index_allows() {
    let e = extend_design(Method::Sobol.sampler().as_ref(), &Points::new(2), 70_000, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("65536"), "{e}");
}

/// Seed 004, Figs. 7-8: FSSF-f has the largest MID of the sequential methods in 10-D, and MIPT
/// falls far behind it there while it is close to FSSF-f in 2-D.
#[test]
fn seed004_ranking_in_ten_dimensions() {
    let mean_mid =
        |m: Method, d: usize| (1..=4).map(|s| mid(&one_shot(m, d, 100, s))).sum::<f64>() / 4.0;
    let fssf = mean_mid(Method::FssfF, 10);
    for m in [
        Method::Mipt,
        Method::Sobol,
        Method::Halton,
        Method::Random,
        Method::FssfFr,
    ] {
        assert!(fssf > mean_mid(m, 10), "fssf-f {fssf} vs {}", m.name());
    }
    let mipt_10 = mean_mid(Method::Mipt, 10) / fssf;
    assert!(mipt_10 < 0.6, "MIPT/FSSF-f in 10-D {mipt_10}");
    let mipt_2 = mean_mid(Method::Mipt, 2) / mean_mid(Method::FssfF, 2);
    assert!(mipt_2 > 0.8, "MIPT/FSSF-f in 2-D {mipt_2}");
}
