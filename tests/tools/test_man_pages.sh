#!/usr/bin/env bash
# Every program has a man page in man/ that is exactly what its --help-man prints (so help and
# man page never drift apart; regenerate with `make man`), and answers --help and --version, the
# latter naming the commit built: one of the checkout's (git describe, perhaps -dirty), or
# "unknown" outside a git checkout.
set -euo pipefail
tools=${QTE_TOOLS:?} src=${QTE_SOURCE:?}
status=0
for cpp in "$src"/tools/*.cpp; do
  name=$(basename "$cpp" .cpp)
  if ! diff -u "$src/man/$name.1" <("$tools/$name" --help-man) >/dev/null; then
    echo "man/$name.1 differs from '$name --help-man' (run: make man)"; status=1
  fi
  "$tools/$name" --help | grep -q -- "--seed" || { echo "$name --help lacks --seed"; status=1; }
  version=$("$tools/$name" --version)
  commit=$(printf '%s\n' "$version" | sed -n "s/^$name (QTE toolkit) [0-9.]*, commit \([^ ]*\)\$/\1/p")
  [ -n "$commit" ] || { echo "$name --version: '$version'"; status=1; }
  if git -C "$src" rev-parse --git-dir > /dev/null 2>&1; then
    git -C "$src" cat-file -e "${commit%-dirty}^{commit}" 2>/dev/null || { echo "$name --version: no commit '$commit'"; status=1; }
  else
    [ "$commit" = unknown ] || { echo "$name --version: '$commit' outside a checkout"; status=1; }
  fi
  out=$("$tools/$name" --no-such-option 2>&1 >/dev/null) && { echo "$name accepted a bad option"; status=1; }
  [ "$(printf '%s\n' "$out" | wc -l)" = 1 ] || { echo "$name: usage error not one line: $out"; status=1; }
done
[ -f "$src/man/qte-stream.5" ] || { echo "man/qte-stream.5 missing"; status=1; }
exit $status
