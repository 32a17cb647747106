#!/usr/bin/env bash
# The saved streams of tests/data are what the programs make today (tests/data/make_data.sh):
# the other command tests start from them, so they must not drift from the programs.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
bash "$src/tests/data/make_data.sh" "$tools" "$tmp" || fail "make_data.sh"
for saved in "$src"/tests/data/*.rec; do
  name=$(basename "$saved")
  [ -f "$tmp/$name" ] || fail "make_data.sh no longer makes $name: remove it from tests/data"
  cmp -s "$saved" "$tmp/$name" \
    || fail "tests/data/$name differs from what the programs make now: if the change is meant, run tests/data/make_data.sh build/tools and commit"
done
for made in "$tmp"/*.rec; do
  [ -f "$src/tests/data/$(basename "$made")" ] || fail "$(basename "$made") is not saved in tests/data"
done
echo "saved data ok"
