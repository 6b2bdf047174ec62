//! Fuzz the JPK reader: any bytes must give curves or a typed error, never a panic,
//! hang or out-of-memory. Seed the corpus with the real files (see docs/theory/afm.md).
#![no_main]

use libfuzzer_sys::fuzz_target;
use nlvid_afm::{ReadOptions, read_jpk_bytes};

fuzz_target!(|data: &[u8]| {
    if let Ok(curves) = read_jpk_bytes(data, "fuzz", &ReadOptions::default()) {
        // exercise the accessors on whatever decoded
        for c in &curves {
            for s in &c.segments {
                let _ = s.force();
                let _ = s.height();
            }
        }
    }
});
