#include "nets/conv3d.hpp"

#include <atomic>

#include "common/error.hpp"
#include "nets/onednn.hpp"

namespace qte::nets {
namespace {

std::atomic<int> swapped_on{-1};  // -1: as onednn::layers_by_default()

// The tensors as LibTorch holds them (contiguous [N, C, D, H, W]).
dnnl::memory::desc plain(const torch::Tensor& t) {
  return dnnl::memory::desc(t.sizes().vec(), dnnl::memory::data_type::f32, dnnl::memory::format_tag::ncdhw);
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
    if (ctx->needs_input_grad(1))
      dw = onednn::weight_gradient_vectorised(plain(x), plain(dy), p) ? conv3d_weight_gradient(x, dy, p)
                                                                        : std::get<1>(torch_backward(false, true));
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
  const bool swappable = swapped_weight_gradient_in_use() && torch::GradMode::is_enabled() && weight.requires_grad() && bias.defined() &&
                         padding >= 0 && all_ones(o.stride()) && all_ones(o.dilation()) && o.groups() == 1 &&
                         !o.transposed() && input.scalar_type() == torch::kFloat && input.device().is_cpu() &&
                         weight.scalar_type() == torch::kFloat;
  if (!swappable) return torch::nn::Conv3dImpl::forward(input);
  return Conv3dFunction::apply(input.contiguous(), weight, bias, padding);
}

torch::Tensor conv3d_weight_gradient(const torch::Tensor& x, const torch::Tensor& dy, int64_t padding) {
  if (x.scalar_type() != torch::kFloat || dy.scalar_type() != torch::kFloat)
    throw Error("conv3d weight gradient: float tensors expected");
  if (x.dim() != 5 || dy.dim() != 5 || x.size(0) != dy.size(0))
    throw Error("conv3d weight gradient: x and dy must be [N, C, D, H, W] of one batch");
  const auto xc = x.contiguous(), dyc = dy.contiguous();
  return onednn::weight_gradient(onednn::over(xc, plain(xc)), onednn::over(dyc, plain(dyc)), padding);
}

void use_swapped_weight_gradient(bool on) { swapped_on = on; }
bool swapped_weight_gradient_in_use() { return swapped_on < 0 ? onednn::layers_by_default() : swapped_on == 1; }

}  // namespace qte::nets
