#include "nets/conv3d.hpp"

#include <oneapi/dnnl/dnnl.hpp>

#include <array>
#include <atomic>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

#include "common/error.hpp"

namespace qte::nets {
namespace {

using dnnl::memory;
using Dims = memory::dims;

std::atomic<bool> swapped_on{true};

const dnnl::engine& cpu_engine() {
  static const dnnl::engine engine(dnnl::engine::kind::cpu, 0);
  return engine;
}

// One shape's swapped convolution, its reorders in (the tensors as LibTorch holds them, viewed
// with batch and channels swapped) and out (the gradient in LibTorch's [O, I, k, k, k]).
struct SwappedConvolution {
  bool vectorised = false;
  memory::desc x_swapped, dy_swapped, dw_torch;
  dnnl::convolution_forward::primitive_desc pd;
  dnnl::convolution_forward convolution;
  dnnl::reorder x_in, dy_in, dw_out;
};

// Shape key: N, I, D, H, W of x; O, D', H', W' of dy; padding.
using Key = std::array<int64_t, 10>;

std::shared_ptr<const SwappedConvolution> make_swapped(const Key& key) {
  const auto [n, i, d, h, w, o, a, b, c, p] = key;
  const auto f32 = memory::data_type::f32;
  auto s = std::make_shared<SwappedConvolution>();
  const int64_t x_volume = d * h * w, dy_volume = a * b * c;
  const Dims kernel{d + 2 * p - a + 1, h + 2 * p - b + 1, w + 2 * p - c + 1};
  const int64_t k_volume = kernel[0] * kernel[1] * kernel[2];
  s->x_swapped = memory::desc({i, n, d, h, w}, f32, Dims{x_volume, i * x_volume, h * w, w, 1});
  s->dy_swapped = memory::desc({o, n, a, b, c}, f32, Dims{dy_volume, o * dy_volume, b * c, c, 1});
  s->dw_torch = memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32,
                             Dims{k_volume, i * k_volume, kernel[1] * kernel[2], kernel[2], 1});
  const auto any = memory::format_tag::any;
  const dnnl::convolution_forward::desc desc(
      dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct, memory::desc({i, n, d, h, w}, f32, any),
      memory::desc({o, n, a, b, c}, f32, any), memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32, any),
      Dims{1, 1, 1}, Dims{p, p, p}, Dims{p, p, p});
  s->pd = dnnl::convolution_forward::primitive_desc(desc, cpu_engine());
  s->vectorised = std::strncmp(s->pd.impl_info_str(), "jit", 3) == 0;
  s->convolution = dnnl::convolution_forward(s->pd);
  s->x_in = dnnl::reorder(dnnl::reorder::primitive_desc(cpu_engine(), s->x_swapped, cpu_engine(), s->pd.src_desc()));
  s->dy_in =
      dnnl::reorder(dnnl::reorder::primitive_desc(cpu_engine(), s->dy_swapped, cpu_engine(), s->pd.weights_desc()));
  s->dw_out = dnnl::reorder(dnnl::reorder::primitive_desc(cpu_engine(), s->pd.dst_desc(), cpu_engine(), s->dw_torch));
  return s;
}

// Created once per shape (a network has a handful) and shared by the threads that train.
std::shared_ptr<const SwappedConvolution> swapped_for(const torch::Tensor& x, const torch::Tensor& dy,
                                                      int64_t padding) {
  if (x.dim() != 5 || dy.dim() != 5 || x.size(0) != dy.size(0))
    throw Error("conv3d weight gradient: x and dy must be [N, C, D, H, W] of one batch");
  const Key key{x.size(0), x.size(1), x.size(2), x.size(3), x.size(4), dy.size(1), dy.size(2), dy.size(3), dy.size(4),
                padding};
  static std::mutex mutex;
  static std::map<Key, std::shared_ptr<const SwappedConvolution>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& entry = cache[key];
  if (!entry) entry = make_swapped(key);
  return entry;
}

torch::Tensor scratch_for(const memory::desc& desc) {
  return torch::empty({static_cast<int64_t>((desc.get_size() + 3) / 4)}, torch::kFloat);
}

