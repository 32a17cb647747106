#include "nets/light_trunk.hpp"

#include <ATen/Parallel.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "common/error.hpp"
#include "nets/onednn.hpp"
#include "nets/qattention_modules.hpp"

namespace qte::nets {
namespace {

using dnnl::memory;
using Desc = memory::desc;
using Dims = memory::dims;
using Tag = memory::format_tag;
using onednn::Buffer;
using onednn::buffer;
using onednn::engine;
using onednn::over;
constexpr auto f32 = memory::data_type::f32;
constexpr auto bf16 = memory::data_type::bf16;
constexpr float kLeaky = static_cast<float>(kLeakySlope);  // LightNet's LeakyReLU

std::atomic<int> trunk_on{-1};  // -1: as onednn::layers_by_default()
std::atomic<Precision> precision_on{Precision::fp32};
std::atomic<bool> inference_primitives_on{true};

// light_trunk_time()'s counters, nanoseconds.
enum Counter { kTrainingForward, kBackward, kInference, kForwardConvolutions, kBackwardData, kWeightGradients,
               kLayouts, kPrecisionConversions, kCounters };
std::array<std::atomic<int64_t>, kCounters> time_ns{};

// Adds the wall time from its construction to its destruction to one counter.
class Timed {
 public:
  explicit Timed(Counter c) : counter_(c), start_(std::chrono::steady_clock::now()) {}
  ~Timed() {
    time_ns[counter_] += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start_).count();
  }
  Timed(const Timed&) = delete;
  Timed& operator=(const Timed&) = delete;

