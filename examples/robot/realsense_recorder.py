#!/usr/bin/env python3
"""The RealSense camera's recorder for the robot spool (formats/robot-spool.md): takes robot-step's frames.

    python3 examples/robot/realsense_recorder.py --spool spool                 # the first camera found
    python3 examples/robot/realsense_recorder.py --print-intrinsics            # robot-step's --intrinsics
    python3 examples/robot/realsense_recorder.py --spool spool --dry-run --frames saved/   # no camera

Watches the spool for capture-<session>-<n>.request and answers each, in the order robot-step
wrote them, with capture-...-n.color.png (8-bit RGB), capture-...-n.depth.png (16-bit greyscale,
the depth aligned to the colour image, in the camera's depth unit: 1 mm for the D400 series as
they start) and last capture-...-n.ready (empty), each written whole under a '.' name and
renamed. A frame that cannot be taken, for whatever error, is answered with capture-...-n.fault,
one line (the error in words). `stop` in the spool, SIGINT or SIGTERM end it without answering
anything more; a signal, or an error outside a capture, also writes `stop` in the spool saying
why, so that robot-step stops at once instead of waiting for the frame.

With Intel's Python wrapper (pip install pyrealsense2; not a dependency of the toolkit) and
NumPy. The aligned depth has the colour stream's pixels, so robot-step's --intrinsics are the
colour stream's fx,fy,cx,cy: --print-intrinsics prints them for the --width, --height and --fps
given, with the depth unit. Each capture drops --settle frames first, so the frame is taken
after the request (the arm at rest) and not from the camera's queue.

--dry-run imports neither: it answers each request with the next pair of frames of --frames DIR
(color_%06d.png and depth_%06d.png, the indices present in both, cycling), copied byte for byte,
so the protocol can be exercised without a camera.
"""
import argparse
import os
import re
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import robot_spool  # noqa: E402


def png_bytes(image):
    """A PNG of a NumPy image: H x W x 3 uint8 (RGB) or H x W uint16 (greyscale, as depth is)."""
    import numpy as np
    if image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3:
        bit_depth, colour_type, samples = 8, 2, image
    elif image.dtype == np.uint16 and image.ndim == 2:
        bit_depth, colour_type, samples = 16, 0, image.astype(">u2")  # PNG is big-endian
    else:
        raise ValueError(f"cannot write a {image.dtype} image of shape {image.shape} as PNG")
    height, width = image.shape[:2]
    rows = np.ascontiguousarray(samples).view(np.uint8).reshape(height, -1)
    filtered = np.hstack([np.zeros((height, 1), np.uint8), rows])  # filter type 0 on every row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(filtered.tobytes(), 6))
            + chunk(b"IEND", b""))


class SavedFrames:
    """The dry run's camera: the pairs of --frames DIR in turn."""

    def __init__(self, directory):
        self.directory = directory
        found = {}
        for name in os.listdir(directory):
            m = re.match(r"^(color|depth)_([0-9]{6,})\.png$", name)
            if m:
                found.setdefault(int(m.group(2)), set()).add(m.group(1))
        self.indices = sorted(i for i, kinds in found.items() if kinds == {"color", "depth"})
        if not self.indices:
            raise SystemExit(f"{directory}: no pair of color_%06d.png and depth_%06d.png")
        self.taken = 0

    def answer(self, spool, stem):
        index = self.indices[self.taken % len(self.indices)]
        self.taken += 1
        for kind in ("color", "depth"):
            spool.copy(os.path.join(self.directory, f"{kind}_{index:06d}.png"), f"{stem}.{kind}.png")
        return index


