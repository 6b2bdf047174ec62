//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-membrane --test it <module>::`).

mod elastic;
#[path = "../common/reference_pr.rs"]
mod reference_pr;
mod table_2_1;
mod unloading;
mod visco;
