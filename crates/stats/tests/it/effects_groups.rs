//! Effect sizes, Prony moduli, group curves and comparisons against hand
//! computations and second implementations written here.

use nlvid_model::{Prony, Relaxation};
use nlvid_stats::{
    Method, Used, cliffs_delta, compare_over_time, effect, group_curves, hodges_lehmann, mean_sd,
    rank_biserial, rank_sum, relaxation_amounts,
};

#[test]
fn effect_sizes_of_a_hand_counted_example() {
    // Pairs (x, y): (1,2)< (1,4)< (2,2)= (2,4)< (3,2)> (3,4)<  → 1 win, 4 losses, 1 tie.
    let (x, y) = ([1.0, 2.0, 3.0], [2.0, 4.0]);
    let e = effect(&x, &y).unwrap();
    assert_eq!(e.cliffs_delta, -0.5);
    assert_eq!(e.rank_biserial, -0.5);
    assert_eq!(e.superiority, 0.25);
    // Differences −1, −3, 0, −2, 1, −1 → sorted −3 −2 −1 −1 0 1 → median −1.
    assert_eq!(e.hodges_lehmann, -1.0);
}

#[test]
fn rank_biserial_from_ranks_equals_cliffs_delta_from_pairs() {
    // A deterministic pseudo-random sample with many ties (LCG, seed 7).
    let mut s: u64 = 7;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) % 9) as f64
    };
    for (n1, n2) in [(5, 7), (13, 11), (30, 2)] {
        let x: Vec<f64> = (0..n1).map(|_| next()).collect();
        let y: Vec<f64> = (0..n2).map(|_| next() + 1.0).collect();
        let r = rank_biserial(&x, &y).unwrap();
        let d = cliffs_delta(&x, &y).unwrap();
        assert!((r - d).abs() < 1e-14, "n1 = {n1}: r = {r}, δ = {d}");
    }
}

#[test]
fn hodges_lehmann_recovers_an_exact_shift() {
    let y = [0.3, 1.7, -0.4, 2.2, 0.9, 1.1];
    let x: Vec<f64> = y.iter().map(|v| v + 2.5).collect();
    assert!((hodges_lehmann(&x, &y).unwrap() - 2.5).abs() < 1e-12);
    assert!((hodges_lehmann(&[5.0], &[1.0, 2.0, 4.0]).unwrap() - 3.0).abs() < 1e-15);
}

fn thesis_cell(g0: f64, g1: f64, g2: f64) -> Relaxation {
    Prony::new("G", &[(g1, 0.5), (g2, 10.0)])
        .and_then(|p| Relaxation::new("G0", g0, p))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn prony_modulus_matches_eq_5_1_by_hand() {
    // G0 = 1 kPa, g1 = g2 = 0.3, τ1 = 0.5 s, τ2 = 10 s (issue 4's test cell).
    // The stats stage evaluates G(t) only through `nlvid_model::Relaxation`.
    let c = thesis_cell(1000.0, 0.3, 0.3);
    assert_eq!(c.value(0.0), 1000.0);
    assert!((c.g_inf() - 400.0).abs() < 1e-12);
    // t = 1 s: 0.4 + 0.3 e^-2 + 0.3 e^-0.1 = 0.4 + 0.04060058497098381 + 0.27145122541078785
    assert!((c.value(1.0) - 712.0518103817717).abs() < 1e-9);
    assert!((c.young(1.0) - 3.0 * 712.0518103817717).abs() < 1e-9);
    assert!((relaxation_amounts(&[c], 1e6)[0] - 0.6).abs() < 1e-12);
}

#[test]
fn mean_and_sample_sd_by_hand() {
    let m = mean_sd("v", &[1.0, 2.0, 3.0, 4.0]).unwrap();
    assert_eq!(m.mean, 2.5);
    assert!((m.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
    assert!(mean_sd("v", &[1.0]).is_err());
}

#[test]
fn group_curves_average_cells_and_scale_e_by_three() {
    let cells = [
        thesis_cell(3000.0, 0.3, 0.3),
        thesis_cell(2000.0, 0.2, 0.4),
        thesis_cell(2500.0, 0.25, 0.35),
    ];
    let times = [0.0, 1.0, 52.0];
    let g = group_curves("A", &cells, &times).unwrap();
    assert_eq!(g.n, 3);
    assert_eq!(g.shear[0].mean, 2500.0);
    assert!((g.shear[0].sd - 500.0).abs() < 1e-12);
    assert_eq!(g.normalised[0].mean, 1.0);
    assert_eq!(g.normalised[0].sd, 0.0);
    for (i, &t) in times.iter().enumerate() {
        assert!((g.young[i].mean - 3.0 * g.shear[i].mean).abs() < 1e-9);
        assert!((g.young[i].sd - 3.0 * g.shear[i].sd).abs() < 1e-9);
        // Independent: eq. 5.1 typed here (τ1 = 0.5 s, τ2 = 10 s).
        let by_hand = |g0: f64, g1: f64, g2: f64| {
            g0 * (1.0 - g1 - g2 + g1 * (-t / 0.5f64).exp() + g2 * (-t / 10.0f64).exp())
        };
        let direct =
            (by_hand(3000.0, 0.3, 0.3) + by_hand(2000.0, 0.2, 0.4) + by_hand(2500.0, 0.25, 0.35))
                / 3.0;
        assert!((g.shear[i].mean - direct).abs() < 1e-9);
    }
    assert!(group_curves("B", &cells[..1], &times).is_err());
}

#[test]
fn comparison_over_time_tests_g_and_normalised_g_at_each_time() {
    let a: Vec<Relaxation> = (0..12)
        .map(|i| thesis_cell(2500.0 + 100.0 * i as f64, 0.3, 0.25 + 0.01 * i as f64))
        .collect();
    let b: Vec<Relaxation> = (0..12)
        .map(|i| thesis_cell(1800.0 + 90.0 * i as f64, 0.35, 0.4 + 0.01 * i as f64))
        .collect();
    let times = [0.0, 5.0, 52.0];
    let cmp = compare_over_time(&a, &b, &times, Method::MATLAB_RANKSUM).unwrap();
    // t = 0: every G/G0 is 1 → all tied → p = 1.
    assert_eq!(cmp[0].normalised.p, 1.0);
    for (k, &t) in times.iter().enumerate() {
        let ga: Vec<f64> = a.iter().map(|c| c.value(t)).collect();
        let gb: Vec<f64> = b.iter().map(|c| c.value(t)).collect();
        let direct = rank_sum(&ga, &gb, Method::MATLAB_RANKSUM).unwrap();
        assert_eq!(cmp[k].shear.p, direct.p);
        assert!(matches!(cmp[k].shear.used, Used::Asymptotic { .. }));
    }
    // The relaxation-amount test is the test of G/G0 at that time.
    let ra = relaxation_amounts(&a, 52.0);
    let rb = relaxation_amounts(&b, 52.0);
    let r = rank_sum(&ra, &rb, Method::MATLAB_RANKSUM).unwrap();
    assert!((r.p - cmp[2].normalised.p).abs() < 1e-15);
    assert!(cmp[2].normalised.p < 1e-4);
    assert!(cmp[2].shear_effect.rank_biserial > 0.9);
}