 private:
  Counter counter_;
  std::chrono::steady_clock::time_point start_;
};

// LightNet's convolutions, in the order of their parameters.
enum Layer { kInput, kDown10, kDown12, kDown20, kDown22, kLateral2, kUp1, kLateral1, kUp0, kQ, kLayers };

// The activations' layouts: channels in blocks of b (oneDNN's nCdhw8c or nCdhw16c), or plain
// (b = 1); 0 for any other. Of either data type.
int64_t channel_block(const Desc& d) {
  const Dims dims = d.dims();
  if (dims.size() != 5) return 0;
  const auto type = d.data_type();
  if (d == Desc(dims, type, Tag::nCdhw8c)) return 8;
  if (d == Desc(dims, type, Tag::nCdhw16c)) return 16;
  if (d == Desc(dims, type, Tag::ncdhw)) return 1;
  return 0;
}

// The layout of d (one channel_block knows) with another data type.
Desc with_type(const Desc& d, memory::data_type type) {
  const int64_t b = channel_block(d);
  return Desc(d.dims(), type, b == 16 ? Tag::nCdhw16c : b == 8 ? Tag::nCdhw8c : Tag::ncdhw);
}

// Whether a and b lay out the same dimensions alike, whatever their data types.
bool same_layout(const Desc& a, const Desc& b) {
  return a.dims() == b.dims() && channel_block(a) > 0 && channel_block(a) == channel_block(b);
}

// A buffer of layout d seen as [N, C/b, voxels, b] (channels padded to a multiple of b).
torch::Tensor blocked_view(const torch::Tensor& storage, const Desc& d) {
  const Dims dims = d.dims();
  const int64_t b = channel_block(d), blocks = (dims[1] + b - 1) / b, voxels = dims[2] * dims[3] * dims[4];
  return storage.narrow(0, 0, dims[0] * blocks * voxels * b).view({dims[0], blocks, voxels, b});
}

// Per sample and channel, the sum over the voxels: [N, C].
torch::Tensor voxel_sums(const torch::Tensor& storage, const Desc& d) {
  const auto sums = blocked_view(storage, d).sum(2);
  return sums.reshape({sums.size(0), -1}).narrow(1, 0, d.dims()[1]);
}

// In bf16 a convolution reads bf16 inputs and weights and writes fp32 (oneDNN accumulates in
// fp32): the activations between layers, the pooling, upsampling, sums and every gradient
// outside the convolutions stay fp32; only each convolution's input and the gradient at its
// output are rounded to bf16 on their way in.
struct Convolution {
  int64_t padding = 0;
  bool leaky = false;  // LeakyReLU fused as a post-op
  dnnl::convolution_forward::primitive_desc forward_pd;
  dnnl::convolution_forward forward;
  dnnl::reorder weights_forward;  // LibTorch's [O, I, k, k, k] into the forward's layout
  bool has_backward_data = false;
  dnnl::convolution_backward_data::primitive_desc backward_pd;
  dnnl::convolution_backward_data backward_data;
  dnnl::reorder weights_backward;
  dnnl::eltwise_backward leaky_backward;  // through the fused LeakyReLU, from its output
  Desc src() const { return forward_pd.src_desc(); }  // in the convolution's data type
  Desc dst() const { return forward_pd.dst_desc(); }  // fp32
};

dnnl::eltwise_backward leaky_backward_for(const Desc& y) {
  const auto algorithm = dnnl::algorithm::eltwise_relu_use_dst_for_bwd;
  const dnnl::eltwise_forward::primitive_desc hint({dnnl::prop_kind::forward_training, algorithm, y, kLeaky},
                                                   engine());
  return dnnl::eltwise_backward(dnnl::eltwise_backward::primitive_desc({algorithm, y, y, kLeaky}, engine(), hint));
}

// `type`: the data type of the convolution's input and weights (f32 or bf16). Without
// `training`, only the forward, as an inference primitive.
Convolution make_convolution(int64_t n, int64_t in, int64_t out, int64_t v, int64_t kernel, bool leaky,
                             bool backward_data, memory::data_type type, bool training) {
  Convolution c;
  c.padding = kernel / 2, c.leaky = leaky, c.has_backward_data = backward_data && training;
  const Dims strides{1, 1, 1}, pad{c.padding, c.padding, c.padding};
  const Desc src({n, in, v, v, v}, type, Tag::any), weights({out, in, kernel, kernel, kernel}, type, Tag::any),
      bias({out}, f32, Tag::x), dst({n, out, v, v, v}, f32, Tag::any);
  const Desc diff_src({n, in, v, v, v}, f32, Tag::any), diff_dst({n, out, v, v, v}, type, Tag::any);
  const Desc torch_weights({out, in, kernel, kernel, kernel}, f32, Tag::oidhw);
  dnnl::primitive_attr attr;
  if (leaky) {
    dnnl::post_ops ops;
    ops.append_eltwise(1.f, dnnl::algorithm::eltwise_relu, kLeaky, 0.f);
    attr.set_post_ops(ops);
  }
  c.forward_pd = dnnl::convolution_forward::primitive_desc(
      {dnnl::prop_kind::forward_training, dnnl::algorithm::convolution_direct, src, weights, bias, dst, strides, pad,
       pad},
      attr, engine());
  if (!training)  // in the layouts a training forward chose (left free, inference picks channels-last ones)
    c.forward_pd = dnnl::convolution_forward::primitive_desc(
        {dnnl::prop_kind::forward_inference, dnnl::algorithm::convolution_direct, c.forward_pd.src_desc(), weights,
         bias, c.forward_pd.dst_desc(), strides, pad, pad},
        attr, engine());
  c.forward = dnnl::convolution_forward(c.forward_pd);
  c.weights_forward =
      dnnl::reorder(dnnl::reorder::primitive_desc(engine(), torch_weights, engine(), c.forward_pd.weights_desc()));
  if (c.has_backward_data) {
    c.backward_pd = dnnl::convolution_backward_data::primitive_desc(
        {dnnl::algorithm::convolution_direct, diff_src, weights, diff_dst, strides, pad, pad}, engine(), c.forward_pd);
    c.backward_data = dnnl::convolution_backward_data(c.backward_pd);
    c.weights_backward =
        dnnl::reorder(dnnl::reorder::primitive_desc(engine(), torch_weights, engine(), c.backward_pd.weights_desc()));
  }
  if (leaky && training) c.leaky_backward = leaky_backward_for(c.dst());
  return c;
}

struct Pooling {  // LightNet's max pooling: 3^3 windows, stride 2, padding 1
  dnnl::pooling_v2_forward::primitive_desc forward_pd;
  dnnl::pooling_v2_forward forward;
  dnnl::pooling_v2_backward backward;
};

Pooling make_pooling(const Desc& src, bool training) {
  const Dims d = src.dims();
  const int64_t o = (d[2] - 1) / 2 + 1;
  const Dims strides{2, 2, 2}, kernel{3, 3, 3}, dilation{0, 0, 0}, pad{1, 1, 1};
  Pooling p;
  p.forward_pd = dnnl::pooling_v2_forward::primitive_desc(
      {training ? dnnl::prop_kind::forward_training : dnnl::prop_kind::forward_inference, dnnl::algorithm::pooling_max,
       src, Desc({d[0], d[1], o, o, o}, f32, Tag::any), strides, kernel, dilation, pad, pad},
      engine());
  p.forward = dnnl::pooling_v2_forward(p.forward_pd);
  if (!training) return p;
  p.backward = dnnl::pooling_v2_backward(dnnl::pooling_v2_backward::primitive_desc(
      {dnnl::algorithm::pooling_max, src, p.forward_pd.dst_desc(), strides, kernel, dilation, pad, pad}, engine(),
      p.forward_pd));
  return p;
}

// Trilinear x2 upsampling, half-pixel centres (LibTorch's align_corners=false). Its backward is
// ours (upsampling_adjoint): oneDNN 2.6 has no vectorised kernel for it (its generic one took
// 4-5x as long as LibTorch's, which needs the plain layout).
struct Upsampling {
  dnnl::resampling_forward forward;
};

Upsampling make_upsampling(const Desc& src, const Desc& dst, bool training) {
  return {dnnl::resampling_forward(dnnl::resampling_forward::primitive_desc(
      {training ? dnnl::prop_kind::forward_training : dnnl::prop_kind::forward_inference,
       dnnl::algorithm::resampling_linear, src, dst},
      engine()))};
}

// The adjoint of x2 linear upsampling along one axis of x [outer, 2 * small, inner] into
// y [outer, small, inner]: output sample l sits at (l + 0.5) / 2 - 0.5 in the input, so y[s]
// gets x[2s] and x[2s + 1] with weight 3/4 and their outer neighbours x[2s - 1] and x[2s + 2]
// with 1/4; at the ends the edge sample takes the whole weight (the clamped indices below).
void upsampling_adjoint_axis(const float* x, float* y, int64_t outer, int64_t small, int64_t inner) {
  const int64_t large = 2 * small;
  at::parallel_for(0, outer, 1, [&](int64_t begin, int64_t end) {
    for (int64_t o = begin; o < end; ++o)
      for (int64_t s = 0; s < small; ++s) {
        const float* xo = x + o * large * inner;
        const float* a = xo + std::max<int64_t>(2 * s - 1, 0) * inner;
        const float* b = xo + 2 * s * inner;
        const float* c = b + inner;
        const float* d = xo + std::min<int64_t>(2 * s + 2, large - 1) * inner;
        float* out = y + (o * small + s) * inner;
        for (int64_t i = 0; i < inner; ++i) out[i] = 0.75f * (b[i] + c[i]) + 0.25f * (a[i] + d[i]);
      }
  });
}

// The gradient at a trilinear x2 upsampling's input from the one at its output, both in one
// channel-blocked layout [N, C/b, D, H, W, b]: the 1D adjoint along W, then H, then D (the
// trilinear weights are the product of the three axes' weights).
void upsampling_adjoint(const float* large, float* small, const Dims& small_dims, int64_t block) {
  const int64_t planes = small_dims[0] * ((small_dims[1] + block - 1) / block);
  const int64_t d = small_dims[2], h = small_dims[3], w = small_dims[4];
  std::vector<float> along_w(static_cast<size_t>(planes * 2 * d * 2 * h * w * block));
  std::vector<float> along_h(static_cast<size_t>(planes * 2 * d * h * w * block));
  upsampling_adjoint_axis(large, along_w.data(), planes * 2 * d * 2 * h, w, block);
  upsampling_adjoint_axis(along_w.data(), along_h.data(), planes * 2 * d, h, w * block);
  upsampling_adjoint_axis(along_h.data(), small, planes, d, h * w * block);
}

// Every primitive of one batch size, precision and pass, created once.
struct Graph {
  std::array<Convolution, kLayers> convolution;
  dnnl::eltwise_forward leaky0;  // the first activation, after the proprioception's bias
  dnnl::eltwise_backward leaky0_backward;
  Pooling pool0, pool1;
  Upsampling up2, up1;  // from level 2 to 1, from 1 to 0
  Desc e0, e1, e2, grid_plain, grid;  // grid: the first convolution's input, in its data type
  bool bf16 = false, training = false;
  bool supported = false;
};

bool vectorised(const dnnl::primitive_desc_base& pd) { return std::strncmp(pd.impl_info_str(), "jit", 3) == 0; }

std::unique_ptr<Graph> make_graph(int64_t n, int64_t channels, int64_t k, int64_t v, bool bf16_convolutions,
                                  bool training) {
  auto g = std::make_unique<Graph>();
  g->bf16 = bf16_convolutions, g->training = training;
  // bf16 only with the processor's own bf16 instructions: elsewhere oneDNN emulates them, slower.
  if (bf16_convolutions && !bf16_native_here()) return g;
  const auto type = bf16_convolutions ? bf16 : f32;
  auto& c = g->convolution;
  const auto convolution = [&](int64_t in, int64_t out, int64_t size, int64_t kernel, bool leaky, bool backward_data) {
    return make_convolution(n, in, out, size, kernel, leaky, backward_data, type, training);
  };
  c[kInput] = convolution(channels, k, v, 3, false, false);
  g->e0 = c[kInput].dst();
  g->grid = c[kInput].src();
  g->grid_plain = Desc({n, channels, v, v, v}, f32, Tag::ncdhw);
  const auto leaky = dnnl::algorithm::eltwise_relu_use_dst_for_bwd;
  g->leaky0 = dnnl::eltwise_forward(dnnl::eltwise_forward::primitive_desc(
      {training ? dnnl::prop_kind::forward_training : dnnl::prop_kind::forward_inference, leaky, g->e0, kLeaky},
      engine()));
  if (training) g->leaky0_backward = leaky_backward_for(g->e0);
  g->pool0 = make_pooling(g->e0, training);
  c[kDown10] = convolution(k, 2 * k, v / 2, 3, true, true);
  c[kDown12] = convolution(2 * k, 2 * k, v / 2, 3, true, true);
  g->e1 = c[kDown12].dst();
  g->pool1 = make_pooling(g->e1, training);
  c[kDown20] = convolution(2 * k, 4 * k, v / 4, 3, true, true);
  c[kDown22] = convolution(4 * k, 4 * k, v / 4, 3, true, true);
  g->e2 = c[kDown22].dst();
  c[kLateral2] = convolution(4 * k, 2 * k, v / 4, 1, false, true);
  g->up2 = make_upsampling(c[kLateral2].dst(), g->e1, training);
  c[kUp1] = convolution(2 * k, 2 * k, v / 2, 3, true, true);
  c[kLateral1] = convolution(2 * k, k, v / 2, 1, false, true);
  g->up1 = make_upsampling(c[kLateral1].dst(), g->e0, training);
  c[kUp0] = convolution(k, k, v, 3, true, true);
  c[kQ] = convolution(k, 1, v, 1, false, true);
  // Each layer reads its input in the layout the one before wrote it (in bf16: the same layout,
  // rounded to bf16), and its backward passes gradients in those layouts; otherwise (a layout
  // this code does not expect) LibTorch runs it.
  const std::array<std::pair<Desc, Desc>, 9> links{{{c[kDown10].src(), g->pool0.forward_pd.dst_desc()},
                                                    {c[kDown12].src(), c[kDown10].dst()},
                                                    {c[kDown20].src(), g->pool1.forward_pd.dst_desc()},
                                                    {c[kDown22].src(), c[kDown20].dst()},
                                                    {c[kLateral2].src(), g->e2},
                                                    {c[kUp1].src(), g->e1},
                                                    {c[kLateral1].src(), c[kUp1].dst()},
                                                    {c[kUp0].src(), g->e0},
                                                    {c[kQ].src(), c[kUp0].dst()}}};
  bool ok = channel_block(g->e0) > 1 && k % channel_block(g->e0) == 0 &&
            channel_block(c[kLateral2].dst()) == channel_block(g->e1) &&
            channel_block(c[kLateral1].dst()) == channel_block(g->e0);
  for (const auto& [a, b] : links) ok = ok && same_layout(a, b);
  for (const Convolution& conv : c) {
    ok = ok && vectorised(conv.forward_pd) && channel_block(conv.dst()) > 0;
    if (conv.has_backward_data)
      ok = ok && vectorised(conv.backward_pd) && same_layout(conv.backward_pd.diff_src_desc(), conv.src()) &&
           conv.backward_pd.diff_dst_desc() == with_type(conv.dst(), conv.src().data_type());
    // bf16's weight gradients come from oneDNN's own kernel, which must be there too.
    if (ok && bf16_convolutions && training)
      ok = onednn::weight_gradient_native(conv.src(), with_type(conv.dst(), bf16), conv.padding);
  }
  g->supported = ok;
  return g;
}

const Graph& graph_for(int64_t n, int64_t channels, int64_t k, int64_t v, bool bf16_convolutions, bool training) {
  static std::mutex mutex;
  static std::map<std::array<int64_t, 6>, std::unique_ptr<Graph>> graphs;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& g = graphs[{n, channels, k, v, bf16_convolutions, training}];
  if (!g) {
    try {
      g = make_graph(n, channels, k, v, bf16_convolutions, training);
    } catch (const dnnl::error&) {  // no implementation of a layer here (bf16 below AVX-512)
      g = std::make_unique<Graph>();
    }
  }
  return *g;
}

// The graph a trunk runs on: bf16 convolutions when asked for and supported here, fp32 otherwise.
const Graph& graph_to_run(int64_t n, int64_t channels, int64_t k, int64_t v, bool training) {
  if (precision_on == Precision::bf16) {
    const Graph& g = graph_for(n, channels, k, v, true, training);
    if (g.supported) return g;
  }
  return graph_for(n, channels, k, v, false, training);
}

// The activations a backward needs, in the order the forward makes them.
// Then, in bf16, each convolution's bf16 input (Run::inputs), layer by layer.
enum Saved { kE0, kP0, kWs0, kT1, kE1, kP1, kWs1, kT2, kE2, kS1, kD1, kS0, kD0, kInputs, kSaved = kInputs + kLayers };

struct Run {
  const Graph& g;
  dnnl::stream stream{engine()};
  // Each convolution's input in the convolution's data type where that is not the activation's
  // own (bf16): what its weight gradient reads.
  std::array<Buffer, kLayers> inputs;
  explicit Run(const Graph& graph) : g(graph) {}

