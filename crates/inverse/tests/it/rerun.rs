//! `rerun` with a real `ForwardModel` whose time grid differs from the
//! fit's: `nlvid_forward::HertzProny` (the Lee–Radok kernel in its exact
//! ramp-hold form, grid (0, 10] s) against this crate's `LeeRadokHertz`
//! (the kernel's recursion for a piecewise-linear δ^{3/2} on a 1-ms grid) —
//! two evaluations of the same physics, both in the order G0, g1, g2, tau1,
//! tau2.

use nlvid_forward::HertzProny;
use nlvid_inverse::{ForwardFromModel, LeeRadokHertz, Model, range_normalised_rmse, rerun};
use nlvid_model::{Domain, ForwardModel};

#[test]
fn rerun_of_hertz_prony_matches_lee_radok_on_the_data_grid() {
    let domain = Domain::table_5_3(0.01).unwrap();
    // G0, g1, g2, tau1, tau2.
    let x = [1200.0, 0.35, 0.3, 0.3, 6.0];
    let (radius, rate, ramp, end) = (5e-6, 1e-6, 1.0, 10.0);
    let hp = HertzProny::new(radius, rate, ramp, end, 100).unwrap();

    // Lee–Radok on a fine grid from rest (dt = 1 ms).
    let fine: Vec<f64> = (0..=10_000).map(|i| i as f64 * 1e-3).collect();
    let delta: Vec<f64> = fine.iter().map(|t| rate * t.min(ramp)).collect();
    let lr = LeeRadokHertz::new(domain.clone(), fine.clone(), &delta, radius, 0.5).unwrap();
    let reference = lr.response(&x).unwrap();
    // Reference sampled on the HertzProny grid (every 100th fine point).
    let grid = hp.time_grid().to_vec();
    let data: Vec<f64> = grid
        .iter()
        .map(|t| reference[(t / 1e-3).round() as usize])
        .collect();

    let r = rerun(&hp, &domain, &x, &grid, &data, None).unwrap();
    let peak = data.iter().copied().fold(0.0, f64::max);
    for (j, (a, b)) in r.response.iter().zip(&data).enumerate() {
        assert!(
            (a - b).abs() < 2e-3 * peak,
            "t = {}: {a:e} vs {b:e}",
            grid[j]
        );
    }
    assert!(r.misfit < 1e-3, "misfit {}", r.misfit);
    assert_eq!(
        r.misfit,
        range_normalised_rmse(&r.response, &data, None).unwrap()
    );

    // The same model through the adapter in the domain's own order, on the
    // fine grid, interpolated onto the coarse one: equals the reference.
    let adapter = ForwardFromModel {
        model: lr,
        identity: "lee-radok".into(),
    };
    let r2 = rerun(&adapter, &domain, &x, &grid, &data, None).unwrap();
    assert!(r2.misfit < 1e-12, "misfit {}", r2.misfit);
}
