//! Every integration test of this crate, one module per topic, built as
//! one binary: one link instead of one per file, and the test harness
//! keeps both cores busy across topics (run one topic with
//! `cargo test -p nlvid-fem --test it <module>::`).

mod afm;
mod capsule;
mod cavity;
mod common;
mod contact;
mod element;
mod membrane;
mod outputs;
mod plates;
mod solid;