  // `from` in layout `to`: `from` itself when it has it, otherwise a new buffer (a bf16 rounding).
  Buffer converted(const Buffer& from, const Desc& to) {
    if (from.memory.get_desc() == to) return from;
    const Timed timed(kPrecisionConversions);
    Buffer out = buffer(to);
    memory src = from.memory;
    dnnl::reorder(src, out.memory).execute(stream, src, out.memory);
    return out;
  }
  // A layer's forward into a new buffer of its output layout.
  Buffer convolve(Layer layer, const Buffer& src, const torch::Tensor& weight, const torch::Tensor& bias) {
    const Convolution& c = g.convolution[layer];
    const Buffer in = converted(src, c.src());
    if (in.memory.get_desc() != src.memory.get_desc()) inputs[layer] = in;
    const Timed timed(kForwardConvolutions);
    Buffer w = buffer(c.forward_pd.weights_desc()), dst = buffer(c.dst());
    memory torch_w = over(weight, Desc(weight.sizes().vec(), f32, Tag::oidhw));
    c.weights_forward.execute(stream, torch_w, w.memory);
    c.forward.execute(stream, {{DNNL_ARG_SRC, in.memory},
                               {DNNL_ARG_WEIGHTS, w.memory},
                               {DNNL_ARG_BIAS, over(bias, c.forward_pd.bias_desc())},
                               {DNNL_ARG_DST, dst.memory}});
    return dst;
  }
  // The gradient at a layer's input (fp32) from the gradient at its output (before its
  // activation, in the convolution's data type).
  Buffer backward_data(Layer layer, const memory& diff_dst, const torch::Tensor& weight) {
    const Timed timed(kBackwardData);
    const Convolution& c = g.convolution[layer];
    Buffer w = buffer(c.backward_pd.weights_desc()), diff_src = buffer(c.backward_pd.diff_src_desc());
    memory torch_w = over(weight, Desc(weight.sizes().vec(), f32, Tag::oidhw));
    c.weights_backward.execute(stream, torch_w, w.memory);
    c.backward_data.execute(stream,
                            {{DNNL_ARG_DIFF_DST, diff_dst}, {DNNL_ARG_WEIGHTS, w.memory}, {DNNL_ARG_DIFF_SRC, diff_src.memory}});
    return diff_src;
  }
  // Through a fused LeakyReLU, from the layer's output y.
  Buffer through_leaky(const dnnl::eltwise_backward& leaky, const Desc& d, const memory& diff, const torch::Tensor& y) {
    Buffer out = buffer(d);
    leaky.execute(stream, {{DNNL_ARG_DST, over(y, d)}, {DNNL_ARG_DIFF_DST, diff}, {DNNL_ARG_DIFF_SRC, out.memory}});
    return out;
  }
  // A plain [N, C, ...] tensor from a buffer of layout d, and back.
  torch::Tensor to_plain(const Buffer& b, const Desc& d) {
    const Timed timed(kLayouts);
    auto out = torch::empty(d.dims(), torch::kFloat);
    memory plain = over(out, Desc(d.dims(), f32, Tag::ncdhw)), src = b.memory;
    dnnl::reorder(src, plain).execute(stream, src, plain);
    return out;
  }
  // The gradient at an upsampling's input (layout `small`) from the one at its output (`large`,
  // the same channel blocks).
  Buffer upsampling_backward(const Buffer& diff, const Desc& small) {
    Buffer out = buffer(small);
    upsampling_adjoint(diff.storage.data_ptr<float>(), out.storage.data_ptr<float>(), small.dims(),
                       channel_block(small));
    return out;
  }
  Buffer from_plain(const torch::Tensor& t, const Desc& d) {
    const Timed timed(kLayouts);
    const auto c = t.contiguous();
    Buffer out = buffer(d);
    memory plain = over(c, Desc(d.dims(), f32, Tag::ncdhw));
    dnnl::reorder(plain, out.memory).execute(stream, plain, out.memory);
    return out;
  }
};

torch::Tensor bias_gradient(const Buffer& diff, const Desc& d) { return voxel_sums(diff.storage, d).sum(0); }

struct LightTrunkFunction : torch::autograd::Function<LightTrunkFunction> {
  static torch::autograd::variable_list forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& grid,
                                                const torch::Tensor& proprio_bias, at::TensorList parameters,
                                                bool levels, bool training) {
    const int64_t n = grid.size(0), k = proprio_bias.size(1);
    const Graph& g = graph_to_run(n, grid.size(1), k, grid.size(2), training);
    Run run(g);
    const auto weight = [&](Layer l) { return parameters[2 * l].contiguous(); };
    const auto bias = [&](Layer l) { return parameters[2 * l + 1].contiguous(); };
    const auto grid_c = grid.contiguous();
    Buffer grid_b = run.from_plain(grid_c, g.grid);
    if (g.bf16) run.inputs[kInput] = grid_b;

    Buffer e0 = run.convolve(kInput, grid_b, weight(kInput), bias(kInput));
    blocked_view(e0.storage, g.e0).add_(proprio_bias.contiguous().view({n, -1, 1, channel_block(g.e0)}));
    g.leaky0.execute(run.stream, {{DNNL_ARG_SRC, e0.memory}, {DNNL_ARG_DST, e0.memory}});
    const auto pool = [&](const Pooling& p, const Buffer& src, Buffer& workspace) {
      Buffer dst = buffer(p.forward_pd.dst_desc());
      std::unordered_map<int, memory> args{{DNNL_ARG_SRC, src.memory}, {DNNL_ARG_DST, dst.memory}};
      if (g.training) {
        workspace = buffer(p.forward_pd.workspace_desc());
        args.emplace(DNNL_ARG_WORKSPACE, workspace.memory);
      }
      p.forward.execute(run.stream, args);
      return dst;
    };
    Buffer ws0, ws1;
    Buffer p0 = pool(g.pool0, e0, ws0);
    Buffer t1 = run.convolve(kDown10, p0, weight(kDown10), bias(kDown10));
    Buffer e1 = run.convolve(kDown12, t1, weight(kDown12), bias(kDown12));
    Buffer p1 = pool(g.pool1, e1, ws1);
    Buffer t2 = run.convolve(kDown20, p1, weight(kDown20), bias(kDown20));
    Buffer e2 = run.convolve(kDown22, t2, weight(kDown22), bias(kDown22));
    const auto upsample_onto = [&](const Upsampling& up, const Buffer& small, const Buffer& skip, const Desc& d) {
      Buffer r = buffer(d);
      up.forward.execute(run.stream, {{DNNL_ARG_SRC, small.memory}, {DNNL_ARG_DST, r.memory}});
      r.storage.add_(skip.storage);  // r is new: the sum needs no buffer of its own
      return r;
    };
    Buffer l2 = run.convolve(kLateral2, e2, weight(kLateral2), bias(kLateral2));
    Buffer s1 = upsample_onto(g.up2, l2, e1, g.e1);
    Buffer d1 = run.convolve(kUp1, s1, weight(kUp1), bias(kUp1));
    Buffer l1 = run.convolve(kLateral1, d1, weight(kLateral1), bias(kLateral1));
    Buffer s0 = upsample_onto(g.up1, l1, e0, g.e0);
    Buffer d0 = run.convolve(kUp0, s0, weight(kUp0), bias(kUp0));
    Buffer q = run.convolve(kQ, d0, weight(kQ), bias(kQ));

    torch::autograd::variable_list out{run.to_plain(q, g.convolution[kQ].dst()).squeeze(1)};
    if (levels) {
      out.push_back(run.to_plain(e0, g.e0));
      out.push_back(run.to_plain(e1, g.e1));
      out.push_back(run.to_plain(e2, g.e2));
      out.push_back(run.to_plain(d0, g.convolution[kUp0].dst()));
    }
    run.stream.wait();
    if (g.training) {  // kept with the autograd node while its outputs live
      std::vector<torch::Tensor> saved(kSaved);
      saved[kE0] = e0.storage, saved[kP0] = p0.storage, saved[kWs0] = ws0.storage, saved[kT1] = t1.storage;
      saved[kE1] = e1.storage, saved[kP1] = p1.storage, saved[kWs1] = ws1.storage, saved[kT2] = t2.storage;
      saved[kE2] = e2.storage, saved[kS1] = s1.storage, saved[kD1] = d1.storage, saved[kS0] = s0.storage;
      saved[kD0] = d0.storage;
      for (int l = 0; l < kLayers; ++l)
        saved[kInputs + l] = run.inputs[l].storage.defined() ? run.inputs[l].storage : torch::empty({0});
      ctx->saved_data["activations"] = saved;
      std::vector<torch::Tensor> inputs{grid_c};
      for (const auto& p : parameters) inputs.push_back(p);
      ctx->save_for_backward(inputs);
      ctx->saved_data["proprio_channels"] = k;
      ctx->saved_data["bf16"] = g.bf16;
    }
    return out;
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const Timed timed(kBackward);
    const auto inputs = ctx->get_saved_variables();
    const auto saved = ctx->saved_data["activations"].toTensorVector();
    const torch::Tensor& grid = inputs[0];
    const int64_t n = grid.size(0), k = ctx->saved_data["proprio_channels"].toInt(), v = grid.size(2);
    const Graph& g = graph_for(n, grid.size(1), k, v, ctx->saved_data["bf16"].toBool(), true);
    const auto& c = g.convolution;
    Run run(g);
    const auto weight = [&](Layer l) { return inputs[1 + 2 * l].contiguous(); };
    const auto at = [&](Saved s, const Desc& d) { return over(saved[s], d); };
    // Layer l's input as its convolution read it: in bf16 the rounded copy, in fp32 `x` itself.
    const auto input_of = [&](Layer l, const memory& x) { return g.bf16 ? at(Saved(kInputs + l), c[l].src()) : x; };
    torch::autograd::variable_list out(2 + 2 * kLayers + 2);  // grid, proprio_bias, parameters, levels, training
    // The weight and bias gradients of a layer from its input x and the gradient at its output
    // (`diff`, fp32, and `diff_in`, the same in the convolution's data type).
    const auto parameter_gradients = [&](Layer l, const memory& x, const Buffer& diff, const Buffer& diff_in) {
      {
        const Timed timed(kWeightGradients);
        out[2 + 2 * l] = onednn::weight_gradient(input_of(l, x), diff_in.memory, c[l].padding);
      }
      out[2 + 2 * l + 1] = bias_gradient(diff, c[l].dst());
    };
    // The gradient at a convolution's output in the convolution's data type.
    const auto for_convolution = [&](Layer l, const Buffer& diff) {
      return run.converted(diff, with_type(c[l].dst(), c[l].src().data_type()));
    };
    const auto level_gradient = [&](size_t i, const Desc& d) -> torch::Tensor {
      if (grads.size() <= i || !grads[i].defined()) return {};
      return run.from_plain(grads[i], d).storage;
    };
    const auto add_level = [&](Buffer& b, size_t i, const Desc& d) {
      const auto extra = level_gradient(i, d);
      if (extra.defined()) b.storage.add_(extra);  // b is this backward's own
    };

    // Back through layer l and its LeakyReLU (if it has one; `y` its output): its parameters'
    // gradients from its input x; returns the gradient at its input.
    const auto back_through = [&](Layer l, const Buffer& diff_y, const torch::Tensor& y, const memory& x) {
      const Buffer diff = c[l].leaky ? run.through_leaky(c[l].leaky_backward, c[l].dst(), diff_y.memory, y) : diff_y;
      const Buffer diff_in = for_convolution(l, diff);
      Buffer diff_x = run.backward_data(l, diff_in.memory, weight(l));
      parameter_gradients(l, x, diff, diff_in);
      return diff_x;
    };
    const auto unpool = [&](const Pooling& p, const Buffer& diff_dst, Saved workspace, const Desc& src) {
      Buffer diff_src = buffer(src);
      p.backward.execute(run.stream, {{DNNL_ARG_DIFF_DST, diff_dst.memory},
                                      {DNNL_ARG_WORKSPACE, at(workspace, p.forward_pd.workspace_desc())},
                                      {DNNL_ARG_DIFF_SRC, diff_src.memory}});
      return diff_src;
    };

    const Desc d0_desc = c[kUp0].dst();
    const torch::Tensor dq =
        grads[0].defined() ? grads[0].unsqueeze(1) : torch::zeros({n, 1, v, v, v}, torch::kFloat);
    Buffer g_d0 = back_through(kQ, run.from_plain(dq, c[kQ].dst()), {}, at(kD0, d0_desc));
    add_level(g_d0, 4, d0_desc);
    const Buffer g_s0 = back_through(kUp0, g_d0, saved[kD0], at(kS0, g.e0));
    const Buffer g_d1 = back_through(kLateral1, run.upsampling_backward(g_s0, c[kLateral1].dst()), {},
                                     at(kD1, c[kUp1].dst()));
    const Buffer g_s1 = back_through(kUp1, g_d1, saved[kD1], at(kS1, g.e1));
    Buffer g_e2 = back_through(kLateral2, run.upsampling_backward(g_s1, c[kLateral2].dst()), {},
                               at(kE2, g.e2));
    add_level(g_e2, 3, g.e2);
    const Buffer g_t2 = back_through(kDown22, g_e2, saved[kE2], at(kT2, c[kDown20].dst()));
    const Buffer g_p1 = back_through(kDown20, g_t2, saved[kT2], at(kP1, c[kDown20].src()));
    Buffer g_e1 = unpool(g.pool1, g_p1, kWs1, g.e1);
    g_e1.storage.add_(g_s1.storage);
    add_level(g_e1, 2, g.e1);
    const Buffer g_t1 = back_through(kDown12, g_e1, saved[kE1], at(kT1, c[kDown10].dst()));
    const Buffer g_p0 = back_through(kDown10, g_t1, saved[kT1], at(kP0, c[kDown10].src()));
    Buffer g_e0 = unpool(g.pool0, g_p0, kWs0, g.e0);
    g_e0.storage.add_(g_s0.storage);
    add_level(g_e0, 1, g.e0);
    Buffer g_a0 = run.through_leaky(g.leaky0_backward, g.e0, g_e0.memory, saved[kE0]);
    const Buffer g_a0_in = for_convolution(kInput, g_a0);
    run.stream.wait();
    {
      const Timed timed(kWeightGradients);
      out[2 + 2 * kInput] = onednn::weight_gradient(input_of(kInput, over(grid, g.grid_plain)), g_a0_in.memory, 1);
    }
    const auto per_sample = voxel_sums(g_a0.storage, g.e0);
    out[2 + 2 * kInput + 1] = per_sample.sum(0);
    out[1] = per_sample;
    return out;
  }
};

