#!/usr/bin/env bash
# Every program has a man page in man/ that is exactly what its --help-man prints (so help and
# man page never drift apart; regenerate with `make man`), and answers --help and --version.
set -euo pipefail
tools=${QTE_TOOLS:?} src=${QTE_SOURCE:?}
status=0
for cpp in "$src"/tools/*.cpp; do
  name=$(basename "$cpp" .cpp)
  if ! diff -u "$src/man/$name.1" <("$tools/$name" --help-man) >/dev/null; then
    echo "man/$name.1 differs from '$name --help-man' (run: make man)"; status=1
  fi
  "$tools/$name" --help | grep -q -- "--seed" || { echo "$name --help lacks --seed"; status=1; }
  "$tools/$name" --version | grep -q "QTE toolkit" || { echo "$name --version"; status=1; }
  out=$("$tools/$name" --no-such-option 2>&1 >/dev/null) && { echo "$name accepted a bad option"; status=1; }
  [ "$(printf '%s\n' "$out" | wc -l)" = 1 ] || { echo "$name: usage error not one line: $out"; status=1; }
done
[ -f "$src/man/qte-stream.5" ] || { echo "man/qte-stream.5 missing"; status=1; }
exit $status
