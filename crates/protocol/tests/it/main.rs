//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-protocol --test it <module>::`).

mod programs;
mod section;
mod table;