// Without gradients (acting, the learner's targets) the batch size varies from call to call,
// and each new size costs its primitives' creation (tens of milliseconds): batches larger than
// 4 run padded with zero samples to a multiple of 4, so that few sizes ever occur.
int64_t padded_batch(int64_t n) { return torch::GradMode::is_enabled() || n <= 4 ? n : (n + 3) / 4 * 4; }

}  // namespace

std::vector<torch::Tensor> light_trunk(const torch::Tensor& grid, const torch::Tensor& proprio_bias,
                                       const std::vector<torch::Tensor>& parameters, bool levels) {
  if (parameters.size() != 2 * kLayers) throw Error("light trunk: expected 20 parameters");
  const int64_t n = grid.size(0), padded = padded_batch(n);
  const bool training = torch::GradMode::is_enabled() || !inference_primitives_on;
  const Timed timed(torch::GradMode::is_enabled() ? kTrainingForward : kInference);
  if (torch::GradMode::is_enabled() || padded == n)
    return LightTrunkFunction::apply(grid, proprio_bias, at::TensorList(parameters), levels, training);
  const auto pad = [&](const torch::Tensor& t) {
    auto sizes = t.sizes().vec();
    sizes[0] = padded - n;
    return torch::cat({t, torch::zeros(sizes, t.options())});
  };
  auto out = LightTrunkFunction::apply(pad(grid), pad(proprio_bias), at::TensorList(parameters), levels, training);
  for (auto& t : out) t = t.narrow(0, 0, n);
  return out;
}

