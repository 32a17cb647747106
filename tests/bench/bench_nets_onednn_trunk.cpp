// Headroom for the networks' forward: `light`'s no-gradient trunk (depth 0, 16^3 grid, 10
// channels) as the toolkit runs it (LibTorch, lib/nets) against the same layers run by oneDNN
// directly with its blocked layout kept from layer to layer: bias and LeakyReLU fused into each
// convolution, max pooling and trilinear x2 upsampling (with the skip connection's sum fused) as
// oneDNN primitives, created once. Random weights: it times, it does not compare values; the
// oneDNN side leaves out the proprioception's per-sample bias (one broadcast add at 16^3).
// Alternated run by run at the batch sizes of acting (2), of a tree expansion's branches (20)
// and of the training batch's targets (32), 2 threads; prints medians and the ratio.
// Options: --reps R (default 9), --threads N (default 2).
#include <oneapi/dnnl/dnnl.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <vector>

#include "nets/qattention_modules.hpp"

namespace {

using dnnl::memory;
using Tag = memory::format_tag;
constexpr auto f32 = memory::data_type::f32;
using Clock = std::chrono::steady_clock;

// The trunk as a list of primitive calls on memories created once.
class OneDnnTrunk {
 public:
  explicit OneDnnTrunk(int batch) : n_(batch) {
    grid_ = filled(memory::desc({n_, 10, 16, 16, 16}, f32, Tag::ncdhw));
    const memory e0 = conv(grid_, 16, 3, true, 16);
    const memory e1 = conv(conv(pool(e0, 16), 32, 3, true, 8), 32, 3, true, 8);
    const memory e2 = conv(conv(pool(e1, 8), 64, 3, true, 4), 64, 3, true, 4);
    const memory d1 = conv(upsample_onto(conv(e2, 32, 1, false, 4), e1), 32, 3, true, 8);
    const memory d0 = conv(upsample_onto(conv(d1, 16, 1, false, 8), e0), 16, 3, true, 16);
    const memory q = conv(d0, 1, 1, false, 16);
    q_ = memory(memory::desc({n_, 1, 16, 16, 16}, f32, Tag::ncdhw), engine_);
    add(dnnl::reorder(q, q_), {{DNNL_ARG_FROM, q}, {DNNL_ARG_TO, q_}});
  }
  void run() {
    for (auto& [primitive, args] : steps_) primitive.execute(stream_, args);
    stream_.wait();
  }

 private:
  memory filled(const memory::desc& desc) {
    memory m(desc, engine_);
    auto* p = static_cast<float*>(m.get_data_handle());
    for (size_t i = 0; i < desc.get_size() / sizeof(float); ++i) p[i] = static_cast<float>((i * 7919) % 13) * 0.01f - 0.06f;
    return m;
  }
  void add(dnnl::primitive p, std::unordered_map<int, memory> args) { steps_.push_back({std::move(p), std::move(args)}); }

