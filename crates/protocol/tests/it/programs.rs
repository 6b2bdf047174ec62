//! Loading programs against hand-computed values.

use nlvid_protocol::{
    AfmScript, Cantilever, Label, Leg, ProgramBuilder, ProtocolError, Quantity, grid, indentation,
    programs,
};

const UM: f64 = 1e-6;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn assert_all_close(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len(), "got {got:?}, want {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(close(*g, *w, tol), "got {got:?}, want {want:?}");
    }
}

#[test]
fn afm_ch5_piezo_breakpoints_and_values_match_hand_computation() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    // 2 µm at 10 µm/s = 0.2 s; 1 µm back = 0.1 s; 1 µm at 5 µm/s = 0.2 s
    // each way; 1 µm at 1 µm/s = 1 s each way; 1 µm at 10 µm/s = 0.1 s; 50 s.
    let want_t = [0.0, 0.2, 0.3, 0.5, 0.7, 1.7, 2.7, 2.8, 52.8];
    let want_z = [0.0, 2.0, 1.0, 2.0, 1.0, 2.0, 1.0, 2.0, 2.0];
    let bps = z.breakpoints();
    assert_all_close(bps, &want_t, 1e-12);
    for (t, zz) in bps.iter().zip(want_z) {
        assert!(close(z.value(*t), zz * UM, 1e-18), "Z({t})");
    }
    assert!(close(z.duration(), 52.8, 1e-12));
    // Mid-segment values and rates.
    assert!(close(z.value(0.25), 1.5 * UM, 1e-18));
    assert!(close(z.value(1.2), 1.5 * UM, 1e-18));
    assert!(close(z.value(30.0), 2.0 * UM, 1e-18));
    assert!(close(z.rate(0.25), -10.0 * UM, 1e-15));
    assert!(close(z.rate(0.6), -5.0 * UM, 1e-15));
    assert!(close(z.rate(2.75), 10.0 * UM, 1e-15));
    assert_eq!(z.rate(10.0), 0.0);
    // At a kink: right and left derivatives differ.
    assert!(close(z.rate(bps[1]), -10.0 * UM, 1e-15));
    assert!(close(z.rate_left(bps[1]), 10.0 * UM, 1e-15));
}

#[test]
fn afm_segment_labels_name_cycle_leg_ramp_and_hold() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    let rr = |cycle, leg| Label::RampReverse { cycle, leg };
    assert_eq!(z.label(0.1), rr(1, Leg::Load));
    assert_eq!(z.label(0.25), rr(1, Leg::Unload));
    assert_eq!(z.label(0.4), rr(2, Leg::Load));
    assert_eq!(z.label(0.6), rr(2, Leg::Unload));
    assert_eq!(z.label(1.0), rr(3, Leg::Load));
    assert_eq!(z.label(2.0), rr(3, Leg::Unload));
    assert_eq!(z.label(2.75), Label::Ramp);
    assert_eq!(z.label(10.0), Label::Hold);
    assert_eq!(
        rr(2, Leg::Unload).to_string(),
        "ramp-reverse cycle 2 reverse"
    );
}

#[test]
fn afm_app_a_script_uses_3um_and_15s_engage_hold() {
    let s = AfmScript::thesis_app_a(0.072).unwrap();
    let z = s.piezo().unwrap();
    // 3 µm at 10 → 0.3 s, back 1 µm 0.1 s; 2↔3 µm at 5 → 0.2 s; at 1 → 1 s.
    let want_t = [0.0, 0.3, 0.4, 0.6, 0.8, 1.8, 2.8, 2.9, 52.9];
    assert_all_close(z.breakpoints(), &want_t, 1e-12);
    assert!(close(z.value(0.8), 2.0 * UM, 1e-18));
    // Step 1: δd = 5 nm at 1 nm/s on k = 0.072 N/m → 0.36 nN over 5 s, hold 15 s.
    let f = s.engage_program().unwrap();
    assert!(close(s.engage.setpoint_force, 0.36e-9, 1e-21));
    assert_all_close(f.breakpoints(), &[0.0, 5.0, 20.0], 1e-12);
    assert!(close(f.value(2.5), 0.18e-9, 1e-21));
    assert_eq!(f.label(10.0), Label::EngageHold);
    assert_eq!(f.quantity(), Quantity::Force);
    assert!(close(s.engage_duration(), 20.0, 1e-12));
}

