#!/usr/bin/env bash
# A relocatable install: `cmake --install` of the build into a scratch prefix, which is then
# moved elsewhere; the installed sim-step, run from there with no QTE_DATA_DIR, finds its robot
# in PREFIX/share/qte. No path of the checkout or of the build tree is compiled into a program,
# and a prefix without its share/qte is one line naming where the program looked and the variable.
source "$(dirname "$0")/common.sh"
build=$(cd "$tools/.." && pwd)
source_dir=${QTE_SOURCE:?set QTE_SOURCE to the checkout}
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log" 2>&1 || fail "cmake --install: $(tail -1 "$tmp/install.log")"
[ -f "$tmp/prefix/share/qte/xarm7.urdf" ] || fail "no share/qte/xarm7.urdf in the prefix"
for program in "$tmp"/prefix/bin/*; do
  # A sanitizer build (make sanitize) records its source files' paths for its reports: not checked.
  ! grep -qF __asan_init "$program" || continue
  for path in "$source_dir" "$build"; do
    ! grep -qF "$path" "$program" || fail "$(basename "$program") holds the path $path"
  done
done
mv "$tmp/prefix" "$tmp/moved"
(cd "$tmp" && env -u QTE_DATA_DIR "$tmp/moved/bin/sim-step" --task reach_target --episodes 1 --seed 1 \
  --output "$tmp/obs.rec" < /dev/null) 2> "$tmp/err" || fail "the moved install's sim-step: $(cat "$tmp/err")"
stream-dump "$tmp/obs.rec" > "$tmp/obs.txt" || fail "stream-dump of the moved install's observations"
grep -q "^#0 @0 obs" "$tmp/obs.txt" && grep -q "front.rgb" "$tmp/obs.txt" || fail "no observation written"
# Without its data: one line naming where it looked and QTE_DATA_DIR.
rm -r "$tmp/moved/share/qte"
env -u QTE_DATA_DIR "$tmp/moved/bin/sim-step" --task reach_target --episodes 1 --output "$tmp/none.rec" \
  < /dev/null 2> "$tmp/err" && fail "ran without its robot description"
[ "$(wc -l < "$tmp/err")" = 1 ] && grep -q "$tmp/moved/bin" "$tmp/err" && grep -q QTE_DATA_DIR "$tmp/err" \
  || fail "without share/qte: $(cat "$tmp/err")"
[ ! -e "$tmp/none.rec" ] || fail "a half-written output was left"
# QTE_DATA_DIR names another directory: it is used.
mkdir -p "$tmp/data" && cp "$source_dir/lib/robot/xarm7.urdf" "$tmp/data/"
QTE_DATA_DIR="$tmp/data" "$tmp/moved/bin/sim-step" --task reach_target --episodes 1 --output "$tmp/env.rec" \
  < /dev/null 2> "$tmp/err" || fail "with QTE_DATA_DIR: $(cat "$tmp/err")"
echo "install: relocatable"
