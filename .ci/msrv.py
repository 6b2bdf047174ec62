#!/usr/bin/env python3
"""Checks that the workspace's `rust-version` is at least what every locked
dependency declares, so the README's Rust version really builds the lock.

Reads Cargo.lock and each registry package's Cargo.toml from cargo's
registry cache (run after a build or `cargo fetch --locked`). Exit 1 with
the offending packages when the workspace promises an older Rust.
"""
import glob
import os
import re
import sys


def version(text):
    parts = [int(x) for x in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    manifest = open(os.path.join(root, "Cargo.toml")).read()
    m = re.search(r'^rust-version\s*=\s*"([^"]+)"', manifest, re.M)
    if not m:
        print("Cargo.toml: no workspace rust-version")
        return 1
    promised = version(m.group(1))
    lock = open(os.path.join(root, "Cargo.lock")).read()
    packages = re.findall(
        r'\[\[package\]\]\nname = "([^"]+)"\nversion = "([^"]+)"\nsource = "registry', lock
    )
    home = os.environ.get("CARGO_HOME", os.path.expanduser("~/.cargo"))
    registries = glob.glob(os.path.join(home, "registry", "src", "*"))
    too_new, missing = [], 0
    for name, ver in packages:
        found = [p for r in registries for p in [os.path.join(r, f"{name}-{ver}", "Cargo.toml")] if os.path.exists(p)]
        if not found:
            missing += 1
            continue
        n = re.search(r'^rust-version\s*=\s*"([^"]+)"', open(found[0]).read(), re.M)
        if n and version(n.group(1)) > promised:
            too_new.append(f"{name} {ver} needs Rust {n.group(1)}")
    if missing:
        print(f"msrv: {missing} of {len(packages)} locked packages not in the registry cache; run `cargo fetch --locked` first")
        return 1
    if too_new:
        print(f"msrv: Cargo.toml promises Rust {m.group(1)}, but:")
        print("\n".join("  " + t for t in too_new))
        return 1
    print(f"msrv: all {len(packages)} locked packages build with Rust {m.group(1)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