#[test]
fn next_breakpoint_keeps_a_stepper_on_every_kink() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    let mut t = 0.0;
    let mut visited = vec![0.0];
    while t < z.end() {
        let dt = 0.07;
        match z.next_breakpoint(t) {
            Some(bp) if t + dt >= bp => {
                t = bp;
                visited.push(bp);
            }
            _ => t += dt,
        }
    }
    assert_eq!(visited, z.breakpoints());
    assert_eq!(z.next_breakpoint(z.end()), None);
}

#[test]
fn step_is_a_right_continuous_jump() {
    let p = programs::step(Quantity::Dimensionless, 0.78, 10.0).unwrap();
    assert_eq!(p.value_left(0.0), 0.0);
    assert_eq!(p.value(0.0), 0.78);
    assert_eq!(p.value(-1.0), 0.0);
    assert_eq!(p.value(5.0), 0.78);
    assert_eq!(p.jumps(), vec![0.0]);
    assert_eq!(p.breakpoints(), vec![0.0, 10.0]);
    assert_eq!(p.label(0.0), Label::Hold);
}

#[test]
fn jump_inside_a_program_has_distinct_left_and_right_values() {
    let p = ProgramBuilder::new(Quantity::Displacement, 0.0)
        .ramp_to(1.0, 1.0, Label::Ramp)
        .unwrap()
        .jump_to(3.0)
        .unwrap()
        .hold(1.0, Label::Hold)
        .unwrap()
        .build()
        .unwrap();
    assert_eq!(p.value_left(1.0), 1.0);
    assert_eq!(p.value(1.0), 3.0);
    assert_eq!(p.rate_left(1.0), 1.0);
    assert_eq!(p.rate(1.0), 0.0);
    assert_eq!(p.breakpoints(), vec![0.0, 1.0, 2.0]);
    assert_eq!(p.value_range(), (0.0, 3.0));
}

#[test]
fn constant_rate_ramp_hold_and_load_unload_match_closed_forms() {
    let c = programs::constant_rate(Quantity::Dimensionless, 0.5, 4.0).unwrap();
    for t in [0.0, 0.3, 1.7, 4.0] {
        assert!(close(c.value(t), 0.5 * t, 1e-15));
        if t < 4.0 {
            assert_eq!(c.rate(t), 0.5);
        }
    }
    let rh = programs::ramp_hold(Quantity::Displacement, 1.5e-3, 0.2e-3, 20.0).unwrap();
    assert_all_close(rh.breakpoints(), &[0.0, 7.5, 27.5], 1e-12);
    assert!(close(rh.value(3.0), 0.6e-3, 1e-15));
    // Fig. 2.14: D/r0 = 0.78 at s_l = 1, unloading at s_u = 1/5.
    let lu = programs::load_unload(Quantity::Dimensionless, 0.78, 1.0, 0.2, 0.0).unwrap();
    assert_all_close(lu.breakpoints(), &[0.0, 0.78, 0.78 + 3.9], 1e-12);
    assert!(close(lu.value(0.78 + 1.0), 0.78 - 0.2, 1e-12));
    assert_eq!(lu.label(0.5), Label::Load);
    assert_eq!(lu.label(1.0), Label::Unload);
    let rr = programs::ramp_reverse(Quantity::Displacement, 1e-3, 0.2e-3, 0.0).unwrap();
    assert_all_close(rr.breakpoints(), &[0.0, 5.0, 10.0], 1e-12);
}

