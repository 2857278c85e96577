#!/usr/bin/env bash
# The installed package and the build-system examples (docs/batch.md, "CMake", "Make"):
# `cmake --install` into a prefix; examples/cmake-project configured and built against it with
# Ninja and with Unix Makefiles, examples/make/Makefile with GNU Make; for each: the first build
# bakes the three fabrics and the plain weave's scene plan (SCENE) and the reader program opens
# them, a second build does nothing, touching one fabric rebakes exactly that asset, touching the
# scene rebakes exactly the planned asset, an albedo edit rebakes it through the cache (only the two
# colour stages are stored anew). Usage: build_systems.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1"; source="$2"
work=$(mktemp -d /tmp/clothbake-buildsys-XXXXXX)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
exe="$work/prefix/bin/clothbake"
fail() { echo "FAIL: $*"; exit 1; }
entries() { "$exe" cache info "$work/cache" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["entries"])'; }

for gen in Ninja "Unix Makefiles"; do
  rm -rf "$work/project" "$work/b" "$work/cache"
  cp -r "$source/examples/cmake-project" "$work/project"
  cmake -S "$work/project" -B "$work/b" -G "$gen" -DCMAKE_PREFIX_PATH="$work/prefix" \
    "-DCLOTHBAKE_OPTIONS=--cache;$work/cache" >/dev/null
  n=$(cmake --build "$work/b" 2>&1 | tee "$work/log1" | grep -c "clothbake: baking" || true)
  [[ "$n" == 4 ]] || { cat "$work/log1"; fail "$gen: first build baked $n assets, not 4"; }
  "$work/b/open_assets" "$work/b/fabrics/"*.cbk "$work/b/planned/plain-swatch.cbk" >/dev/null ||
    fail "$gen: the reader cannot open the assets"
  grep -q "swatch.toml" "$work/b/planned/plain-swatch.cbk.d" || fail "$gen: the depfile does not name the scene"
  n=$(cmake --build "$work/b" 2>&1 | grep -c "clothbake: baking" || true)
  [[ "$n" == 0 ]] || fail "$gen: a second build baked $n assets"
  sleep 1; touch "$work/project/fabrics/twill.toml"
  out=$(cmake --build "$work/b" 2>&1)
  n=$(grep -c "clothbake: baking" <<<"$out" || true)
  [[ "$n" == 1 && "$out" == *fabrics_twill* ]] || { echo "$out"; fail "$gen: touching twill.toml baked $n assets"; }
  sleep 1; touch "$work/project/scenes/swatch.toml"
  out=$(cmake --build "$work/b" 2>&1)
  n=$(grep -c "clothbake: baking" <<<"$out" || true)
  [[ "$n" == 1 && "$out" == *plain_swatch* ]] || { echo "$out"; fail "$gen: touching the scene baked $n assets"; }
  before=$(entries)
  sed -i 's/color = \[0.05, 0.09, 0.26\]/color = [0.50, 0.10, 0.02]/' "$work/project/fabrics/satin.toml"
  start=$(date +%s.%N)
  out=$(cmake --build "$work/b" 2>&1)
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  n=$(grep -c "clothbake: baking" <<<"$out" || true)
  [[ "$n" == 1 && "$out" == *fabrics_satin* ]] || { echo "$out"; fail "$gen: the albedo edit baked $n assets"; }
  after=$(entries)
  [[ $((after - before)) == 2 ]] || fail "$gen: the albedo edit stored $((after - before)) entries, not 2 (fabric_records, feature_maps)"
  echo "$gen: 3 baked and 1 planned, no-op rebuild, one touched fabric and the touched scene rebaked, albedo edit through the cache in $seconds s"
done

rm -rf "$work/mk" "$work/make"
cp -r "$source/examples" "$work/make"
mk() { make -C "$work/make/make" CLOTHBAKE="$exe" OUT="$work/mk" "$@"; }
n=$(mk 2>&1 | grep -c " bake " || true)
[[ "$n" == 3 ]] || fail "make: first build baked $n assets"
mk -q || fail "make: not up to date after the build"
sleep 1; touch "$work/make/cmake-project/fabrics/plain.toml"
out=$(mk 2>&1)
n=$(grep -c " bake " <<<"$out" || true)
[[ "$n" == 1 && "$out" == *plain.toml* ]] || { echo "$out"; fail "make: touching plain.toml baked $n assets"; }
mk -q || fail "make: not up to date after the rebake"
echo "make: 3 baked, up to date, one touched fabric rebaked"