bool light_trunk_supported(const torch::Tensor& grid, int base_channels) {
  if (grid.dim() != 5 || grid.scalar_type() != torch::kFloat || !grid.device().is_cpu() || grid.size(2) % 4 != 0 ||
      grid.size(2) != grid.size(3) || grid.size(2) != grid.size(4))
    return false;
  return graph_for(padded_batch(grid.size(0)), grid.size(1), base_channels, grid.size(2), false,
                   torch::GradMode::is_enabled() || !inference_primitives_on)
      .supported;
}

bool bf16_native_here() {
  const auto isa = static_cast<unsigned>(dnnl::get_effective_cpu_isa());
  const auto bf16_isa = static_cast<unsigned>(dnnl::cpu_isa::avx512_core_bf16);  // AMX's includes its bits
  return (isa & bf16_isa) == bf16_isa;
}

bool bf16_faster_here() {
  const auto isa = static_cast<unsigned>(dnnl::get_effective_cpu_isa());
  const auto amx = static_cast<unsigned>(dnnl::cpu_isa::avx512_core_amx);
  return (isa & amx) == amx;
}

Precision precision_from_name(const std::string& name) {
  if (name == "fp32") return Precision::fp32;
  if (name == "bf16") return Precision::bf16;
  if (name == "auto") return bf16_faster_here() ? Precision::bf16 : Precision::fp32;
  throw Error("--precision must be auto, fp32 or bf16, got '" + name + "'");
}

