#!/usr/bin/env bash
# One-time set-up for `cargo build --features oidn`: installs Intel Open Image Denoise 2.5.1 from
# the PyPI wheel `pyoidn` (the official libOpenImageDenoise.so.2.5.1 with its CPU device, TBB and
# the trained weights compiled in) into DIR, checks the files the `oidn` crate links and the
# binary loads, and prints the line that points the build at them:
#
#   eval "$(scripts/setup-oidn.sh)"     # sets OIDN_DIR
#   cargo build --release --features oidn
#
# DIR defaults to ${XDG_CACHE_HOME:-$HOME/.cache}/pathwave/pyoidn-2.5.1. Needs python3 with pip
# (only to download and unpack the wheel: nothing of Python is used at run time). The build
# records DIR/pyoidn/oidn/lib as the binary's run path (build.rs), so it must stay where it is.
set -euo pipefail
version=2.5.1
dest="${1:-${XDG_CACHE_HOME:-$HOME/.cache}/pathwave/pyoidn-$version}"
oidn="$dest/pyoidn/oidn"
lib="$oidn/lib"
if [ ! -e "$lib/libOpenImageDenoise.so.$version" ]; then
  echo "installing pyoidn $version into $dest" >&2
  PIP_ROOT_USER_ACTION=ignore python3 -m pip install --quiet --disable-pip-version-check --no-deps --target "$dest" \
    "pyoidn==$version" >&2
fi
# The crate links -lOpenImageDenoise from OIDN_DIR/lib; the binary then needs the soname, which
# needs the core (weights inside); the core loads the CPU device module, which needs TBB.
for f in libOpenImageDenoise.so libOpenImageDenoise.so.2 "libOpenImageDenoise_core.so.$version" \
  "libOpenImageDenoise_device_cpu.so.$version" libtbb.so.12; do
  if [ ! -e "$lib/$f" ]; then
    echo "error: $lib/$f is missing: the pyoidn $version wheel has changed its layout" >&2
    exit 1
  fi
done
echo "export OIDN_DIR=$oidn"
