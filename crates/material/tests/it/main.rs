//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-material --test it <module>::`).

mod axisymmetric;
mod common;
mod hyperelastic;
mod pipkin_rogers;
mod prony_viscoelastic;
mod study_sections;
mod tangents;
