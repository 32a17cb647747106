"""Times the PyTorch reference's scatter-mean voxelizer (2 threads) on the same 128x128 cloud
into 16^3 that bench_voxelize uses, for a side-by-side figure. Usage:
  /usr/bin/python3 tests/bench/torch_voxelize.py PATH/TO/torch_qattention_ref.py"""
import importlib.util, sys, time, torch

path = sys.argv[1]
sys.argv = [path, "2"]  # the reference reads its thread count from argv[1]
spec = importlib.util.spec_from_file_location("ref", path)
ref = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ref)  # the reference's benchmarks run only under __main__
N = 128 * 128
pts, rgb, lo, hi = torch.rand(N, 3), torch.rand(N, 3), torch.zeros(3), torch.ones(3)
ref.voxelize(pts, rgb, lo, hi)
times = []
for _ in range(50):
    t = time.perf_counter(); ref.voxelize(pts, rgb, lo, hi); times.append(time.perf_counter() - t)
dt = sorted(times)[len(times) // 2]
print(f"torch scatter-mean voxelize 128x128 cloud -> 16^3, {torch.get_num_threads()} threads: {dt*1e3:.3f} ms ({N/dt/1e6:.0f} Mpoints/s)")