const char* precision_name(Precision precision) { return precision == Precision::bf16 ? "bf16" : "fp32"; }

void use_precision(Precision precision) { precision_on = precision; }
void use_inference_primitives(bool on) { inference_primitives_on = on; }
Precision precision_requested() { return precision_on; }

Precision precision_running(int64_t batch, int64_t channels, int base_channels, int64_t voxels) {
  if (!onednn_trunk_in_use() || precision_on == Precision::fp32) return Precision::fp32;
  return graph_for(batch, channels, base_channels, voxels, true, true).supported ? Precision::bf16 : Precision::fp32;
}

TrunkTime light_trunk_time() {
  std::array<double, kCounters> s{};
  for (int c = 0; c < kCounters; ++c) s[c] = static_cast<double>(time_ns[c].load()) * 1e-9;
  TrunkTime t;
  t.training_forward_s = s[kTrainingForward], t.backward_s = s[kBackward], t.inference_s = s[kInference];
  t.forward_convolutions_s = s[kForwardConvolutions], t.backward_data_s = s[kBackwardData];
  t.weight_gradients_s = s[kWeightGradients], t.layouts_s = s[kLayouts];
  t.precision_conversions_s = s[kPrecisionConversions];
  t.other_s = t.training_forward_s + t.backward_s + t.inference_s - t.forward_convolutions_s - t.backward_data_s -
              t.weight_gradients_s - t.layouts_s - t.precision_conversions_s;
  return t;
}

void use_onednn_trunk(bool on) { trunk_on = on; }
bool onednn_trunk_in_use() { return trunk_on < 0 ? onednn::layers_by_default() : trunk_on == 1; }

}  // namespace qte::nets
