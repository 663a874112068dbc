#!/bin/sh
# Builds and runs the Embree anchor on this machine (Debian: apt-get install libembree-dev).
# Arguments: knot rings and segments (default 2000 250, 1M triangles).
set -e
out="${TMPDIR:-/tmp}/pathwave-embree-anchor"
cc -O3 -march=native -o "$out" "$(dirname "$0")/anchor.c" -lembree3 -lpthread -lm
"$out" "$@"
