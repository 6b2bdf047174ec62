//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid --test it <module>::`).

mod bad_inputs;
mod build_kill;
mod check;
mod cohort_kill;
mod common;
mod compare;
mod demo_installed;
mod fit;
mod full_disk;
mod fuzz_smoke;
mod helpers;
mod inspect_batch;
mod kill_anywhere;
mod material;
mod membrane;
mod one_cell;
mod proptest_parsers;
mod slurm_scripts;
mod surrogate_scale;
mod usability;
