#!/usr/bin/env python3
"""obs-pack on hostile camera files, made here: .pcd headers that lie about their points (10^9 in a
200-byte file, WIDTH x HEIGHT not POINTS, compressed sizes), x stored as doubles, malformed ASCII
points; a PNG whose header claims 100000 x 100000 pixels, a truncated PNG, an 8-bit depth PNG; a
joint CSV whose first row is nan. Each must end with exit 1 and one line on stderr naming the file
and what was expected (no library message before it), no output file, and within bounded memory
(obs-pack runs under a 2 GiB address-space limit). A PNG that libpng warns about reads silently.
Run with /usr/bin/python3 (ctest does)."""
import os
import resource
import struct
import subprocess
import sys
import tempfile
import zlib

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_frame_damage_")


def p(name):
    return os.path.join(tmp, name)


def write(name, data):
    with open(p(name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def pcd(fields, size, type_, width, height, points, data, body):
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\nTYPE {type_}\nCOUNT {' '.join('1' * len(fields.split()))}\n"
            f"WIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {data}\n").encode() + body


def xyz(width, points, data, body, size="4 4 4", type_="F F F", height=1):
    return pcd("x y z", size, type_, width, height, points, data, body)


def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png(width, height, depth, colour, raw, extra=b""):
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)) + extra +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# In a build with AddressSanitizer (make sanitize) a program reserves terabytes of address space
# for its shadow memory at start: there the bound is left to its allocator, which makes a program
# that asks for a huge allocation end with an error report.
SANITIZED = b"libasan" in subprocess.run(["ldd", os.path.join(TOOLS, "obs-pack")], capture_output=True).stdout


def limit_memory():
    if not SANITIZED:
        resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


def obs_pack(*args):
    r = subprocess.run([os.path.join(TOOLS, "obs-pack"), *args, "--output", p("out.rec")], capture_output=True,
                       preexec_fn=limit_memory, timeout=120)
    return r.returncode, r.stderr.decode(errors="replace")


pose = ["--camera-pose", "1,0,1,0,0,0,1"]
images = ["--intrinsics", "2,2,1,1", *pose]
colour_rows = (b"\0" + b"\x40\x80\xc0" * 2) * 2  # 2 x 2 RGB, a filter byte per row
depth_rows = (b"\0" + struct.pack(">HH", 1000, 1000)) * 2  # 2 x 2, 16-bit big-endian
write("colour_000000.png", png(2, 2, 8, 2, colour_rows))
write("depth_000000.png", png(2, 2, 16, 0, depth_rows))
write("joints.csv", "0,0,0,0,0,0,0\n")

cases = []  # (files to write, obs-pack arguments, the file the line must name, words it must hold)


def pcd_case(name, data, words):
    write(name + "_000000.pcd", data)
    cases.append((["--pcd", p(name + "_%06d.pcd"), *pose], p(name + "_000000.pcd"), words))


pcd_case("billion", xyz(10**9, 10**9, "binary", bytes(200)), "POINTS 1000000000, expected at most 50000000")
pcd_case("short", xyz(10**7, 10**7, "binary", bytes(200)), "POINTS 10000000 of 12 bytes need 120000000 bytes of binary data, the file has 200")
pcd_case("short_ascii", xyz(10**7, 10**7, "ascii", b"1 2 3\n"), "cannot fit in the 6 bytes of ASCII data")
pcd_case("doubles", xyz(2, 2, "binary", bytes(48), size="8 8 8"), "field x is TYPE F SIZE 8 COUNT 1, expected a 4-byte float")
pcd_case("letters", xyz(2, 2, "ascii", b"1 2 3\n4 5 x\n"), "data line 2: value 3 (field z) is 'x', expected a 4-byte float")
pcd_case("four", xyz(2, 2, "ascii", b"1 2 3\n4 5 6 7\n"), "data line 2: 4 values, expected 3")
pcd_case("organized", xyz(3, 4, "binary", bytes(48), height=1), "WIDTH 3 x HEIGHT 1 does not make POINTS 4")
pcd_case("wrapped", xyz(65536, 1, "binary", bytes(12), height=65536), "WIDTH 65536 x HEIGHT 65536 does not make POINTS 1")
pcd_case("lzf", xyz(2, 2, "binary_compressed", struct.pack("<II", 4000, 24) + bytes(10)), "4000 compressed bytes claimed, the file has 10")
pcd_case("not_pcd", b"\x89PNG\r\n\x1a\n" + bytes(100), "not a .pcd point cloud")


def image_case(colour, depth, named, words, joints=None):
    args = ["--rgb", p(colour + "_%06d.png"), "--depth", p(depth + "_%06d.png"), *images]
    if joints:
        args += ["--joints", p(joints)]
    cases.append((args, p(named), words))


write("huge_000000.png", png(100000, 100000, 8, 2, bytes(301)))
image_case("huge", "depth", "huge_000000.png", "PNG of 100000 x 100000 pixels, expected at most 32768 on a side")
write("huge_depth_000000.png", png(100000, 100000, 16, 0, bytes(301)))
image_case("colour", "huge_depth", "huge_depth_000000.png", "PNG of 100000 x 100000 pixels")
write("truncated_000000.png", png(2, 2, 8, 2, bytes(3)))
image_case("truncated", "depth", "truncated_000000.png", "damaged PNG (Not enough image data), expected a whole PNG image")
image_case("colour", "colour", "colour_000000.png", "8-bit RGB PNG, expected a 16-bit single-channel (greyscale) depth image")
write("text_000000.png", "not a picture\n")
image_case("text", "depth", "text_000000.png", "not a PNG file")
write("nan.csv", "nan,nan,nan,nan,nan,nan,nan\n")
image_case("colour", "depth", "nan.csv", "line 1: column 1 is 'nan', expected a finite number", joints="nan.csv")
write("inf.csv", "j1,j2,j3,j4,j5,j6,j7\n0,0,inf,0,0,0,0\n")
image_case("colour", "depth", "inf.csv", "line 2: column 3 is 'inf', expected a finite number", joints="inf.csv")

failures = []
for args, named, words in cases:
    rc, err = obs_pack(*args)
    left = [f for f in os.listdir(tmp) if f.startswith("out.rec")]
    if rc != 1 or err.count("\n") != 1 or not err.startswith("obs-pack: " + named + ": ") or words not in err or left:
        failures.append(f"{os.path.basename(named)}: exit {rc}, stderr {err[:400]!r}, left {left}")
    for f in left:  # so that the next case starts clean
        os.remove(p(f))

# A PNG libpng warns about (a too short iCCP chunk) reads, and libpng prints nothing.
write("warned_000000.png", png(2, 2, 8, 2, colour_rows, chunk(b"iCCP", b"a\0\0junk")))
rc, err = obs_pack("--rgb", p("warned_%06d.png"), "--depth", p("depth_%06d.png"), *images, "--joints", p("joints.csv"))
if rc != 0 or "libpng" in err:
    failures.append(f"warned PNG: exit {rc}, stderr {err!r}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"ok: {len(cases)} hostile files, each one line and exit 1")