class RealSense:
    """One RealSense, colour and depth streams, depth aligned to colour."""

    def __init__(self, width, height, fps, serial, settle):
        try:
            import pyrealsense2 as rs
        except ImportError:
            sys.exit("realsense_recorder.py: the RealSense SDK's Python module is not installed: "
                     "pip install pyrealsense2 (Intel's librealsense; not a Debian package)")
        self.rs, self.settle = rs, settle
        self.pipeline = rs.pipeline()
        config = rs.config()
        if serial:
            config.enable_device(serial)
        config.enable_stream(rs.stream.depth, width, height, rs.format.z16, fps)
        config.enable_stream(rs.stream.color, width, height, rs.format.rgb8, fps)
        self.profile = self.pipeline.start(config)
        self.align = rs.align(rs.stream.color)
        for _ in range(30):  # auto-exposure settles over the first frames
            self.pipeline.wait_for_frames()

    def intrinsics(self):
        stream = self.profile.get_stream(self.rs.stream.color).as_video_stream_profile()
        return stream.get_intrinsics()

    def depth_unit_m(self):
        return self.profile.get_device().first_depth_sensor().get_depth_scale()

    def frame(self):
        import numpy as np
        for _ in range(self.settle):
            self.pipeline.wait_for_frames()
        frames = self.align.process(self.pipeline.wait_for_frames())
        color, depth = frames.get_color_frame(), frames.get_depth_frame()
        if not color or not depth:
            raise RuntimeError("the camera gave a frame without colour or depth")
        return np.asanyarray(color.get_data()).copy(), np.asanyarray(depth.get_data()).copy()

    def answer(self, spool, stem):
        color, depth = self.frame()
        spool.write(f"{stem}.color.png", png_bytes(color))
        spool.write(f"{stem}.depth.png", png_bytes(depth))

    def close(self):
        self.pipeline.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spool", help="the spool directory robot-step writes to")
    parser.add_argument("--print-intrinsics", action="store_true",
                        help="print the aligned colour stream's --intrinsics and the depth unit, then exit")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    parser.add_argument("--fps", type=int, default=30)
    parser.add_argument("--serial", help="the camera's serial number (default: the first found)")
    parser.add_argument("--settle", type=int, default=5, help="frames dropped before each capture (default 5)")
    parser.add_argument("--dry-run", action="store_true", help="no camera: answer with the frames of --frames DIR")
    parser.add_argument("--frames", help="with --dry-run: a directory of color_%%06d.png and depth_%%06d.png")
    parser.add_argument("--poll", type=float, default=0.02, help="seconds between looks at the spool (default 0.02)")
    args = parser.parse_args()

    if args.print_intrinsics:
        camera = RealSense(args.width, args.height, args.fps, args.serial, 0)
        i = camera.intrinsics()
        print(f"--intrinsics {i.fx:.3f},{i.fy:.3f},{i.ppx:.3f},{i.ppy:.3f}")
        print(f"--depth-unit {camera.depth_unit_m():g}")
        print(f"# aligned colour stream {i.width}x{i.height} at {args.fps} fps; distortion {i.model} {list(i.coeffs)}")
        camera.close()
        return
    if not args.spool:
        sys.exit("--spool is required (or --print-intrinsics)")
    spool = robot_spool.Spool(args.spool, "capture", ["ready", "fault"], args.poll)
    if args.dry_run:
        if not args.frames:
            sys.exit("--dry-run needs --frames DIR")
        camera = SavedFrames(args.frames)
    else:
        camera = RealSense(args.width, args.height, args.fps, args.serial, args.settle)
        if abs(camera.depth_unit_m() - 0.001) > 1e-9:
            print(f"realsense_recorder: the depth unit is {camera.depth_unit_m():g} m: give robot-step that, "
                  "not millimetres", file=sys.stderr)

    def handle(stem, name):
        try:
            taken = camera.answer(spool, stem)
        except Exception as e:  # noqa: BLE001 - the camera's, the file system's, or a fault of this program
            words = robot_spool.in_words(e, (OSError, RuntimeError))
            print(f"{name}: fault: {words}", flush=True)
            spool.answer(name, stem, "fault", words)
            return
        print(f"{name}: frame {taken}" if taken is not None else f"{name}: taken", flush=True)
        spool.answer(name, stem, "ready", "")

    try:
        status = spool.serve(handle, "realsense_recorder")
    finally:
        if not args.dry_run:
            camera.close()
    sys.exit(status)


if __name__ == "__main__":
    main()
