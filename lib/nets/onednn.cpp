#include "nets/onednn.hpp"

#include <atomic>
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

// One shape's weight gradient. Where oneDNN has a vectorised kernel for the convolution's own
// weight gradient here (AVX-512), that; otherwise (AVX2: only im2col + GEMM) the swapped
// convolution: x viewed with batch and channels swapped as the input, dy (swapped) as the
// kernel, the k^3 result reordered into LibTorch's [O, I, k, k, k]. Either way x and dy are
// reordered into the layouts the primitive chose, where they differ.
struct WeightGradient {
  memory::desc x, dy;
  int64_t padding;
  bool native_tried = false, padded_tried = false, native = false, vectorised = false;
  memory::desc x_given, dy_given, dw_torch;  // x and dy as the caller holds them (swapped: permuted)
  Dims dw_sizes;
  dnnl::primitive primitive;
  memory::desc x_desc, dy_desc, dw_desc;  // the primitive's
  dnnl::reorder x_in, dy_in, dw_out;
  // Padded: x's channels zero-padded to a multiple of 16 (x_blocked: x's own dims in blocks of
  // 16, the same bytes as the padded x_desc), the gradient's padded input channels dropped.
  bool padded = false;
  memory::desc x_blocked;
  int x_arg = DNNL_ARG_SRC, dy_arg = DNNL_ARG_DIFF_DST, dw_arg = DNNL_ARG_DIFF_WEIGHTS;
};

std::atomic<bool> native_on{true}, padded_on{true};

bool jit(const dnnl::primitive_desc_base& pd) { return std::strncmp(pd.impl_info_str(), "jit", 3) == 0; }

// oneDNN's own backward-weights primitive for the shape, its x and dy in the layouts `x_tag`
// and `dy_tag` (any: the ones it prefers); false where it has no vectorised kernel for it on
// this processor.
bool make_native_in(WeightGradient& w, memory::format_tag x_tag, memory::format_tag dy_tag) {
  const auto f32 = memory::data_type::f32;
  const auto any = memory::format_tag::any;
  const Dims xd = w.x.dims(), dyd = w.dy.dims(), strides{1, 1, 1}, pad{w.padding, w.padding, w.padding};
  // x and dy in their own data type (f32, or bf16 for a bf16 trunk); the gradient in f32.
  const memory::desc src(xd, w.x.data_type(), x_tag), diff_dst(dyd, w.dy.data_type(), dy_tag),
      weights(w.dw_sizes, f32, any);
  try {
    const dnnl::convolution_forward::primitive_desc hint(
        {dnnl::prop_kind::forward_training, dnnl::algorithm::convolution_direct, src,
         memory::desc(w.dw_sizes, w.x.data_type(), any), diff_dst, strides, pad, pad},
        engine());
    const dnnl::convolution_backward_weights::primitive_desc pd(
        {dnnl::algorithm::convolution_direct, src, weights, diff_dst, strides, pad, pad}, engine(), hint);
    if (!jit(pd)) return false;
    w.primitive = dnnl::convolution_backward_weights(pd);
    w.x_desc = pd.src_desc(), w.dy_desc = pd.diff_dst_desc(), w.dw_desc = pd.diff_weights_desc();
  } catch (const dnnl::error&) {
    return false;
  }
  w.x_given = w.x, w.dy_given = w.dy;
  w.dw_torch = memory::desc(w.dw_sizes, f32, memory::format_tag::oidhw);
  return true;
}

// In the layouts oneDNN prefers, or else with x's channels zero-padded to a multiple of 16: for
// an input of few channels (the grid's 10) oneDNN has only im2col + GEMM, where for 16 its
// vectorised kernel runs (an eighth of the swapped convolution's time on AVX-512). The padded
// channels' gradients are computed and dropped.
bool make_native(WeightGradient& w, bool try_padded) {
  const auto any = memory::format_tag::any, blocked = memory::format_tag::nCdhw16c;
  if (make_native_in(w, any, any)) return true;
  const Dims xd = w.x.dims();
  if (!try_padded || xd[1] % 16 == 0) return false;
  WeightGradient padded = w;
  Dims padded_dims = xd;
  padded_dims[1] = (xd[1] + 15) / 16 * 16;
  padded.x = memory::desc(padded_dims, w.x.data_type(), blocked);
  padded.dw_sizes[1] = padded_dims[1];
  if (!make_native_in(padded, blocked, any)) return false;
  const memory::desc original = w.x;
  w = padded;
  w.x = w.x_given = original;
  w.padded = true;
  w.x_blocked = memory::desc(xd, w.x.data_type(), blocked);
  return true;
}

