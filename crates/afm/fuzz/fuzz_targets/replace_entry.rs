//! Structured fuzzing past the ZIP checksums: the input replaces one entry (chosen by
//! its first byte) of a real JPK file, which is then re-packed (stored) and read. This
//! drives arbitrary text into the properties parser / header logic and arbitrary bytes
//! into the channel decoder. Must never panic.
#![no_main]

use std::io::{Cursor, Read, Write};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use nlvid_afm::{ReadOptions, read_jpk_bytes};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipArchive, ZipWriter};

static SR: &[u8] = include_bytes!("../../tests/data/fmt-jpk-sr_cell1-0008.jpk-force");
static FD: &[u8] = include_bytes!("../../tests/data/fmt-jpk-fd_spot3-0192.jpk-force");

fn entries(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let Ok(mut zip) = ZipArchive::new(Cursor::new(bytes)) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for i in 0..zip.len() {
        if let Ok(mut f) = zip.by_index(i) {
            let mut buf = Vec::new();
            if f.read_to_end(&mut buf).is_ok() {
                out.push((f.name().to_string(), buf));
            }
        }
    }
    out
}

fuzz_target!(|data: &[u8]| {
    let Some((&sel, content)) = data.split_first() else {
        return;
    };
    static CACHE: OnceLock<[Vec<(String, Vec<u8>)>; 2]> = OnceLock::new();
    let files = CACHE.get_or_init(|| {
        let files = |src| {
            entries(src)
                .into_iter()
                .filter(|(n, _)| !n.ends_with('/'))
                .collect()
        };
        [files(SR), files(FD)]
    });
    let mut e = files[usize::from(sel >> 7)].clone();
    if e.is_empty() {
        return;
    }
    let k = usize::from(sel & 0x7f) % e.len();
    e[k].1 = content.to_vec();
    let mut w = ZipWriter::new(Cursor::new(Vec::new()));
    let opts = SimpleFileOptions::default().compression_method(CompressionMethod::Stored);
    for (n, d) in &e {
        if w.start_file(n.as_str(), opts).is_err() || w.write_all(d).is_err() {
            return;
        }
    }
    let Ok(out) = w.finish() else { return };
    let _ = read_jpk_bytes(&out.into_inner(), "fuzz", &ReadOptions::default());
});
