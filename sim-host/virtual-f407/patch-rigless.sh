#!/usr/bin/env bash
# rigless 0.4.0 as the virtual board builds it: the crate from crates.io (its sha256 checked
# against the one below), with rigless-0.4.0.patch applied, in patched/rigless-0.4.0 (what
# Cargo.toml's [patch.crates-io] names). The patch is two corrections of the STM32F427's tables
# the USB model needs, the core's NMI input and its rate following the clock (see README.md):
# never a vendored copy. Idempotent.
set -euo pipefail
cd "$(dirname "$0")"
version=0.4.0
# The crate's sha256 on crates.io (Cargo.lock cannot carry it: [patch] makes rigless a path
# package there).
checksum=9041299d0f44759b725de2d1a78b53ac153f5182543fe7516721ab2635212eaa
dest=patched/rigless-$version
stamp=$dest/.sandjumper-patch
want=$(sha256sum rigless-$version.patch | cut -d' ' -f1)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
crate=""
for c in "${CARGO_HOME:-$HOME/.cargo}"/registry/cache/*/rigless-$version.crate; do
  if [ -f "$c" ] && [ "$(sha256sum "$c" | cut -d' ' -f1)" = "$checksum" ]; then
    crate=$c
    break
  fi
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ -z "$crate" ]; then
  crate=$tmp/rigless-$version.crate
  curl -fsSL --retry 3 -o "$crate" "https://static.crates.io/crates/rigless/rigless-$version.crate"
fi
got=$(sha256sum "$crate" | cut -d' ' -f1)
if [ "$got" != "$checksum" ]; then
  echo "patch-rigless: $crate has sha256 $got, crates.io's rigless $version has $checksum" >&2
  exit 2
fi
tar xzf "$crate" -C "$tmp"
(cd "$tmp/rigless-$version" && patch -p1 --quiet < "$OLDPWD/rigless-$version.patch")
rm -rf "$dest"
mkdir -p patched
mv "$tmp/rigless-$version" "$dest"
echo "$want" > "$stamp"
echo "patch-rigless: $dest ready (rigless $version + rigless-$version.patch)" >&2
