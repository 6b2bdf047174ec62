#!/usr/bin/env python3
"""Checks that the workspace's `rust-version` equals the highest
`rust-version` any locked dependency declares, so the README's minimum Rust
version is exactly what the lock needs.

This reads declarations; it does not compile with that toolchain. CI builds
and tests with the one toolchain it has (printed by `cargo --version` at
the top of the CI log); see the README's Install section.

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


# Language features of the workspace's own code and the Rust release that
# stabilised them: the promise must cover these as well as the lock.
OWN_CODE = [
    (re.compile(r'^edition\s*=\s*"2024"', re.M), "Cargo.toml", "1.85", "edition 2024"),
    (re.compile(r"&&\s+let\s"), ".rs", "1.88", "let chains (`if let .. && let ..`)"),
]


def own_code_needs(root):
    """Highest Rust version the workspace's own sources need, and why."""
    best, why = (0, 0, 0), "none"
    files = [os.path.join(root, "Cargo.toml")] + glob.glob(
        os.path.join(root, "crates", "**", "*.rs"), recursive=True
    )
    for pattern, suffix, ver, what in OWN_CODE:
        for f in files:
            if f.endswith(suffix) and "/fuzz/" not in f and pattern.search(open(f).read()):
                if version(ver) > best:
                    best, why = version(ver), f"{what} in {os.path.relpath(f, root)}"
                break
    return best, why


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
    highest, highest_by = (0, 0, 0), "none"
    for name, ver in packages:
        found = [p for r in registries for p in [os.path.join(r, f"{name}-{ver}", "Cargo.toml")] if os.path.exists(p)]
        if not found:
            missing += 1
            continue
        n = re.search(r'^rust-version\s*=\s*"([^"]+)"', open(found[0]).read(), re.M)
        if n and version(n.group(1)) > highest:
            highest, highest_by = version(n.group(1)), f"{name} {ver}"
        if n and version(n.group(1)) > promised:
            too_new.append(f"{name} {ver} needs Rust {n.group(1)}")
    if missing:
        print(f"msrv: {missing} of {len(packages)} locked packages not in the registry cache; run `cargo fetch --locked` first")
        return 1
    own, own_why = own_code_needs(root)
    if own > promised:
        too_new.append(f"the workspace's own code needs Rust {'.'.join(map(str, own))}: {own_why}")
    if own > highest:
        highest, highest_by = own, f"the workspace's own code: {own_why}"
    if too_new:
        print(f"msrv: Cargo.toml promises Rust {m.group(1)}, but:")
        print("\n".join("  " + t for t in too_new))
        return 1
    need = ".".join(map(str, highest))
    if highest < promised:
        # Not wrong, but the README would then name a version nothing needs.
        print(f"msrv: Cargo.toml promises Rust {m.group(1)}, but the lock and the code need "
              f"only {need} ({highest_by}); lower rust-version to {need}")
        return 1
    print(f"msrv: Rust {m.group(1)} is what the lock and the code need: the highest "
          f"requirement is {need} ({highest_by}); {len(packages)} locked packages checked")
    return 0


if __name__ == "__main__":
    sys.exit(main())