#[test]
fn cantilever_force_and_indentation_follow_section_5_2_2() {
    let c = Cantilever::new(0.12).unwrap();
    // 4 nm deflection on 0.12 N/m → 0.48 nN; a 2 µm piezo travel with 50 nm
    // deflection indents 1.95 µm.
    assert!(close(c.force(4e-9), 0.48e-9, 1e-22));
    assert!(close(c.deflection(0.48e-9), 4e-9, 1e-22));
    assert!(close(indentation(2e-6, 50e-9), 1.95e-6, 1e-20));
    assert!(close(c.indentation_from_force(2e-6, 6e-9), 1.95e-6, 1e-20));
    assert!(matches!(
        Cantilever::new(0.0),
        Err(ProtocolError::Parameter { name: "k", .. })
    ));
}

#[test]
fn invalid_script_parameters_are_named() {
    let mut s = AfmScript::thesis_ch5(0.12).unwrap();
    s.retract = 3e-6;
    let e = s.piezo().unwrap_err().to_string();
    assert!(e.contains("retract"), "{e}");
    let mut s = AfmScript::thesis_ch5(0.12).unwrap();
    s.cycle_rates[1] = 0.0;
    let e = s.piezo().unwrap_err().to_string();
    assert!(e.contains("cycle rate"), "{e}");
    let mut s = AfmScript::thesis_ch5(0.12).unwrap();
    s.hold = f64::NAN;
    assert!(s.piezo().is_err());
    assert!(ProgramBuilder::new(Quantity::Force, 0.0).build().is_err());
}

#[test]
fn uniform_grid_has_exact_ends_and_constant_spacing() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    let g = z.uniform_grid(5095).unwrap();
    assert_eq!(g.len(), 5095);
    assert_eq!(g[0], 0.0);
    assert_eq!(g[5094], z.end());
    let h = z.end() / 5094.0;
    for w in g.windows(2) {
        assert!(close(w[1] - w[0], h, 1e-12));
    }
    assert!(grid::uniform(0.0, 1.0, 1).is_err());
    assert!(grid::uniform(1.0, 1.0, 10).is_err());
}

fn check_grid_contains_breakpoints(g: &[f64], bps: &[f64], max_dt: f64) {
    for w in g.windows(2) {
        assert!(w[1] > w[0], "grid not increasing at {w:?}");
        assert!(
            w[1] - w[0] <= max_dt * (1.0 + 1e-12),
            "step {w:?} > {max_dt}"
        );
    }
    for b in bps {
        assert!(g.contains(b), "breakpoint {b} missing");
    }
}

#[test]
fn stepper_grid_hits_every_breakpoint_with_steps_at_most_max_dt() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    let g = z.stepper_grid(0.05).unwrap();
    check_grid_contains_breakpoints(&g, z.breakpoints(), 0.05);
    // 0.2/0.05 = 4, 0.1 → 2, 0.2 → 4, 0.2 → 4, 1 → 20, 1 → 20, 0.1 → 2, 50 → 1000.
    assert_eq!(g.len(), 1 + 4 + 2 + 4 + 4 + 20 + 20 + 2 + 1000);
}

#[test]
fn refined_grid_is_fine_at_breakpoints_and_coarse_inside() {
    let z = AfmScript::thesis_ch5(0.12).unwrap().piezo().unwrap();
    let (min_dt, max_dt) = (1e-3, 0.5);
    let g = z.refined_grid(min_dt, max_dt, 1.2).unwrap();
    let bps = z.breakpoints();
    check_grid_contains_breakpoints(&g, bps, max_dt);
    for b in bps {
        let i = g.iter().position(|x| x == b).unwrap();
        if i + 1 < g.len() {
            assert!(g[i + 1] - g[i] <= min_dt * (1.0 + 1e-12));
        }
        if i > 0 {
            assert!(g[i] - g[i - 1] <= min_dt * (1.0 + 1e-12));
        }
    }
    // The 50 s hold reaches the coarse spacing in its middle.
    let mid = g.iter().position(|&t| t > 27.8).unwrap();
    assert!(g[mid] - g[mid - 1] > 0.4);
    // Geometric sums give ≈ 450 points (≈ 157 in the hold); a uniform grid
    // at min_dt would need 52 800.
    assert!(g.len() < 600, "{} points", g.len());
}
