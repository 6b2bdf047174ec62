//! CPU-time check of the Fig. 2.6 relaxation run (the criterion bench's case)
//! for the `nlvid-material` adapter (`adapter`) or the session-1 principal
//! form (`reference`): `/usr/bin/time -f %U cargo run --release -p
//! nlvid-membrane --example bench_cpu -- adapter 10` and divide by the runs.
use nlvid_membrane::{ControlKind, Geometry, Loading, PipkinRogersParams, simulate, simulate_with};
use nlvid_protocol::{Quantity, programs};

#[path = "../tests/common/reference_pr.rs"]
mod reference_pr;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("adapter");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let p = PipkinRogersParams::chapter2(0.2, 0.3, 0.5);
    for d in [0.53, 0.78] {
        let prog = programs::step(Quantity::Dimensionless, d, 10.0)?;
        let times = (0..=100).map(|k| 0.1 * k as f64).collect();
        let l = Loading::new(ControlKind::Displacement, prog, times)?;
        for _ in 0..n {
            let r = if which == "reference" {
                simulate_with(
                    reference_pr::PipkinRogersMembrane { p },
                    1.0,
                    &Geometry::default(),
                    &l,
                )?
            } else {
                simulate(&p, &Geometry::default(), &l)?
            };
            std::hint::black_box(r);
        }
    }
    Ok(())
}
