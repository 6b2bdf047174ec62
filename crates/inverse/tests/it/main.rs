//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-inverse --test it <module>::`).

mod basis;
mod common;
mod fixed_inputs;
mod identifiability;
mod measured;
mod optimiser;
mod posterior;
mod recovery;
mod reduced;
mod rerun;
mod surrogate_adapter;
mod surrogate_recovery;
