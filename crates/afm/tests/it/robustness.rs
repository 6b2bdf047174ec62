//! Seeded random damage to the real files (byte flips, cuts, splices, in both the
//! deflated originals and stored re-packs): the reader returns curves or a typed error,
//! never panics. Complements the cargo-fuzz target in crates/afm/fuzz.

use crate::common;

use common::*;
use nlvid_afm::{ReadOptions, read_jpk_bytes};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn mutate(rng: &mut ChaCha8Rng, src: &[u8]) -> Vec<u8> {
    let mut b = src.to_vec();
    match rng.random_range(0..4u8) {
        0 => {
            for _ in 0..rng.random_range(1..8usize) {
                let i = rng.random_range(0..b.len());
                b[i] ^= 1 << rng.random_range(0..8u32);
            }
        }
        1 => b.truncate(rng.random_range(0..b.len())),
        2 => {
            let i = rng.random_range(0..b.len());
            let n = rng.random_range(1..64usize).min(b.len() - i);
            b.drain(i..i + n);
        }
        _ => {
            let i = rng.random_range(0..b.len());
            let j = rng.random_range(0..b.len());
            let n = rng.random_range(1..256usize).min(b.len() - i.max(j));
            let chunk = b[j..j + n].to_vec();
            b[i..i + n].copy_from_slice(&chunk);
        }
    }
    b
}

#[test]
fn randomly_damaged_real_files_never_panic() {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let mut inputs = Vec::new();
    for p in [SR, FD] {
        let bytes = std::fs::read(p).expect("read");
        inputs.push(zip_of(&entries(&bytes), true));
        inputs.push(bytes);
    }
    let (mut ok, mut err) = (0, 0);
    for round in 0..400 {
        let src = &inputs[round % inputs.len()];
        let damaged = mutate(&mut rng, src);
        match read_jpk_bytes(&damaged, "damaged", &ReadOptions::default()) {
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(!e.to_string().is_empty());
                err += 1;
            }
        }
    }
    // most damage must be detected (CRC, structure); some flips land in unused bytes
    assert!(err > 200, "ok {ok}, err {err}");
}

#[test]
fn damaged_headers_of_maps_with_shared_references_never_panic() {
    // QI map and QI series with a header damaged before re-packing: the damage passes
    // the CRC and reaches the properties parser, the shared references and the raster
    // channels.
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let mut inputs = Vec::new();
    for name in [QI_DATA, QI_SERIES] {
        let bytes = std::fs::read(data(name)).expect("read");
        let e: Vec<_> = entries(&bytes)
            .into_iter()
            .filter(|(n, _)| n.ends_with(".properties"))
            .collect();
        inputs.push((bytes, e));
    }
    let mut failed = 0;
    for round in 0..200 {
        let (bytes, headers) = &inputs[round % 2];
        let (name, text) = &headers[(round / 2) % headers.len()];
        let new = mutate(&mut rng, text);
        let damaged = with_entry(bytes, name, |_| new.clone());
        // every curve's own result, never a panic
        match nlvid_afm::read_jpk_each(&damaged, "damaged", &ReadOptions::default()) {
            Ok(curves) => {
                for (_, c) in curves {
                    if let Err(e) = c {
                        assert!(!e.to_string().is_empty());
                        failed += 1;
                    }
                }
            }
            Err(_) => failed += 1,
        }
    }
    assert!(failed > 50, "only {failed} of 200 damaged headers detected");
}