  memory conv(memory src, int out, int k, bool leaky, int v) {
    const int in = static_cast<int>(src.get_desc().dims()[1]), p = k / 2;
    const dnnl::convolution_forward::desc desc(
        dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
        memory::desc(src.get_desc().dims(), f32, Tag::any), memory::desc({out, in, k, k, k}, f32, Tag::any),
        memory::desc({out}, f32, Tag::x), memory::desc({n_, out, v, v, v}, f32, Tag::any), {1, 1, 1}, {p, p, p},
        {p, p, p});
    dnnl::primitive_attr attr;
    if (leaky) {
      dnnl::post_ops ops;
      ops.append_eltwise(1.f, dnnl::algorithm::eltwise_relu, 0.02f, 0.f);  // LeakyReLU 0.02
      attr.set_post_ops(ops);
    }
    const dnnl::convolution_forward::primitive_desc pd(desc, attr, engine_);
    if (pd.src_desc() != src.get_desc()) {
      memory blocked(pd.src_desc(), engine_);
      add(dnnl::reorder(src, blocked), {{DNNL_ARG_FROM, src}, {DNNL_ARG_TO, blocked}});
      src = blocked;
    }
    memory dst(pd.dst_desc(), engine_);
    add(dnnl::convolution_forward(pd), {{DNNL_ARG_SRC, src},
                                        {DNNL_ARG_WEIGHTS, filled(pd.weights_desc())},
                                        {DNNL_ARG_BIAS, filled(pd.bias_desc())},
                                        {DNNL_ARG_DST, dst}});
    return dst;
  }
  memory pool(const memory& src, int v) {
    const int c = static_cast<int>(src.get_desc().dims()[1]), o = (v - 1) / 2 + 1;
    const dnnl::pooling_v2_forward::desc desc(dnnl::prop_kind::forward_inference, dnnl::algorithm::pooling_max,
                                              src.get_desc(), memory::desc({n_, c, o, o, o}, f32, Tag::any),
                                              {2, 2, 2}, {3, 3, 3}, {0, 0, 0}, {1, 1, 1}, {1, 1, 1});
    const dnnl::pooling_v2_forward::primitive_desc pd(desc, engine_);
    memory dst(pd.dst_desc(), engine_);
    add(dnnl::pooling_v2_forward(pd), {{DNNL_ARG_SRC, src}, {DNNL_ARG_DST, dst}});
    return dst;
  }
  // skip + trilinear x2 of small, written over a copy of skip (sum post-op).
  memory upsample_onto(const memory& small, const memory& skip) {
    memory dst(skip.get_desc(), engine_);
    add(dnnl::reorder(skip, dst), {{DNNL_ARG_FROM, skip}, {DNNL_ARG_TO, dst}});
    const dnnl::resampling_forward::desc desc(dnnl::prop_kind::forward_inference, dnnl::algorithm::resampling_linear,
                                              small.get_desc(), skip.get_desc());
    dnnl::primitive_attr attr;
    dnnl::post_ops ops;
    ops.append_sum(1.f);
    attr.set_post_ops(ops);
    const dnnl::resampling_forward::primitive_desc pd(desc, attr, engine_);
    add(dnnl::resampling_forward(pd), {{DNNL_ARG_SRC, small}, {DNNL_ARG_DST, dst}});
    return dst;
  }

  dnnl::engine engine_{dnnl::engine::kind::cpu, 0};
  dnnl::stream stream_{engine_};
  int64_t n_;
  memory grid_, q_;
  std::vector<std::pair<dnnl::primitive, std::unordered_map<int, memory>>> steps_;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  qte::nets::prepare_process_for_networks(argv);
  int reps = 9, threads = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--reps")) reps = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--threads")) threads = std::max(1, std::atoi(argv[i + 1]));
  }
  qte::nets::set_torch_threads(threads);
  torch::manual_seed(0);
  torch::NoGradGuard no_grad;
  qte::nets::NetConfig config;  // light, depth 0
  const auto net = qte::nets::make_qattention_module(config);
  std::printf("light's no-gradient trunk (16^3, 10 channels), %d threads, median of %d, alternated:\n", threads, reps);
  for (int batch : {2, 20, 32}) {
    OneDnnTrunk onednn(batch);
    const auto grid = torch::rand({batch, config.channels, 16, 16, 16});
    const auto proprio = torch::rand({batch, config.proprio});
    std::vector<double> ours, direct;
    for (int r = 0; r <= reps; ++r) {
      auto t0 = Clock::now();
      net->trunk(grid, proprio);
      const double a = std::chrono::duration<double>(Clock::now() - t0).count();
      t0 = Clock::now();
      onednn.run();
      const double b = std::chrono::duration<double>(Clock::now() - t0).count();
      if (r == 0) continue;  // warm-up
      ours.push_back(a), direct.push_back(b);
    }
    std::printf("  batch %2d: LibTorch (lib/nets) %7.2f ms, oneDNN blocked %7.2f ms: %.2fx as fast\n", batch,
                1e3 * median(ours), 1e3 * median(direct), median(ours) / median(direct));
  }
  return 0;
}