void make_swapped(WeightGradient& w, const Dims& kernel) {
  const auto f32 = memory::data_type::f32;
  const auto any = memory::format_tag::any;
  const Dims xd = w.x.dims(), dyd = w.dy.dims();
  const int64_t n = xd[0], i = xd[1], o = dyd[1], k_volume = kernel[0] * kernel[1] * kernel[2], p = w.padding;
  w.x_given = w.x.permute_axes({1, 0, 2, 3, 4});
  w.dy_given = w.dy.permute_axes({1, 0, 2, 3, 4});
  w.dw_torch = memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32,
                            Dims{k_volume, i * k_volume, kernel[1] * kernel[2], kernel[2], 1});
  const dnnl::convolution_forward::desc desc(
      dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct,
      memory::desc({i, n, xd[2], xd[3], xd[4]}, f32, any), memory::desc({o, n, dyd[2], dyd[3], dyd[4]}, f32, any),
      memory::desc({i, o, kernel[0], kernel[1], kernel[2]}, f32, any), Dims{1, 1, 1}, Dims{p, p, p}, Dims{p, p, p});
  const dnnl::convolution_forward::primitive_desc pd(desc, engine());
  w.vectorised = jit(pd);
  w.primitive = dnnl::convolution_forward(pd);
  w.x_desc = pd.src_desc(), w.dy_desc = pd.weights_desc(), w.dw_desc = pd.dst_desc();
  w.x_arg = DNNL_ARG_SRC, w.dy_arg = DNNL_ARG_WEIGHTS, w.dw_arg = DNNL_ARG_DST;
}

std::unique_ptr<WeightGradient> make_weight_gradient(const memory::desc& x, const memory::desc& dy, int64_t p,
                                                     bool try_native, bool try_padded) {
  auto w = std::make_unique<WeightGradient>();
  w->x = x, w->dy = dy, w->padding = p, w->native_tried = try_native, w->padded_tried = try_padded;
  const Dims xd = x.dims(), dyd = dy.dims();
  const Dims kernel{xd[2] + 2 * p - dyd[2] + 1, xd[3] + 2 * p - dyd[3] + 1, xd[4] + 2 * p - dyd[4] + 1};
  w->dw_sizes = {dyd[1], xd[1], kernel[0], kernel[1], kernel[2]};
  w->native = w->vectorised = try_native && make_native(*w, try_padded);
  if (!w->native) make_swapped(*w, kernel);
  w->x_in = dnnl::reorder(
      dnnl::reorder::primitive_desc(engine(), w->x_given, engine(), w->padded ? w->x_blocked : w->x_desc));
  w->dy_in = dnnl::reorder(dnnl::reorder::primitive_desc(engine(), w->dy_given, engine(), w->dy_desc));
  w->dw_out = dnnl::reorder(dnnl::reorder::primitive_desc(engine(), w->dw_desc, engine(), w->dw_torch));
  return w;
}

// Created once per shape, layout and way (a network has a handful). A primitive keeps its
// scratch memory (oneDNN's default), so one must not run in two threads at once: the learner's
// backward runs in the thread that calls it, one at a time.
const WeightGradient& weight_gradient_for(const memory::desc& x, const memory::desc& dy, int64_t padding) {
  static std::mutex mutex;
  static std::vector<std::unique_ptr<WeightGradient>> cache;
  const bool try_native = native_on, try_padded = padded_on;
  const std::lock_guard<std::mutex> lock(mutex);
  for (const auto& w : cache)
    if (w->x == x && w->dy == dy && w->padding == padding && w->native_tried == try_native &&
        w->padded_tried == try_padded)
      return *w;
  cache.push_back(make_weight_gradient(x, dy, padding, try_native, try_padded));
  return *cache.back();
}

// `from` reordered by r into a new buffer of layout `to` (kept in `keep`), or `from` itself where
// it already has that layout.
memory reordered(const dnnl::stream& stream, const dnnl::reorder& r, memory from, const memory::desc& to,
                 Buffer& keep) {
  if (from.get_desc() == to) return from;
  keep = buffer(to);
  r.execute(stream, from, keep.memory);
  return keep.memory;
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
  const WeightGradient& w = weight_gradient_for(x.get_desc(), dy.get_desc(), padding);
  dnnl::stream stream(engine());
  Buffer x_keep, dy_keep, dw = buffer(w.dw_desc);
  auto result = torch::empty(w.dw_sizes, torch::kFloat);
  const memory x_given(w.x_given, engine(), x.get_data_handle()), dy_given(w.dy_given, engine(), dy.get_data_handle());
  const memory x_in = w.padded ? memory(w.x_desc, engine(), reordered(stream, w.x_in, x_given, w.x_blocked, x_keep).get_data_handle())
                               : reordered(stream, w.x_in, x_given, w.x_desc, x_keep);
  const memory dy_in = reordered(stream, w.dy_in, dy_given, w.dy_desc, dy_keep);
  w.primitive.execute(stream, {{w.x_arg, x_in}, {w.dy_arg, dy_in}, {w.dw_arg, dw.memory}});
  memory dw_torch = over(result, w.dw_torch);
  w.dw_out.execute(stream, dw.memory, dw_torch);
  stream.wait();
  return w.padded ? result.narrow(1, 0, w.x.dims()[1]).contiguous() : result;
}

bool weight_gradient_vectorised(const memory::desc& x, const memory::desc& dy, int64_t padding) {
  return weight_gradient_for(x, dy, padding).vectorised;
}

bool weight_gradient_native(const memory::desc& x, const memory::desc& dy, int64_t padding) {
  return weight_gradient_for(x, dy, padding).native;
}

void use_native_weight_gradient(bool on) { native_on = on; }
void use_padded_weight_gradient(bool on) { padded_on = on; }

}  // namespace qte::nets::onednn
