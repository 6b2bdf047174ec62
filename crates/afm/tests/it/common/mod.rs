//! Shared helpers for the integration tests: paths to the real JPK files and a ZIP
//! rewriter that builds damaged or altered copies of them.
#![allow(dead_code)]

use std::io::{Cursor, Read, Write};

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

/// Ramp-hold stress relaxation on a living cell (JPK format 2.0).
pub const SR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/fmt-jpk-sr_cell1-0008.jpk-force"
);
/// Approach/retract force–distance curve (JPK format 0.12).
pub const FD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/fmt-jpk-fd_spot3-0192.jpk-force"
);

/// All entries (name, bytes) of a ZIP archive, in archive order.
pub fn entries(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut zip = ZipArchive::new(Cursor::new(bytes)).expect("test input is a zip");
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).expect("entry");
        let mut buf = Vec::new();
        f.read_to_end(&mut buf).expect("entry bytes");
        out.push((f.name().to_string(), buf));
    }
    out
}

/// Write entries back into a ZIP archive (stored, i.e. uncompressed, if `stored`).
pub fn zip_of(entries: &[(String, Vec<u8>)], stored: bool) -> Vec<u8> {
    let mut w = ZipWriter::new(Cursor::new(Vec::new()));
    let method = if stored {
        CompressionMethod::Stored
    } else {
        CompressionMethod::Deflated
    };
    let opts = SimpleFileOptions::default().compression_method(method);
    for (name, data) in entries {
        if name.ends_with('/') {
            w.add_directory(name.trim_end_matches('/'), opts)
                .expect("dir");
        } else {
            w.start_file(name.as_str(), opts).expect("start");
            w.write_all(data).expect("write");
        }
    }
    w.finish().expect("finish").into_inner()
}

/// Copy of `bytes` with entry `name` replaced by `f(old)`.
pub fn with_entry(bytes: &[u8], name: &str, f: impl Fn(&[u8]) -> Vec<u8>) -> Vec<u8> {
    let mut e = entries(bytes);
    let mut found = false;
    for (n, d) in &mut e {
        if n == name {
            *d = f(d);
            found = true;
        }
    }
    assert!(found, "entry {name} not in archive");
    zip_of(&e, false)
}

/// Copy of `bytes` with text `from` replaced by `to` in entry `name`.
pub fn with_text(bytes: &[u8], name: &str, from: &str, to: &str) -> Vec<u8> {
    with_entry(bytes, name, |d| {
        let s = String::from_utf8_lossy(d);
        assert!(s.contains(from), "'{from}' not in {name}");
        s.replace(from, to).into_bytes()
    })
}

/// Relative difference |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// Arithmetic mean.
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Path of a file in tests/data.
pub fn data(name: &str) -> String {
    format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Force map, 2×2 curves extracted from a 10×10 grid (format 2.0, segment settings in
/// the shared header).
pub const MAP: &str = "fmt-jpk-fd_map2x2_extracted.jpk-force-map";
/// QI map, 4 curves.
pub const QI_DATA: &str = "fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data";
/// One QI curve, with computed (raster) time channels.
pub const QI_SERIES: &str = "fmt-jpk-fd_qi-data-2021.04.13.jpk-qi-series";
/// A curve extracted from a map: the curve header stands in for the file header.
pub const EXTRACTED: &str = "fmt-jpk-fd_flipsign_2015.05.22-15.31.49.352.jpk-force";
/// Creep compliance: extend, constant-force pause, retract.
pub const CREEP: &str = "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force";
/// The 15 ramp-hold curves of Battistella et al. 2022, fig. 5d, as published (a ZIP of
/// `.jpk-force` files).
pub const FIG5D: &str = "10.1002_btm2.10294_fig5d-cell1.zip";

/// The curves of the fig. 5d archive: (file name, bytes), in name order.
pub fn fig5d() -> Vec<(String, Vec<u8>)> {
    let bytes = std::fs::read(data(FIG5D)).expect("fig5d archive");
    let mut e: Vec<_> = entries(&bytes)
        .into_iter()
        .filter(|(n, _)| n.ends_with(".jpk-force"))
        .collect();
    e.sort();
    e
}

/// A standard normal deviate (Box–Muller) from `rng`.
pub fn gauss(rng: &mut impl rand::RngExt) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
