#!/usr/bin/env bash
# plot-curves: a PNG of the asked size, one colour per group, same input -> same bytes, errors
# that name the file, line and column, and no picture left behind by a failure.
source "$(dirname "$0")/common.sh"

# Two methods, three seeds, five evaluation steps, as episode-stats --label --column rows.
{
  echo "label,seed,step,episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return"
  for method in qte c2farm; do for seed in 1 2 3; do for step in 0 1000 2000 3000 4000; do
    awk -v m=$method -v s=$seed -v t=$step 'BEGIN {
      r = (m == "qte" ? 0.2 : 0.1) * t / 1000 + 0.03 * s; if (r > 1) r = 1
      printf "%s,%d,%d,25,%d,%g,%g,%g,4,%g\n", m, s, t, r * 25, r, r * 0.8, r * 0.8 + 0.2, 100 * r }'
  done; done; done
} > "$tmp/curves.csv"

# PNG facts without image libraries: size from IHDR, and pixels decoded (8-bit RGB, filters
# 0-4) to count those near a colour of the palette.
cat > "$tmp/png.py" <<'EOF'
import struct, sys, zlib
def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, colour, interlace) == (8, 2, 0), "expected 8-bit RGB, not interlaced"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, rows, previous = zlib.decompress(idat), width * 3, [], bytearray(width * 3)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b, c = previous[i], previous[i - 3] if i >= 3 else 0
            if kind == 1: line[i] = (line[i] + a) & 255
            elif kind == 2: line[i] = (line[i] + b) & 255
            elif kind == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        previous = line
    return width, height, rows
width, height, rows = read_png(sys.argv[1])
if sys.argv[2] == "size":
    print(f"{width}x{height}")
else:  # pixels near blue (31,119,180) and orange (255,127,14), and distinct saturated colours
    near = lambda p, q: sum(abs(x - y) for x, y in zip(p, q)) < 30
    blue = orange = 0
    saturated = set()
    for line in rows:
        for x in range(width):
            p = tuple(line[3 * x:3 * x + 3])
            blue += near(p, (31, 119, 180))
            orange += near(p, (255, 127, 14))
            if max(p) - min(p) > 60: saturated.add(p)
    print(blue, orange, len(saturated))
EOF

plot-curves --x step --y success_rate --group label --band ci --y-range 0,1 --size 400x300 \
  --title "reach_target" --output "$tmp/two.png" "$tmp/curves.csv" || fail "plot-curves exit $?"
[ "$($py "$tmp/png.py" "$tmp/two.png" size)" = 400x300 ] || fail "size: $($py "$tmp/png.py" "$tmp/two.png" size)"
plot-curves --x step --y success_rate --size 400x300 --output "$tmp/one.png" "$tmp/curves.csv" \
  || fail "one curve: exit $?"
read -r blue2 orange2 colours2 <<<"$($py "$tmp/png.py" "$tmp/two.png" colours)"
read -r blue1 orange1 colours1 <<<"$($py "$tmp/png.py" "$tmp/one.png" colours)"
[ "$blue2" -gt 100 ] && [ "$orange2" -gt 100 ] || fail "two groups: $blue2 blue, $orange2 orange pixels"
[ "$blue1" -gt 100 ] && [ "$orange1" = 0 ] || fail "one curve: $blue1 blue, $orange1 orange pixels"
[ "$colours2" -gt "$colours1" ] || fail "two groups gave $colours2 colours, one gave $colours1"

# Same input, same bytes; the default size; the tables episode-stats writes, from stdin.
plot-curves --x step --y success_rate --group label --band ci --y-range 0,1 --size 400x300 \
  --title "reach_target" --output "$tmp/again.png" "$tmp/curves.csv"
cmp -s "$tmp/two.png" "$tmp/again.png" || fail "same input gave different bytes"
for step in 100 200; do
  stream-pack obs terminal:u8=1 success:u8=1 step:i32=2 reward:f32=100 \
    | episode-stats --label a --column step=$step
done | plot-curves --x step --y success_rate --group label --band ci --output "$tmp/stats.png" - \
  || fail "episode-stats rows: exit $?"
[ "$($py "$tmp/png.py" "$tmp/stats.png" size)" = 800x500 ] || fail "default size"

# Errors: one line naming file, column (and the header it has) or line; no picture left.
err=$(plot-curves --x step --y reward --output "$tmp/bad.png" "$tmp/curves.csv" 2>&1); rc=$?
[ $rc = 1 ] || fail "missing column: exit $rc"
[ "$(wc -l <<<"$err")" = 1 ] || fail "not one line: $err"
grep -q "$tmp/curves.csv: no column 'reward' (its header: label,seed,step," <<<"$err" || fail "$err"
printf 'step,success_rate\n0,0.5\n1000,half\n' > "$tmp/text.csv"
err=$(plot-curves --x step --y success_rate --output "$tmp/bad.png" "$tmp/text.csv" 2>&1); rc=$?
[ $rc = 1 ] && grep -q "$tmp/text.csv: line 3, column 'success_rate': 'half' is not a finite number" <<<"$err" \
  || fail "non-numeric cell: $rc $err"
printf 'step,success_rate\n' > "$tmp/empty.csv"
err=$(plot-curves --x step --y success_rate --output "$tmp/bad.png" "$tmp/empty.csv" 2>&1); rc=$?
[ $rc = 1 ] && grep -q "no rows" <<<"$err" || fail "no rows: $rc $err"
plot-curves --x step --y success_rate --band wide --output "$tmp/bad.png" "$tmp/curves.csv" 2>/dev/null
[ $? = 2 ] || fail "bad --band accepted"

# --panel: one panel of --size per task, --panel-columns to a row, under a title band.
awk -F, 'NR == 1 { print "task," $0; next } { print "reach," $0; if ($1 == "qte") print "lift," $0 }' \
  "$tmp/curves.csv" > "$tmp/tasks.csv"
plot-curves --x step --y success_rate --group label --panel task --panel-columns 3 --size 300x200 \
  --title "two tasks" --output "$tmp/panels.png" "$tmp/tasks.csv" || fail "panels: exit $?"
size=$($py "$tmp/png.py" "$tmp/panels.png" size)
[ "${size%x*}" = 600 ] && [ "${size#*x}" -gt 200 ] && [ "${size#*x}" -lt 260 ] \
  || fail "2 panels, 3 to a row, 300x200 each: $size"
plot-curves --x step --y success_rate --panel task --panel-columns 1 --size 300x200 \
  --output "$tmp/stacked.png" "$tmp/tasks.csv" || fail "stacked panels: exit $?"
[ "$($py "$tmp/png.py" "$tmp/stacked.png" size)" = 300x400 ] || fail "1 to a row, no title: $($py "$tmp/png.py" "$tmp/stacked.png" size)"
err=$(plot-curves --x step --y success_rate --panel task --output "$tmp/bad.png" "$tmp/curves.csv" 2>&1); rc=$?
[ $rc = 1 ] && grep -q "$tmp/curves.csv: no column 'task'" <<<"$err" || fail "no panel column: $rc $err"
plot-curves --x step --y success_rate --panel task --panel-columns 0 --output "$tmp/bad.png" "$tmp/tasks.csv" 2>/dev/null
[ $? = 2 ] || fail "--panel-columns 0 accepted"
[ -z "$(ls "$tmp" | grep -e bad.png -e '\.tmp\.')" ] || fail "files left behind: $(ls "$tmp")"
echo "plot-curves ok"