torch::Tensor swapped_weight_gradient(const SwappedConvolution& s, const torch::Tensor& x, const torch::Tensor& dy) {
  const auto& engine = cpu_engine();
  dnnl::stream stream(engine);
  const auto x_buffer = scratch_for(s.pd.src_desc()), dy_buffer = scratch_for(s.pd.weights_desc()),
             dw_buffer = scratch_for(s.pd.dst_desc());
  auto dw = torch::empty({s.dw_torch.dims()[1], s.dw_torch.dims()[0], s.dw_torch.dims()[2], s.dw_torch.dims()[3],
                          s.dw_torch.dims()[4]},
                         torch::kFloat);
  memory x_torch(s.x_swapped, engine, x.data_ptr()), x_blocked(s.pd.src_desc(), engine, x_buffer.data_ptr());
  memory dy_torch(s.dy_swapped, engine, dy.data_ptr()), dy_blocked(s.pd.weights_desc(), engine, dy_buffer.data_ptr());
  memory dw_blocked(s.pd.dst_desc(), engine, dw_buffer.data_ptr()), dw_torch(s.dw_torch, engine, dw.data_ptr());
  s.x_in.execute(stream, x_torch, x_blocked);
  s.dy_in.execute(stream, dy_torch, dy_blocked);
  s.convolution.execute(stream,
                        {{DNNL_ARG_SRC, x_blocked}, {DNNL_ARG_WEIGHTS, dy_blocked}, {DNNL_ARG_DST, dw_blocked}});
  s.dw_out.execute(stream, dw_blocked, dw_torch);
  stream.wait();
  return dw;
}

// The convolution as LibTorch computes it forward, with the swapped weight gradient backward.
struct Conv3dFunction : torch::autograd::Function<Conv3dFunction> {
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& x,
                               const torch::Tensor& weight, const torch::Tensor& bias, int64_t padding) {
    ctx->save_for_backward({x, weight});
    ctx->saved_data["padding"] = padding;
    return torch::conv3d(x, weight, bias, 1, padding);
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const auto saved = ctx->get_saved_variables();
    const auto& x = saved[0];
    const auto& weight = saved[1];
    const auto dy = grads[0].contiguous();
    const int64_t p = ctx->saved_data["padding"].toInt();
    const auto torch_backward = [&](bool input, bool weights) {
      return at::convolution_backward(dy, x, weight, c10::nullopt, {1, 1, 1}, {p, p, p}, {1, 1, 1}, false, {0, 0, 0},
                                      1, {input, weights, false});
    };
    torch::Tensor dx, dw, db;
    if (ctx->needs_input_grad(0)) dx = std::get<0>(torch_backward(true, false));
    if (ctx->needs_input_grad(1)) {
      const auto swapped = swapped_for(x, dy, p);
      dw = swapped->vectorised ? swapped_weight_gradient(*swapped, x, dy) : std::get<1>(torch_backward(false, true));
    }
    if (ctx->needs_input_grad(2)) db = dy.sum({0, 2, 3, 4});
    return {dx, dw, db, torch::Tensor()};
  }
};

bool all_ones(const torch::ExpandingArray<3>& a) { return (*a)[0] == 1 && (*a)[1] == 1 && (*a)[2] == 1; }

// The padding when it is the same on every side and zeros are padded; -1 otherwise.
int64_t plain_padding(const torch::nn::detail::ConvNdOptions<3>& o) {
  if (!c10::holds_alternative<torch::enumtype::kZeros>(o.padding_mode())) return -1;
  const auto* padding = c10::get_if<torch::ExpandingArray<3>>(&o.padding());
  if (!padding || (**padding)[0] != (**padding)[1] || (**padding)[0] != (**padding)[2]) return -1;
  return (**padding)[0];
}

}  // namespace

torch::Tensor Conv3dLayerImpl::forward(const torch::Tensor& input) {
  const auto& o = options;
  const int64_t padding = plain_padding(o);
  const bool swappable = swapped_on && torch::GradMode::is_enabled() && weight.requires_grad() && bias.defined() &&
                         padding >= 0 && all_ones(o.stride()) && all_ones(o.dilation()) && o.groups() == 1 &&
                         !o.transposed() && input.scalar_type() == torch::kFloat && input.device().is_cpu() &&
                         weight.scalar_type() == torch::kFloat;
  if (!swappable) return torch::nn::Conv3dImpl::forward(input);
  return Conv3dFunction::apply(input.contiguous(), weight, bias, padding);
}

torch::Tensor conv3d_weight_gradient(const torch::Tensor& x, const torch::Tensor& dy, int64_t padding) {
  if (x.scalar_type() != torch::kFloat || dy.scalar_type() != torch::kFloat)
    throw Error("conv3d weight gradient: float tensors expected");
  const auto xc = x.contiguous(), dyc = dy.contiguous();
  return swapped_weight_gradient(*swapped_for(xc, dyc, padding), xc, dyc);
}

void use_swapped_weight_gradient(bool on) { swapped_on = on; }
bool swapped_weight_gradient_in_use() { return swapped_on; }

}  // namespace qte::nets
