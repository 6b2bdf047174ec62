use nlvid_membrane::{Control, Geometry, MembraneSolver, PipkinRogersParams};
#[test]
fn explore_visco() {
    let p = PipkinRogersParams { g1: 0.2, g2: 0.3, c: 1.0, gamma0: 0.1, ..Default::default() };
    let m = p.check().unwrap();
    let mut s = MembraneSolver::new(m, Geometry { rs: 1.03, nodes: 96 }, 1.0).unwrap();
    let t0 = std::time::Instant::now();
    let n = 100;
    let mut last = None;
    for k in 0..=n {
        let t = 10.0 * k as f64 / n as f64;
        let sol = s.advance(t, Control::Displacement(0.78)).unwrap();
        if k % 10 == 0 {
            eprintln!("t {t:.2} F {:.4} psic {:.5} ({:.2}) ang {:.2} it {}", sol.force, sol.psi_c, sol.psi_c.to_degrees(), sol.current_contact_angle_deg(), sol.iterations);
        }
        last = Some(sol);
    }
    let sol = last.unwrap();
    eprintln!("crown l2 {:.5} edge l2 {:.5} elapsed {:?}", sol.profile[0].lambda2, sol.profile.last().unwrap().lambda2, t0.elapsed());
}
