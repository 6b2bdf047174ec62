//! Embeds the bundled example `examples/demo/` in the binary, so an
//! installed `nlvid demo` needs no source tree: writes
//! `$OUT_DIR/demo_files.rs`, one `(relative path, include_bytes!(…))` per
//! file, read by `src/embedded_demo.rs` (the one place that says which
//! files are embedded: every file under `examples/demo/` except the
//! regeneration script's scratch folder `work/`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Files larger than this are not embedded: `nlvid demo` then says where it
/// looked for them (keeps a large meta-model out of the binary by choice).
const MAX_EMBEDDED_BYTES: u64 = 32 << 20;

fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, PathBuf, u64)>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = rd.filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        let rel = p
            .strip_prefix(root)
            .map(|r| r.to_string_lossy().replace('\\', "/"))
            .unwrap_or_default();
        if p.is_dir() {
            if rel != "work" {
                walk(root, &p, out);
            }
        } else if let Ok(m) = p.metadata() {
            out.push((rel, p, m.len()));
        }
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    let demo = manifest.join("../../examples/demo");
    let demo = demo.canonicalize().unwrap_or(demo);
    println!("cargo:rerun-if-changed={}", demo.display());
    let mut files = Vec::new();
    walk(&demo, &demo, &mut files);
    let mut code = String::from(
        "/// Embedded files of examples/demo: (path relative to the demo folder, bytes).\n\
         pub const FILES: &[(&str, &[u8])] = &[\n",
    );
    let mut skipped = String::from(
        "/// Files of examples/demo too large to embed: (path, size in bytes).\n\
         pub const NOT_EMBEDDED: &[(&str, u64)] = &[\n",
    );
    for (rel, path, len) in &files {
        println!("cargo:rerun-if-changed={}", path.display());
        if *len > MAX_EMBEDDED_BYTES {
            println!("cargo:warning=examples/demo/{rel} ({len} bytes) is not embedded");
            let _ = writeln!(skipped, "    ({rel:?}, {len}),");
        } else {
            let _ = writeln!(code, "    ({rel:?}, include_bytes!({path:?})),");
        }
    }
    code.push_str("];\n");
    skipped.push_str("];\n");
    code.push_str(&skipped);
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    if let Err(e) = std::fs::write(out.join("demo_files.rs"), code) {
        panic!("cannot write demo_files.rs into OUT_DIR: {e}");
    }
}
