#!/usr/bin/env bash
# Regenerates the Mitsuba 3 fixtures that tests/tests/against_mitsuba.rs holds our path
# tracer to: for each scene tests/fixtures/mitsuba/NAME.toml, Mitsuba's image NAME.exr,
# the variance of its pixels' means NAME.var.exr and NAME.json (spp, seconds, noise).
#
# Needs: a Rust toolchain (it builds `ppm`, whose `export` writes each scene for Mitsuba),
# and a Python 3.11 or later with Mitsuba 3.9.1 and numpy, named by $PYTHON (default python3):
#
#   python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba==3.9.1 numpy
#   PYTHON=/tmp/mi/bin/python scripts/mitsuba/fixtures.sh [--threads N] [--only NAME ...]
#
# Takes: 40 minutes on two cores that other work shared (2,388 s for the ten fixtures of
# 32x32 pixels, 65,536 samples per pixel each in 16 batches: 120 s for the smooth gold
# sphere to 393 s for the mirror; each NAME.json has its time), almost all of it Mitsuba's
# `scalar_rgb` on the CPU; about half that on two idle cores. Arguments go to fixtures.py:
# `--threads` (Mitsuba's, default 2), `--only` to redo some, `--meshes` to rewrite
# sphere.obj and checker.png (byte for byte the same unless fixtures.py changed), `--coat`
# to print the internal reflectance of Mitsuba's coats that the test's rough-coat
# allowance quotes (seconds; renders nothing).
#
# Our own images are not stored: the test renders them each time, so a change to our BSDFs
# is measured against these files without regenerating them. Regenerate them when a scene
# file changes, or to check them against a newer Mitsuba.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"
(cd "$root" && cargo build --release --bin ppm)
"${PYTHON:-python3}" "$root/scripts/mitsuba/fixtures.py" --ppm "$target/release/ppm" "$@"
