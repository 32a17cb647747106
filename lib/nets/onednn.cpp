#include "nets/onednn.hpp"

#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/error.hpp"

namespace qte::nets::onednn {
namespace {

using dnnl::memory;
using Dims = memory::dims;

// One shape's swapped convolution: x viewed with batch and channels swapped as the input, dy
// (swapped) as the kernel, the k^3 result reordered into LibTorch's [O, I, k, k, k].
struct Swapped {
  memory::desc x, dy;
  int64_t padding;
  memory::desc x_swapped, dy_swapped, dw_torch;
  Dims dw_sizes;
  bool vectorised = false;
  dnnl::convolution_forward::primitive_desc pd;
  dnnl::convolution_forward convolution;
  dnnl::reorder x_in, dy_in, dw_out;
};

std::unique_ptr<Swapped> make_swapped(const memory::desc& x, const memory::desc& dy, int64_t p) {
  const auto f32 = memory::data_type::f32;
  const auto any = memory::format_tag::any;
  auto s = std::make_unique<Swapped>();
  s->x = x, s->dy = dy, s->padding = p;
  const Dims xd = x.dims(), dyd = dy.dims();
  const int64_t n = xd[0], i = xd[1], o = dyd[1];
  const Dims kernel{xd[2] + 2 * p - dyd[2] + 1, xd[3] + 2 * p - dyd[3] + 1, xd[4] + 2 * p - dyd[4] + 1};
  const int64_t k_volume = kernel[0] * kernel[1] * kernel[2];
  s->x_swapped = x.permute_axes({1, 0, 2, 3, 4});
  s->dy_swapped = dy.permute_axes({1, 0, 2, 3, 4});
  s->dw_torch = memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32,
                             Dims{k_volume, i * k_volume, kernel[1] * kernel[2], kernel[2], 1});
  s->dw_sizes = {o, i, kernel[0], kernel[1], kernel[2]};
  const dnnl::convolution_forward::desc desc(
      dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
      memory::desc({i, n, xd[2], xd[3], xd[4]}, f32, any), memory::desc({o, n, dyd[2], dyd[3], dyd[4]}, f32, any),
      memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32, any), Dims{1, 1, 1}, Dims{p, p, p}, Dims{p, p, p});
  s->pd = dnnl::convolution_forward::primitive_desc(desc, engine());
  s->vectorised = std::strncmp(s->pd.impl_info_str(), "jit", 3) == 0;
  s->convolution = dnnl::convolution_forward(s->pd);
  s->x_in = dnnl::reorder(dnnl::reorder::primitive_desc(engine(), s->x_swapped, engine(), s->pd.src_desc()));
  s->dy_in = dnnl::reorder(dnnl::reorder::primitive_desc(engine(), s->dy_swapped, engine(), s->pd.weights_desc()));
  s->dw_out = dnnl::reorder(dnnl::reorder::primitive_desc(engine(), s->pd.dst_desc(), engine(), s->dw_torch));
  return s;
}

// Created once per shape and layout (a network has a handful) and shared by the threads that train.
const Swapped& swapped(const memory::desc& x, const memory::desc& dy, int64_t padding) {
  static std::mutex mutex;
  static std::vector<std::unique_ptr<Swapped>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  for (const auto& s : cache)
    if (s->x == x && s->dy == dy && s->padding == padding) return *s;
  cache.push_back(make_swapped(x, dy, padding));
  return *cache.back();
}

}  // namespace

bool layers_by_default() {
  static const bool onednn = [] {
    const char* value = std::getenv("QTE_NETWORK_LAYERS");
    if (!value || std::strcmp(value, "onednn") == 0) return true;
    if (std::strcmp(value, "libtorch") == 0) return false;
    throw Error(std::string("QTE_NETWORK_LAYERS must be libtorch or onednn, got '") + value + "'");
  }();
  return onednn;
}

const dnnl::engine& engine() {
  static const dnnl::engine cpu(dnnl::engine::kind::cpu, 0);
  return cpu;
}

Buffer buffer(const memory::desc& desc) {
  auto storage = torch::empty({static_cast<int64_t>((desc.get_size() + 3) / 4)}, torch::kFloat);
  return {storage, over(storage, desc)};
}

memory over(const torch::Tensor& storage, const memory::desc& desc) {
  return memory(desc, engine(), storage.data_ptr());
}

torch::Tensor weight_gradient(const memory& x, const memory& dy, int64_t padding) {
  const Swapped& s = swapped(x.get_desc(), dy.get_desc(), padding);
  dnnl::stream stream(engine());
  Buffer x_in = buffer(s.pd.src_desc()), dy_in = buffer(s.pd.weights_desc()), dw = buffer(s.pd.dst_desc());
  auto result = torch::empty(s.dw_sizes, torch::kFloat);
  memory x_swapped(s.x_swapped, engine(), x.get_data_handle()), dy_swapped(s.dy_swapped, engine(), dy.get_data_handle());
  s.x_in.execute(stream, x_swapped, x_in.memory);
  s.dy_in.execute(stream, dy_swapped, dy_in.memory);
  s.convolution.execute(stream, {{DNNL_ARG_SRC, x_in.memory}, {DNNL_ARG_WEIGHTS, dy_in.memory}, {DNNL_ARG_DST, dw.memory}});
  memory dw_torch = over(result, s.dw_torch);
  s.dw_out.execute(stream, dw.memory, dw_torch);
  stream.wait();
  return result;
}

bool weight_gradient_vectorised(const memory::desc& x, const memory::desc& dy, int64_t padding) {
  return swapped(x, dy, padding).vectorised;
}

}  // namespace qte::nets::onednn
