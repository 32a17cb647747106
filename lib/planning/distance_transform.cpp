#include "planning/distance_transform.hpp"

#include <algorithm>
#include <limits>
#include <thread>

namespace qte::planning {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// The lower envelope of parabolas over one line of `n` values `stride` apart, in place: each
// value becomes min over sites r of (q - r)^2 + f(r). Infinite values are not sites.
// `site` and `boundary` are scratch of n and n + 1.
void transform_line(float* f, int n, std::ptrdiff_t stride, std::vector<float>& values, std::vector<int>& site,
                    std::vector<float>& boundary) {
  for (int q = 0; q < n; ++q) values[q] = f[q * stride];
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const float fq = values[q];
    if (fq == kInfinity) continue;
    if (k < 0) {
      k = 0;
      site[0] = q;
      boundary[0] = -kInfinity;
      boundary[1] = kInfinity;
      continue;
    }
    float s;
    while (true) {
      const int r = site[k];
      s = ((fq + static_cast<float>(q) * q) - (values[r] + static_cast<float>(r) * r)) / (2.0f * (q - r));
      if (s > boundary[k]) break;
      --k;  // boundary[0] is -infinity, so k stays >= 0
    }
    ++k;
    site[k] = q;
    boundary[k] = s;
    boundary[k + 1] = kInfinity;
  }
  if (k < 0) return;  // no site on this line: it stays infinite
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (boundary[k + 1] < q) ++k;
    const float d = static_cast<float>(q - site[k]);
    f[q * stride] = d * d + values[site[k]];
  }
}

// Runs `body(first, last)` over [0, count) split into `threads` contiguous parts.
template <typename Body>
void split(int count, int threads, const Body& body) {
  threads = std::clamp(threads, 1, std::max(1, count));
  std::vector<std::thread> workers;
  for (int t = 1; t < threads; ++t)
    workers.emplace_back(body, count * t / threads, count * (t + 1) / threads);
  body(0, count / threads);
  for (auto& w : workers) w.join();
}

}  // namespace

std::vector<float> squared_distance_transform(const std::vector<uint8_t>& occupied, const Eigen::Vector3i& size,
                                              int threads) {
  const int nx = size.x(), ny = size.y(), nz = size.z();
  const std::ptrdiff_t plane = static_cast<std::ptrdiff_t>(ny) * nz;
  std::vector<float> d(occupied.size());
  for (std::size_t i = 0; i < occupied.size(); ++i) d[i] = occupied[i] ? 0.0f : kInfinity;
  const int longest = std::max({nx, ny, nz});

  // z and y: lines within one x slab, slabs shared out.
  split(nx, threads, [&](int first, int last) {
    std::vector<float> values(longest);
    std::vector<int> site(longest);
    std::vector<float> boundary(longest + 1);
    for (int x = first; x < last; ++x) {
      float* slab = d.data() + x * plane;
      for (int y = 0; y < ny; ++y) transform_line(slab + y * nz, nz, 1, values, site, boundary);
      for (int z = 0; z < nz; ++z) transform_line(slab + z, ny, nz, values, site, boundary);
    }
  });
  // x: lines across slabs, shared out by y.
  split(ny, threads, [&](int first, int last) {
    std::vector<float> values(longest);
    std::vector<int> site(longest);
    std::vector<float> boundary(longest + 1);
    for (int y = first; y < last; ++y)
      for (int z = 0; z < nz; ++z) transform_line(d.data() + y * nz + z, nx, plane, values, site, boundary);
  });
  return d;
}

}  // namespace qte::planning
